"""Path files: the waypoint CSV that ``plan`` writes and ``simulate --path`` reads, the executed CSV, the replans.

A path CSV has the header ``x,y,psi1,psi2`` and one configuration per row
(metres, radians), written with 17 significant digits so that a path read
back is the path written, bit for bit. :func:`parse_path_csv` reads the rows
and the line of each; the errors (:class:`~drake_social.errors.ScenarioError`)
name the file and the line. Checking them against a scenario (start, goal,
limits, collisions) is :func:`drake_social.app.read_path_csv`.

Example::

    from drake_social.io.paths import parse_path_csv, write_path_csv

    write_path_csv("out/office_bar/path.csv", result.waypoints)
    rows, lines = parse_path_csv("out/office_bar/path.csv")
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.io.textfile import MAX_PATH_FILE_BYTES, read_text_file, shorten
from drake_social.limits import MAX_WAYPOINTS

__all__ = ["PATH_HEADER", "EXECUTED_HEADER", "parse_path_csv", "write_executed_csv", "write_path_csv",
           "PEOPLE_HEADER", "write_people_csv", "REPLANS_HEADER", "write_replans_csv"]

#: The header of a path CSV: the four values of a configuration.
PATH_HEADER = "x,y,psi1,psi2"
#: The header of ``executed.csv``: time (s), configuration and its velocity (m/s, rad/s).
EXECUTED_HEADER = "t,x,y,psi1,psi2,vx,vy,dpsi1,dpsi2"
#: The header of ``people.csv``: time (s), the person's id, position (m),
#: heading (rad), speed (m/s); the columns of
#: :data:`drake_social.people.PEOPLE_CSV_FIELDS` (``io`` sits below ``people``).
PEOPLE_HEADER = "t,id,x,y,theta,v"
#: The header of ``replans.csv``: one row per replan (see :func:`write_replans_csv`).
REPLANS_HEADER = "t,plan_time,cost,changed,status,searched,iterations,deadline_hit"


def write_path_csv(path: str | Path, waypoints: Any) -> None:
    """Writes waypoints (N, 4) as CSV with header :data:`PATH_HEADER` (17 digits: exact round trip).

    Args:
        path: the file to write.
        waypoints: (N, 4) configurations ``[x, y, psi1, psi2]`` (metres, radians); N may be 0.
    """
    np.savetxt(path, np.asarray(waypoints, float).reshape(-1, 4), delimiter=",", header=PATH_HEADER,
               comments="", fmt="%.17g")


def write_executed_csv(path: str | Path, times: Any, q: Any, v: Any) -> None:
    """Writes an executed trajectory as CSV with header :data:`EXECUTED_HEADER` (17 digits).

    Args:
        path: the file to write.
        times: (T,) sample times, seconds.
        q: (T, 4) configurations (metres, radians).
        v: (T, 4) their velocities (m/s, rad/s).
    """
    times = np.asarray(times, float).reshape(-1)
    table = (np.column_stack([times, np.asarray(q, float).reshape(-1, 4), np.asarray(v, float).reshape(-1, 4)])
             if len(times) else np.zeros((0, 9)))
    np.savetxt(path, table, delimiter=",", header=EXECUTED_HEADER, comments="", fmt="%.17g")


def write_people_csv(path: str | Path, log: Any) -> None:
    """Writes where the people were as ``people.csv``: header :data:`PEOPLE_HEADER`,
    one row per present person
    per logged time (:meth:`~drake_social.people.PeopleLog.csv_rows`: seconds,
    the person's id, metres, radians, metres per second), numbers with 17
    significant digits; an id with a comma or a quote is quoted as CSV quotes it.

    Args:
        path: the file to write.
        log: the people over the run (a :class:`~drake_social.people.PeopleLog`).
    """
    with open(path, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(PEOPLE_HEADER.split(","))
        for t, pid, x, y, theta, v in log.csv_rows():
            writer.writerow([f"{t:.17g}", pid, f"{x:.17g}", f"{y:.17g}", f"{theta:.17g}", f"{v:.17g}"])


def write_replans_csv(path: str | Path, replans: Any) -> None:
    """Writes a run's replans as ``replans.csv``: header :data:`REPLANS_HEADER`,
    one row per :class:`~drake_social.planning.replan.ReplanResult` in order
    (the first plan's first): ``t`` the simulated time of the replan
    (seconds), ``plan_time`` its computation (wall-clock seconds), ``cost``
    (the exact time-indexed cost of the path it leaves in force; ``inf``
    while waiting), ``changed`` (1: the path changed, else 0), ``status``
    (initial, new, kept or wait), ``searched`` (1: the search tree was
    grown, 0: the current path was only judged), ``iterations`` (samples drawn),
    ``deadline_hit`` (1: the budget stopped it, else 0). Numbers with 17
    significant digits.

    Args:
        path: the file to write.
        replans: the ReplanResults (``SimulationResult.replans``).
    """
    with open(path, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(REPLANS_HEADER.split(","))
        for r in replans:
            writer.writerow([f"{float(r.t):.17g}", f"{float(r.plan_time):.17g}", f"{float(r.cost):.17g}",
                             int(bool(r.changed)), r.status, int(bool(r.searched)), int(r.iterations),
                             int(bool(r.deadline_hit))])


def parse_path_csv(path: str | Path, option: str = "--path") -> tuple[np.ndarray, list[int]]:
    """The rows (N, 4) of a path CSV and the file line of each, before any check against a scenario.

    The file may have at most :data:`~drake_social.io.textfile.MAX_PATH_FILE_BYTES`
    bytes; lines end with LF or CRLF; a leading UTF-8 byte order mark (as
    spreadsheets write) is skipped; blank lines are ignored.

    Args:
        path: the CSV file.
        option: the command-line option that named it, for the messages.

    Raises:
        ScenarioError: the file is missing, not a regular file, too large or
            not UTF-8; the header is not :data:`PATH_HEADER`; a row does not
            hold four finite numbers; fewer than 2 or more than
            :data:`~drake_social.limits.MAX_WAYPOINTS` rows (refused at the
            first row too many). The message names the file and the line.
    """
    path = Path(path)
    text = read_text_file(path, "path", option, limit=MAX_PATH_FILE_BYTES).removeprefix("\ufeff")
    lines = [line.removesuffix("\r") for line in text.split("\n")]
    if lines[0].replace(" ", "") != PATH_HEADER:  # not repeated: any file may be named (io.textfile)
        raise ScenarioError(f"{path}: line 1: the header must be '{PATH_HEADER}' (as plan writes it); this is not "
                            f"a path CSV ({option})")
    rows = []
    numbers = []  # the file line of each row
    for i, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        if len(rows) == MAX_WAYPOINTS:
            raise ScenarioError(f"{path}: line {i}: more than {MAX_WAYPOINTS:,} waypoints; a path may have at most "
                                f"{MAX_WAYPOINTS:,} (drake_social.limits.MAX_WAYPOINTS) ({option})")
        cells = line.split(",")
        if len(cells) != 4:
            raise ScenarioError(f"{path}: line {i}: needs 4 numbers x,y,psi1,psi2, got {len(cells)} values: "
                                f"{shorten(repr(line))} ({option})")
        values = []
        for column, cell in zip(PATH_HEADER.split(","), cells):
            try:
                value = float(cell)
            except ValueError:
                value = None
            if value is None or not np.isfinite(value):
                raise ScenarioError(f"{path}: line {i}: {column}: must be a finite number, got "
                                    f"{shorten(repr(cell.strip()))} ({option})")
            values.append(value)
        rows.append(values)
        numbers.append(i)
    if len(rows) < 2:
        raise ScenarioError(f"{path}: needs at least 2 waypoints (start and goal), got {len(rows)} ({option})")
    return np.array(rows), numbers
