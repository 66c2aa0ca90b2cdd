"""The one study framework: studies of several kinds, run on an executor,
recorded and reported the same way.

A study is a frozen dataclass of what to run; its kind (:mod:`.kinds`, one
table) says how it becomes plain-data tasks, which function runs one task in
any process, how its records are filed and what it writes after them. Run
``r`` of a study has the seed drawn from the study's seed by
``numpy.random.SeedSequence(seed).spawn``, shared by all its scenarios and
variants, so comparisons pair over seeds and the numbers never depend on
which worker ran what. The kinds:

* **planning** (:class:`Study`: groups of a scenario with overrides x
  algorithms x runs; a sweep file or the paper's Section V): each task plans
  (:func:`run_task`), measures the path (:mod:`drake_social.evaluation`)
  and, with ``simulate``, executes it; REPORT.md checks the paper's claims or
  compares a sweep's algorithms, with figures and the Planner Arena files;
* **crowd** (:class:`~.crowd.CrowdStudy`: scenarios with walking people x
  variants x episodes): each task is a closed-loop episode
  (:func:`~.crowd_episode.run_episode`) measured over time per part; REPORT.md
  checks paired claims and the targets, with per-part boxplots and snapshots.

The modules, one concept each (this package re-exports the public names of
the shared ones and of the planning study's):

* :mod:`.framework`: :func:`run_study` (any kind, on an executor:
  :mod:`.executors`), :func:`write_study` (the records first, then the
  kind's outputs), :func:`write_records`, :func:`rescue_records`;
* :mod:`.results`: :class:`StudyResult` (a finished study of any kind),
  the records' CSV, :func:`best_runs`;
* :mod:`.scenarios`: the scenarios of the tasks, loaded once per process;
* :mod:`.kinds`: the table of kinds;
* the planning study: :mod:`.spec` (:class:`Study`, :class:`Group`,
  :func:`study_tasks`, :func:`paper_study`), :mod:`.sweep`
  (:func:`load_sweep`), :mod:`.runs` (:func:`run_task`), :mod:`.report`
  (REPORT.md, figures, and the paired statistics every report uses),
  :mod:`.people_tables`, :mod:`.arena`;
* the crowd study: :mod:`.crowd` (:class:`~.crowd.CrowdStudy`, its tasks),
  :mod:`.crowd_episode` (one episode), :mod:`.crowd_report` (REPORT.md,
  figures).
"""


from drake_social.experiments.study.crowd import CrowdStudy
from drake_social.experiments.study.framework import (count, output_names, record_files, rescue_records, run_study,
                                                      write_records, write_study)
from drake_social.experiments.study.kinds import KINDS, StudyKind, kind_of
from drake_social.experiments.study.results import (TIMING_FIELDS, StudyOutputError, StudyResult, best_runs,
                                                    comparable, results_csv)
from drake_social.experiments.study.runs import PROGRESS_POINTS, run_task
from drake_social.experiments.study.spec import (MAX_PAPER_RUNS, MAX_RUNS, MAX_STUDY_TASKS, NAME_PATTERN, PAPER_PLANNER,
                                                 PAPER_ALGORITHMS, PAPER_OBJECTIVE, PAPER_PAIRS, Group, Study, check_study,
                                                 paper_study, paper_weights, study_tasks)
from drake_social.experiments.study.sweep import Sweep, load_sweep
from drake_social.limits import ALGORITHMS, CHECKERS

__all__ = [
    "ALGORITHMS",
    "CHECKERS",
    "KINDS",
    "MAX_PAPER_RUNS",
    "MAX_RUNS",
    "MAX_STUDY_TASKS",
    "NAME_PATTERN",
    "PAPER_ALGORITHMS",
    "PAPER_OBJECTIVE",
    "PAPER_PLANNER",
    "PAPER_PAIRS",
    "PROGRESS_POINTS",
    "TIMING_FIELDS",
    "CrowdStudy",
    "Group",
    "Study",
    "StudyKind",
    "StudyOutputError",
    "StudyResult",
    "Sweep",
    "best_runs",
    "check_study",
    "comparable",
    "count",
    "kind_of",
    "load_sweep",
    "output_names",
    "paper_study",
    "paper_weights",
    "record_files",
    "rescue_records",
    "results_csv",
    "run_study",
    "run_task",
    "study_tasks",
    "write_records",
    "write_study",
]
