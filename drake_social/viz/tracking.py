"""The figure of a simulated execution: references against what the robot did.

:func:`tracking_figure` stacks four panels over time: the base's x and y
(tracked reference dashed, actual solid), the arm joints psi1 and psi2 (the
same), the commanded wheel speeds with their limit, and the base speed with
its limit. Vertical ticks mark where the sequencer advanced. A run among
people (``run.people``, given the robot's ``geometry``) gets a fifth panel:
the smallest surface distance from the robot, its base, arm and object to
any present person over time, with the safety distance.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from drake_social.kinematics import ArmGeometry
from drake_social.people import PeopleLog
from drake_social.people.proximity import part_distances
from drake_social.viz.labels import fit_width

__all__ = ["people_distances", "tracking_figure"]

_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd")


#: The parts whose distance to people the fifth panel shows.
DISTANCE_PARTS = ("robot", "base", "arm", "object")


def people_distances(geometry: ArmGeometry, times: np.ndarray, q: np.ndarray,
                     people: PeopleLog) -> dict[str, np.ndarray]:
    """The surface distance (T,) of each of :data:`DISTANCE_PARTS` to the
    nearest present person at ``times`` (s) with the robot at ``q`` (T, 4),
    people where ``people`` has them then (:meth:`PeopleLog.state_at`, or
    its samples when taken at ``times``); +inf while nobody is present."""
    times = np.asarray(times, float).reshape(-1)
    if len(people.times) == len(times) and np.array_equal(people.times, times):
        centres, present = people.positions, people.present
    else:
        states = [people.state_at(float(t)) for t in times]
        centres = np.array([s.positions for s in states]).reshape(len(times), people.count, 2)
        present = np.array([s.present for s in states]).reshape(len(times), people.count)
    distances = part_distances(geometry, q, centres, people.radii, present)
    return {part: distances[part] for part in DISTANCE_PARTS}


def tracking_figure(run, *, max_base_speed: float | None = None, max_wheel_speed: float | None = None,
                    title: str | None = None, geometry: ArmGeometry | None = None,
                    safety_distance: float | None = None) -> Figure:
    """Reference against actual over time for a :class:`~drake_social.sim.results.SimulationResult`.

    Args:
        run: the simulation result (its ``times``, ``q``, ``reference``,
            ``v``, ``wheel_speeds``, ``target_index``).
        max_base_speed: drawn as a limit line on the speed panel (m/s).
        max_wheel_speed: drawn as +- limit lines on the wheel panel (rad/s).
        title: the figure title (default: mode, execution and outcome);
            fitted to two lines of the figure's width by
            :func:`~drake_social.viz.labels.fit_width`.
        geometry: the robot and its object; with it and people in the run
            (``run.people``, a PeopleLog of at least one person), a fifth
            panel shows :func:`people_distances` over time.
        safety_distance: drawn on that panel (metres).
    """
    t = np.asarray(run.times, float)
    people = getattr(run, "people", None)
    near = geometry is not None and people is not None and people.count > 0 and len(t) > 0
    fig = Figure(figsize=(9.0, 10.5 if near else 8.5))
    fig.subplots_adjust(left=0.1, right=0.97, bottom=0.06, top=0.94 if near else 0.93, hspace=0.32)
    axes = fig.subplots(5 if near else 4, 1, sharex=True)
    fig.suptitle(fit_width(title if title is not None else f"{run.mode} / {run.execution}: {run.message}", 8.7, 10),
                 fontsize=10)
    if len(t) == 0:
        axes[0].text(0.5, 0.5, "nothing was executed", transform=axes[0].transAxes, ha="center")
        return fig
    advances = t[1:][np.diff(run.target_index) != 0]
    panels = [
        (axes[0], (0, 1), ("x", "y"), "base position (m)"),
        (axes[1], (2, 3), ("psi1", "psi2"), "arm joints (rad)"),
    ]
    for ax, idx, names, ylabel in panels:
        for k, (i, name) in enumerate(zip(idx, names)):
            ax.plot(t, run.reference[:, i], "--", color=_COLORS[k], linewidth=1.0, label=f"{name} reference")
            ax.plot(t, run.q[:, i], "-", color=_COLORS[k], linewidth=1.6, alpha=0.7, label=f"{name} actual")
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=7, ncol=4, loc="best")
    ax = axes[2]
    for k in range(4):
        ax.plot(t, run.wheel_speeds[:, k], color=_COLORS[k], linewidth=1.0, label=f"wheel {k + 1}")
    if max_wheel_speed is not None:
        for sign in (1, -1):
            ax.axhline(sign * max_wheel_speed, color="k", linestyle=":", linewidth=1.0)
    ax.set_ylabel("wheel speed (rad/s)")
    ax.legend(fontsize=7, ncol=4, loc="best")
    ax = axes[3]
    ax.plot(t, np.hypot(run.v[:, 0], run.v[:, 1]), color="#1f3b73", linewidth=1.4, label="base speed")
    if max_base_speed is not None:
        ax.axhline(max_base_speed, color="k", linestyle=":", linewidth=1.0, label="limit")
    ax.set_ylabel("base speed (m/s)")
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=7, loc="best")
    if near:
        ax.set_xlabel("")
        ax = axes[4]
        for k, (part, d) in enumerate(people_distances(geometry, t, np.asarray(run.q, float), people).items()):
            ax.plot(t, np.where(np.isfinite(d), d, np.nan), color=("#000000", *_COLORS)[k],
                    linewidth=1.6 if part == "robot" else 1.0, label=part)
        if safety_distance is not None:
            ax.axhline(safety_distance, color="#b00000", linestyle=":", linewidth=1.0, label="safety distance")
        ax.set_ylabel("distance to people (m)")
        ax.set_xlabel("time (s)")
        ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
        ax.legend(fontsize=7, ncol=5, loc="best")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        for a in advances:
            ax.axvline(a, color="#999999", linewidth=0.5, alpha=0.5)
    return fig
