"""A study as OMPL benchmark logs, for Planner Arena (plannerarena.org).

:func:`write_logs` writes one log per experiment, where an experiment is one
group of the study (a scenario file with its overrides), in the text format
of OMPL's ``Benchmark::saveResultsToStream`` that OMPL's
``ompl_benchmark_statistics.py`` reads: experiment header, then per planner
its run properties and one line per run, then the progress properties (the
anytime curve: ``time`` since the start of solve, ``best_cost``,
``iterations``) and one line of samples per run. Our per-run numbers go in as
run properties: ``time`` (planning, s), ``solved``, ``best_cost`` (the
planner's own objective), ``seed``, F, lengths, irregularity and every
per-part metric (``min_dist_<part>``, ``zone_<zone>_<part>``,
``agf_max_<part>``, ``agf_mean_<part>``, REAL), and the ``exec_*`` and
``nav_*`` ones when executed. The runs are planned for K iterations, not against a clock: the
time limit is written as 0.

:func:`build_database` runs OMPL's own script on the logs, giving the SQLite
database Planner Arena opens.
"""

from __future__ import annotations

import datetime
import math
import platform
import socket
import subprocess
import sys
from pathlib import Path

__all__ = ["RUN_PROPERTIES", "build_database", "experiment_log", "log_name", "write_logs"]

#: The first run properties (name, OMPL type, record field).
RUN_PROPERTIES = (("time", "REAL", "planning_time"), ("solved", "BOOLEAN", "success"), ("best_cost", "REAL", "cost"),
                  ("seed", "INTEGER", "seed"), ("run", "INTEGER", "run"),
                  ("first_solution_iteration", "INTEGER", "first_solution_iteration"),
                  ("graph_states", "INTEGER", "tree_size"))
_SKIP = {"index", "group", "scenario", "overrides", "algorithm", "iterations", "waypoints", "progress", "progress_time",
         *(f for _, _, f in RUN_PROPERTIES)}


def _value(x) -> str:
    if x is None:
        return "nan"
    if isinstance(x, bool):
        return "1" if x else "0"
    if isinstance(x, float):
        return "nan" if math.isnan(x) else ("inf" if math.isinf(x) else repr(x))
    return str(x)


def _ompl_type(values) -> str:
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return "BOOLEAN"
    if present and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        return "INTEGER"
    return "REAL"


def experiment_log(result, group) -> str:
    """The OMPL benchmark log of one group's runs."""
    from drake_social import __version__

    records = [r for r in result.records if r["group"] == group.name]
    extra: list[str] = []
    for r in records:
        extra += [k for k, v in r.items() if k not in _SKIP and k not in extra and not isinstance(v, (list, dict, str))]
    props = [(n, t, f) for n, t, f in RUN_PROPERTIES] + [(k, _ompl_type([r.get(k) for r in records]), k) for k in extra]
    st = result.study
    setup = (f"scenario {group.scenario}\noverrides {list(group.overrides)}\niterations K = {st.iterations}\n"
             f"run seeds {st.run_seeds()}\n{group.label}\n")
    lines = [f"drake-social version {__version__}", f"Experiment {group.name}", f"Running on {socket.gethostname()}",
             f"Starting at {datetime.datetime.now().strftime('%Y-%m-%d %H:%M:%S')}", "<<<|", setup.rstrip("\n"), "|>>>",
             "<<<|", f"{platform.processor() or platform.machine()}, {platform.platform()}", "|>>>",
             f"{st.seed} is the random seed", "0 seconds per run", "0 MB per run", f"{st.runs} runs per planner",
             f"{sum(r['planning_time'] for r in records):.6f} seconds spent to collect the data", "0 enum types",
             f"{len(group.algorithms)} planners"]
    for algorithm in group.algorithms:
        runs = sorted((r for r in records if r["algorithm"] == algorithm), key=lambda r: r["run"])
        lines += [algorithm, "1 common properties", f"iterations = {st.iterations}",
                  f"{len(props)} properties for each run"]
        lines += [f"{n} {t}" for n, t, _ in props]
        lines.append(f"{len(runs)} runs")
        lines += ["".join(f"{_value(r.get(f))}; " for _, _, f in props) for r in runs]
        lines += ["3 progress properties for each run", "time REAL", "best_cost REAL", "iterations INTEGER",
                  f"{len(runs)} runs"]
        for r in runs:
            lines.append("".join(f"{_value(t)},{_value(c)},{int(k)},;"
                                 for t, (k, c) in zip(r["progress_time"], r["progress"])))
        lines.append(".")
    return "\n".join(lines) + "\n"


def log_name(group) -> str:
    """The file name of ``group``'s log: ``arena_<group>.log``."""
    return f"arena_{group.name}.log"


def write_logs(result, out: Path) -> list[str]:
    """Writes ``arena_<group>.log`` for every group; returns the file names."""
    names = []
    for g in result.study.groups:
        name = log_name(g)
        (Path(out) / name).write_text(experiment_log(result, g))
        names.append(name)
    return names


def statistics_script() -> list[str] | None:
    """The command running OMPL's ``ompl_benchmark_statistics.py`` (None without ompl)."""
    try:
        import importlib.util

        if importlib.util.find_spec("ompl.ompl_benchmark_statistics") is None:
            return None
    except ImportError:
        return None
    return [sys.executable, "-m", "ompl.ompl_benchmark_statistics"]


def build_database(logs, database: Path) -> Path | None:
    """Runs OMPL's script on ``logs`` into ``database`` (replaced); None when
    OMPL is not installed.

    Raises:
        RuntimeError: the script rejected a log (its output is in the message).
    """
    command = statistics_script()
    if command is None:
        return None
    database = Path(database)
    database.unlink(missing_ok=True)
    done = subprocess.run([*command, "-d", str(database), *map(str, logs)], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"ompl_benchmark_statistics.py failed on {[str(x) for x in logs]}:\n"
                           f"{done.stdout[-2000:]}{done.stderr[-2000:]}")
    return database
