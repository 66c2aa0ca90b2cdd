"""Social-navigation metrics of an executed run, over time, per body part,
against where people actually were (:func:`run_metrics`; the ``nav_*``
fields of records: :func:`execution_metrics`).

The standard social-navigation set of Francis et al. 2023 ("Principles and
Guidelines for Evaluating Social Robot Navigation Algorithms", Table 1:
success, time to goal, path length, collisions, minimum and mean distance to
people, personal-space compliance, velocity / acceleration / jerk, path
irregularity) and of HuNavSim's evaluator (Pérez-Higueras et al. 2023,
``hunav_evaluator``: time to reach the goal, path length, cumulative heading
changes, average distance to the closest person, minimum distance to people,
intimate / personal / social space intrusions as shares of the time, robot-
person collisions, time not moving), measured from the executed run
(samples ``t_0 < ... < t_{T-1}``, the robot at ``q_k``) against the people of
a :class:`~drake_social.people.PeopleLog` at the same times, absent people
ignored. Where the field's tools reduce the robot to a disc, each metric with
a ``<part>`` is given for ``base``, ``arm``, ``object`` and ``robot`` (the
whole robot: the nearest of the three), with the surface-to-surface distance
``d_k`` of :func:`drake_social.people.proximity.part_distances` to the
nearest present person (+inf when nobody is present).

Integrals over time: **sample-and-hold** for flags and zones (sample k's
value holds over [t_k, t_{k+1}); the last sample for no time; as HuNavSim
counts time steps and as the discrete safety monitor's flag behaves);
the **trapezoid rule** for continuous quantities (mean distance, AGF).
``D = t_{T-1} - t_0`` is the run's duration.

=================================  =======  ==================================================
key                                unit     definition
=================================  =======  ==================================================
``success``                        0/1      1 when the goal was reached (``reached``)
``time_to_goal``                   s        the simulator's goal time (``time_to_goal``;
                                            default ``D``) when reached, else NaN
``timeout``                        0/1      1 when not reached and the log covers the time
                                            limit (``t_{T-1} >= time_limit`` less one step)
``duration``                       s        ``D``
``path_length_base``               m        sum of the base's XY steps |p_{k+1} - p_k|
``irregularity_base``              rad/m    :func:`base_irregularity` of the base track
                                            (HuNavSim's cumulative heading changes per metre)
``speed_mean_base`` / ``_max``     m/s      mean / max of |v| over the first divided
                                            differences of the base's XY samples
``accel_mean_base`` / ``_max``     m/s^2    the same of |a| (2 x second divided differences)
``jerk_mean_base`` / ``_max``      m/s^3    the same of |j| (6 x third divided differences)
``jerk_p95_base``                  m/s^3    the 95th percentile of those |j|
``speed_mean_object`` ... (7)      as above the same, pooled over the object's interest points
``stopped_time``                   s        held time with ``stopped`` true (the safety
                                            monitor holding the robot); NaN when ``stopped``
                                            is None (not recorded)
``stop_count``                     count    runs of consecutive stopped samples; NaN likewise
``stopped_share``                  0..1     ``stopped_time / D``; NaN when D = 0 or not recorded
``slowed_time``                    s        held time with the slow-down's speed limit in force
                                            (finite); NaN when ``speed_limit`` is None (not
                                            recorded)
``slow_stop_count``                count    the slow-down's stops (runs of consecutive
                                            ``slow_stopped`` samples: its limit 0); NaN when
                                            ``slow_stopped`` is None
``slow_stopped_time``              s        held time with ``slow_stopped`` true; NaN likewise
``people_count``                   count    people in the log (0 with no log)
``people_moving``                  0/1      1 when anyone moves, turns, enters or leaves
``min_dist_<part>``                m        min_k d_k; +inf when nobody is ever present
``mean_dist_<part>``               m        trapezoid time average of d_k over the steps with
                                            someone present at both ends; NaN when none
``time_<zone>_<part>``             s        held time with d_k in the zone: intimate
                                            d < 0.45, personal 0.45 <= d < 1.2, social
                                            1.2 <= d < 3.6, public d >= 3.6 (nobody: public)
``share_<zone>_<part>``            0..1     ``time_<zone>_<part> / D`` (the four sum to 1);
                                            NaN when D = 0
``collisions_<part>``              count    contact episodes: runs of consecutive samples with
                                            d_k <= 0, each counted where it starts
``collisions_appeared_<part>``     count    of those, the ones that start with a person
                                            appearing in contact: the part touches (d <= 0) a
                                            person at the sample k where that person enters
                                            (present at t_k and k = 0 or absent at t_{k-1}; a
                                            recorded track that begins inside the robot)
``collisions_moving_<part>``       count    of those, the ones that start at a sample k >= 1,
                                            not by an appearance, with the robot commanded to
                                            move over [t_{k-1}, t_k): not held (``stopped`` or
                                            ``waiting``) at both samples k - 1 and max(k - 2, 0)
                                            (the rule below); NaN when ``stopped`` is None (not
                                            recorded)
``collision_time_<part>``          s        held time with d_k <= 0
``space_compliance_<part>``        0..1     personal-space compliance (Francis et al.): the
                                            share of the time outside every present person's
                                            personal space. Papers differ on the space's size;
                                            here it is Hall's intimate bound, d_k >= 0.45 m
                                            surface to surface (= 1 - share_intimate);
                                            NaN when D = 0
``agf_time_<part>``                s        trapezoid integral over time of the part's
                                            thresholded AGF sum over the present people at
                                            their logged poses (the part's value as in
                                            ``metrics.part_agf``: the point, or the largest
                                            over a capsule's axis); with ``social.speed_scaling``
                                            each person's sigma_h = max(2 |v|, 0.5) m at the
                                            logged speed |v| (sigma_s, sigma_r keep their ratios)
=================================  =======  ==================================================

**Who made a contact.** A contact episode starts at the first sample k of
its run (``d_k <= 0``, ``d_{k-1} > 0`` or k = 0) and began somewhere in
(t_{k-1}, t_k]. The robot is *held* at sample j when ``stopped[j]`` (the
safety monitor's decision at t_j) or ``waiting[j]`` (the replanner's: no safe
path). Over [t_{k-1}, t_k) the base's command follows the hold decided at
t_{k-1}, and the arm's trajectory the one decided a period earlier: a
trajectory source reads the hold one control period after the base's
command (:func:`~drake_social.control.safety_monitor.braking_travel`; the
log's samples are the control periods). So the robot was commanded to move
over that step unless it is held at both samples k - 1 and max(k - 2, 0).
Each episode is counted in exactly one of three classes:

* *appeared*: a person entering at sample k (present at t_k, absent at
  t_{k-1}, or present at t_0 when k = 0) is in contact with the part at t_k:
  the person came into being there (a recorded pedestrian whose track begins
  inside the robot as they enter the camera's view). Every contact at the
  first sample is one.
* *moving*: otherwise, when the robot was commanded to move over
  [t_{k-1}, t_k) (k >= 1): it may have driven into the person.
* the rest: the robot was held over the step (at k - 1 and at k - 2): a
  person walked into the held robot.

The rule reads the commands, not the motion: a held robot in ``dynamic``
mode still creeps by the servo's residue for many periods after the hold,
which does not make a contact "moving". A decision taken between two
samples (a replan period that is not a multiple of the log's) counts from
the next sample.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.cost.agf import PersonalSpace, apply_threshold, gaussian, speed_scaled_sigmas
from drake_social.cost.social import FIELD_CHUNK_ELEMENTS
from drake_social.evaluation.proxemics import ZONES, HallZones, base_irregularity, shape_points
from drake_social.evaluation.time_series import episodes, held_time, motion_stats, run_starts, trapezoid_mean
from drake_social.io.records import NAV_PREFIX
from drake_social.kinematics import ArmGeometry
from drake_social.people import people_model, proximity
from drake_social.people.log import PeopleLog
from drake_social.scenario.geometry import arm_geometry

__all__ = ["RUN_PARTS", "execution_metrics", "run_metrics"]


#: The parts :func:`run_metrics` measures against people: the base disc, the
#: arm's capsules, the object's capsules and the whole robot.
RUN_PARTS = ("base", "arm", "object", "robot")


def _part_points(geometry: ArmGeometry, q: np.ndarray, reference: np.ndarray) -> dict[str, np.ndarray]:
    """The points (M, n, 2) whose largest AGF is each part's: the base
    centre, the arm's and the object's capsule axes, and every interest
    point (``points``; the whole robot's value is the largest of the four,
    as in :func:`drake_social.evaluation.metrics.part_agf`)."""
    interest = geometry.interest_points(q)
    return {"base": interest[:, :1], "points": interest, "arm": shape_points(geometry, q, slice(0, 2), reference),
            "object": shape_points(geometry, q, slice(2, None), reference)}


def _agf_over_time(scenario, geometry: ArmGeometry, q: np.ndarray, people: PeopleLog) -> dict[str, np.ndarray]:
    """Each part's thresholded AGF sum over the present people (M,) at their
    logged poses, sample by sample (Kirby's speed scaling when the scenario asks)."""
    options = scenario.social
    space = PersonalSpace.from_options(options)
    if people.count == 0:
        return {part: np.zeros(len(q)) for part in RUN_PARTS}
    out = {part: np.zeros(len(q)) for part in ("base", "points", "arm", "object")}
    # Blocks of samples whose Gaussians' temporaries hold at most FIELD_CHUNK_ELEMENTS (sample, point,
    # person) values each, however long the run and however many people (at least one sample a block).
    points = max(pts.shape[1] for pts in _part_points(geometry, q[:1], q[0]).values())
    rows = max(1, FIELD_CHUNK_ELEMENTS // (points * people.count))
    for lo in range(0, len(q), rows):
        k = slice(lo, lo + rows)
        pos, heading = people.positions[k], people.headings[k]  # (B, P, 2), (B, P)
        sp = space
        if options.speed_scaling:
            speeds = np.hypot(*np.moveaxis(people.velocities[k], -1, 0))  # (B, P)
            sigmas = speed_scaled_sigmas(speeds, options.side_ratio, options.rear_ratio).reshape(*speeds.shape, 3)
            sp = dc.replace(space, sigma_h=sigmas[:, None, :, 0], sigma_s=sigmas[:, None, :, 1],
                            sigma_r=sigmas[:, None, :, 2])
        cos, sin = np.cos(heading)[:, None, :], np.sin(heading)[:, None, :]
        present = people.present[k][:, None, :]
        for part, pts in _part_points(geometry, q[k], q[0]).items():  # as many points in every block
            value = gaussian(pts[..., 0, None] - pos[:, None, :, 0], pts[..., 1, None] - pos[:, None, :, 1],
                             cos, sin, sp)  # (B, n, P)
            out[part][k] = np.where(present, apply_threshold(value, space), 0.0).sum(-1).max(-1)
    out["robot"] = np.maximum.reduce([out.pop("points"), out["arm"], out["object"]])
    return out


def _appearing_contacts(geometry: ArmGeometry, q: np.ndarray, people: PeopleLog, starts: np.ndarray) -> dict:
    """Per part (RUN_PARTS), a (len(starts),) mask: at sample ``starts[i]`` the part
    touches (d <= 0) a person who enters there (present then, and at the first
    sample or absent at the one before)."""
    present = np.asarray(people.present, bool)
    entering = present & ~np.concatenate([np.zeros((1, present.shape[1]), bool), present[:-1]])
    d = proximity.part_distances(geometry, q[starts], people.positions[starts], people.radii, entering[starts])
    return {part: d[part] <= 0.0 for part in RUN_PARTS}


def run_metrics(scenario, times: np.ndarray, q: np.ndarray, people: PeopleLog | None, stopped: np.ndarray | None,
                reached: bool, time_limit: float, *, time_to_goal: float | None = None,
                zones: HallZones = ZONES, waiting: np.ndarray | None = None,
                speed_limit: np.ndarray | None = None, slow_stopped: np.ndarray | None = None) -> dict[str, float]:
    """The social-navigation metrics of an executed run against where people
    were (the table of the module docstring).

    Args:
        scenario: gives the robot, the object and the AGF's options.
        times: (T,) strictly increasing sample times, seconds (T >= 1).
        q: (T, 4) executed configurations at ``times``.
        people: the people at the same times (``people.times`` equal to
            ``times``); None = nobody.
        stopped: (T,) True where the safety monitor holds the robot from
            sample k on (its decision at t_k); None = not recorded (the stop
            metrics and ``collisions_moving_<part>`` are NaN).
        reached: the goal was reached.
        time_limit: the run's time limit, seconds (for ``timeout``).
        time_to_goal: the simulator's goal time, seconds; None = ``D``.
        zones: Hall's zone bounds.
        waiting: (T,) True where the replanner holds the robot from sample k
            on (no safe path at its latest decision at or before t_k); None =
            no replanner (never waiting).
        speed_limit: (T,) the slow-down's limit logged at the samples (m/s,
            +inf where none); None = not recorded (``slowed_time`` NaN).
        slow_stopped: (T,) True where the slow-down's limit holds the robot
            at 0 from sample k on; None = not recorded (its stop metrics NaN).

    Returns:
        A flat dictionary of floats (keys of the module docstring's table).

    Raises:
        ValueError: shapes that do not match, times not strictly increasing,
            or a people log sampled at other times.
    """
    times = np.asarray(times, float).reshape(-1)
    q = np.asarray(q, float)
    t = len(times)
    if t == 0 or q.shape != (t, 4) or not (np.isfinite(times).all() and (np.diff(times) > 0).all()):
        raise ValueError(f"run_metrics: times must be T >= 1 strictly increasing seconds and q (T, 4); got times "
                         f"of {t} samples and q of shape {q.shape}")
    if people is not None and (len(people.times) != t or not np.allclose(people.times, times, rtol=0, atol=1e-9)):
        raise ValueError(f"run_metrics: the people log has {len(people.times)} samples at other times than the "
                         f"run's {t}; sample it at the run's times (PeopleLog.sample or the simulator's log)")
    for name, flag in (("stopped", stopped), ("waiting", waiting), ("speed_limit", speed_limit),
                       ("slow_stopped", slow_stopped)):
        if flag is not None and np.asarray(flag).shape != (t,):
            raise ValueError(f"run_metrics: {name} must be (T,) = ({t},) booleans, got {np.asarray(flag).shape}")
    g = arm_geometry(scenario)
    duration = float(times[-1] - times[0])
    steps = np.diff(times)

    def share(seconds: float) -> float:
        return seconds / duration if duration > 0 else float("nan")

    out: dict[str, float] = {
        "success": float(bool(reached)),
        "time_to_goal": (duration if time_to_goal is None else float(time_to_goal)) if reached else float("nan"),
        "timeout": float(not reached and times[-1] >= time_limit - (steps.max() if t > 1 else 0.0)),
        "duration": duration,
        "path_length_base": float(np.hypot(*np.diff(q[:, :2], axis=0).T).sum()),
        "irregularity_base": base_irregularity(q[:, :2]),
    }
    out.update({f"{k}_base": v for k, v in motion_stats(times, q[:, :2]).items()})
    object_points = g.interest_points(q)[:, 3:]  # after the base, the elbow and the gripper
    out.update({f"{k}_object": v for k, v in motion_stats(times, object_points).items()})
    if stopped is None:
        out.update(stopped_time=float("nan"), stop_count=float("nan"), stopped_share=float("nan"))
    else:
        count, seconds = episodes(np.asarray(stopped, bool), times)
        out.update(stopped_time=seconds, stop_count=float(count), stopped_share=share(seconds))
    out["slowed_time"] = (float("nan") if speed_limit is None else
                          held_time(np.isfinite(np.asarray(speed_limit, float)), times))
    if slow_stopped is None:
        out.update(slow_stop_count=float("nan"), slow_stopped_time=float("nan"))
    else:
        count, seconds = episodes(np.asarray(slow_stopped, bool), times)
        out.update(slow_stop_count=float(count), slow_stopped_time=seconds)
    out["people_count"] = float(people.count if people is not None else 0)
    out["people_moving"] = float(people is not None and people.count > 0 and not people.static)
    if people is None or people.count == 0:
        dist = {p: np.full(t, np.inf) for p in RUN_PARTS}
        agf = {p: np.zeros(t) for p in RUN_PARTS}
    else:
        dist = proximity.part_distances(g, q, people.positions, people.radii, people.present)
        agf = _agf_over_time(scenario, g, q, people)
    # Commanded to move over [t_{k-1}, t_k) (the module docstring's rule): the base follows the hold of
    # sample k - 1, the arm's trajectory that of sample k - 2; held over the step only when both hold.
    drives = None
    if stopped is not None:
        held = np.asarray(stopped, bool) | (False if waiting is None else np.asarray(waiting, bool))
        drives = ~(held & np.concatenate([held[:1], held[:-1]]))  # index k - 1: samples k - 1 and max(k - 2, 0)
    starts = {part: run_starts(dist[part] <= 0.0) for part in RUN_PARTS}
    every = np.unique(np.concatenate(list(starts.values())))
    appeared = (_appearing_contacts(g, q, people, every) if len(every) else
                {part: np.zeros(0, bool) for part in RUN_PARTS})
    for part in RUN_PARTS:
        d = dist[part]
        out[f"min_dist_{part}"] = float(d.min())
        out[f"mean_dist_{part}"] = trapezoid_mean(d, times)
        zone = zones.classify(d)
        for z, name in enumerate(zones.names):
            seconds = held_time(zone == z, times)
            out[f"time_{name}_{part}"] = seconds
            out[f"share_{name}_{part}"] = share(seconds)
        count, seconds = episodes(d <= 0.0, times)
        out[f"collisions_{part}"] = float(count)
        k = starts[part]
        new = appeared[part][np.searchsorted(every, k)]
        out[f"collisions_appeared_{part}"] = float(np.count_nonzero(new))
        out[f"collisions_moving_{part}"] = (float("nan") if drives is None else
                                            float(np.count_nonzero(~new & (k >= 1) & drives[np.maximum(k - 1, 0)])))
        out[f"collision_time_{part}"] = seconds
        out[f"space_compliance_{part}"] = share(held_time(d >= zones.intimate, times))
        out[f"agf_time_{part}"] = float(np.trapezoid(agf[part], times)) if t > 1 else 0.0
    return out


#: The stand-in for a result without a ``people`` attribute (see :func:`execution_metrics`).
_UNLOGGED = object()


def execution_metrics(scenario, result) -> dict[str, float]:
    """The social-navigation metrics of a simulated run, keys prefixed
    :data:`~drake_social.io.records.NAV_PREFIX` (``nav_``; the fields of
    :data:`~drake_social.io.records.NAV_FIELDS`).

    The people are ``result.people`` (where they were, the crowd reacting to
    the robot), sampled at the run's times by linear interpolation when
    logged at others; a result without a ``people`` attribute (a simulator
    that does not log people) is measured against the scenario's open-loop
    people model sampled at the run's times. The stops are
    ``result.stopped``; without it the stop metrics and the moving contacts
    are NaN (null in JSON). The replanner's holds are ``result.waiting``
    (none without it).

    Args:
        scenario: the executed scenario.
        result: a :class:`~drake_social.sim.results.SimulationResult`.

    Returns:
        ``{"nav_<key>": value}`` for every key of :func:`run_metrics`; empty when
        nothing was executed (no samples).
    """
    times = np.asarray(result.times, float).reshape(-1)
    if not len(times):
        return {}
    # getattr: a SimulationResult before people were logged has no such field.
    people = getattr(result, "people", _UNLOGGED)
    if people is _UNLOGGED:
        people = PeopleLog.sample(people_model(scenario), times)
    elif people is not None and (len(people.times) != len(times) or not np.array_equal(people.times, times)):
        people = PeopleLog.sample(people, times)
    stopped = getattr(result, "stopped", None)
    waiting = getattr(result, "waiting", None)
    speed_limit = getattr(result, "speed_limit", None)
    slow_stopped = getattr(result, "slow_stopped", None)
    metrics = run_metrics(scenario, times, result.q, people, None if stopped is None else np.asarray(stopped, bool),
                          bool(result.reached), float(scenario.execution.time_limit),
                          time_to_goal=result.time_to_goal,
                          waiting=None if waiting is None else np.asarray(waiting, bool),
                          speed_limit=None if speed_limit is None or len(speed_limit) != len(times) else speed_limit,
                          slow_stopped=None if slow_stopped is None or len(slow_stopped) != len(times)
                          else np.asarray(slow_stopped, bool))
    return {NAV_PREFIX + k: v for k, v in metrics.items()}

