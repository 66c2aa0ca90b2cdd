"""Studies: scenarios x algorithms x seeds x overrides, measured per body part.

A :class:`Study` is a list of :class:`Group` s (one scenario with its
overrides and the algorithms planned on it), a run count, K and a seed.
:func:`study_tasks` turns it into plain-data tasks, one per (group,
algorithm, run); run ``r`` of every group and algorithm plans with the same
seed, drawn from the study's seed by ``numpy.random.SeedSequence(seed).spawn``,
so comparisons pair over seeds and the numbers never depend on which worker
ran what. :func:`run_task` (in any process) loads the scenario from its text,
plans, measures the path (:mod:`drake_social.experiments.metrics`) and, with
``simulate``, executes it and measures the executed trajectory too.

The modules, one concept each (this package re-exports their public names):

* :mod:`.spec`: :class:`Study` and :class:`Group`, :func:`check_study`,
  :func:`study_tasks` and :func:`paper_study`, the paper's Section V (A:
  office_bar with the bar, B: generic_L with the L, the five algorithms; D:
  generic_L with the bar, Social Risk-RRT* under three weightings);
* :mod:`.sweep`: :func:`load_sweep`, a study from a YAML file
  (``drake-social experiment sweep``);
* :mod:`.scenarios`: the groups' scenarios, loaded once per process;
* :mod:`.runs`: :func:`run_task` and :func:`run_study`, on an executor
  (:mod:`.executors`);
* :mod:`.results`: :class:`StudyResult`, :func:`best_runs` and the record
  files (:func:`write_records`, :func:`rescue_records`);
* :mod:`.output`: :func:`write_study`: results.csv, results.json, the
  figures (:mod:`.report`), REPORT.md and the Planner Arena log and database
  (:mod:`.arena`), as one output set; the records first, so that an error in
  a later file never costs the finished runs.
"""


from drake_social.experiments.study.output import output_names, write_study
from drake_social.experiments.study.results import (RECORD_FILES, TIMING_FIELDS, StudyOutputError, StudyResult,
                                                    best_runs, comparable, rescue_records, results_csv, write_records)
from drake_social.experiments.study.runs import PROGRESS_POINTS, run_study, run_task
from drake_social.experiments.study.spec import (MAX_PAPER_RUNS, MAX_RUNS, MAX_STUDY_TASKS, NAME_PATTERN, PAPER_PLANNER,
                                                 PAPER_ALGORITHMS, PAPER_OBJECTIVE, PAPER_PAIRS, Group, Study, check_study,
                                                 paper_study, paper_weights, study_tasks)
from drake_social.experiments.study.sweep import Sweep, load_sweep
from drake_social.limits import ALGORITHMS, CHECKERS

__all__ = [
    "ALGORITHMS",
    "CHECKERS",
    "MAX_PAPER_RUNS",
    "MAX_RUNS",
    "MAX_STUDY_TASKS",
    "NAME_PATTERN",
    "PAPER_ALGORITHMS",
    "PAPER_OBJECTIVE",
    "PAPER_PLANNER",
    "PAPER_PAIRS",
    "PROGRESS_POINTS",
    "RECORD_FILES",
    "TIMING_FIELDS",
    "Group",
    "Study",
    "StudyOutputError",
    "StudyResult",
    "Sweep",
    "best_runs",
    "check_study",
    "comparable",
    "load_sweep",
    "output_names",
    "paper_study",
    "paper_weights",
    "rescue_records",
    "results_csv",
    "run_study",
    "run_task",
    "study_tasks",
    "write_records",
    "write_study",
]
