"""Social-navigation metrics of a path, per body part and overall.

The field's tools (HuNavSim, SocNavBench, SEAN, Arena) reduce the robot to one
point or disc; here every body part is measured on its own:

==============  ===========================================================
part            what is measured
==============  ===========================================================
``base``        the base disc (radius ``robot.base_radius``)
``link1_tip``   the elbow, a point
``link2_tip``   the gripper origin, a point
``object_k``    the object's k-th interest point, a point
``arm``         both link capsules (radius ``robot.link_width / 2``)
``object``      every object capsule (radius ``object.thickness / 2``)
``robot``       the whole robot: base disc, arm and object (overall)
==============  ===========================================================

Per part (``<metric>_<part>`` in :func:`path_metrics`' flat dictionary):

* ``min_dist``: smallest *surface-to-surface* distance, metres, from the part
  to any person's body disc (``people[i].radius``): a point's distance to the
  disc's edge, the base disc's and a capsule's edge to the disc's edge. 0 is
  contact; negative is overlap.
* ``zone_intimate`` / ``zone_personal`` / ``zone_social`` / ``zone_public``:
  Hall's proxemic zones, the share (0..1) of the base's arc length during
  which the part's ``min_dist`` is < 0.45 m, in [0.45, 1.2) m, in [1.2, 3.6) m,
  or >= 3.6 m (each step between samples is classified by the mean of its
  end distances). Executed trajectories also get ``zone_time_<zone>``: the
  share of time. NaN when the base does not move (resp. no time passes).
* ``agf_max``: the largest thresholded AGF sum over people that the part
  meets (for a shape: any point of its axis, sampled every
  :data:`SHAPE_SPACING` metres); dimensionless, in [0, number of people].
* ``agf_mean``: its mean over the configuration-space arc length s (the
  paper's ``ds``): ``integral AGF ds / integral ds``. For an interest point,
  ``agf_mean * path_length`` is its unweighted share of F.

Overall:

* ``F_multi``: the paper's final cost F(q_end), the social integral (Msc) with
  weight 1 on every interest point, whatever weights the planner used;
  ``F_base``: the same with base-only weights (1 on the base, 0 elsewhere);
  ``F_planner``: with the planner's own weights.
* ``path_length`` (configuration space, plain norm), ``base_length`` (metres),
  ``irregularity``: the base track's total heading change per metre of it,
  rad/m (the track is resampled every :data:`HEADING_STEP` metres first, so
  that the jitter of an executed trajectory does not count).

Over time, against where people actually were (:func:`run_metrics`)
-------------------------------------------------------------------

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
``speed_mean_object`` ... (6)      as above the same, pooled over the object's interest points
``stopped_time``                   s        held time with ``stopped`` true (the safety
                                            monitor holding the robot); NaN when ``stopped``
                                            is None (not recorded)
``stop_count``                     count    runs of consecutive stopped samples; NaN likewise
``stopped_share``                  0..1     ``stopped_time / D``; NaN when D = 0 or not recorded
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
``collision_time_<part>``          s        held time with d_k <= 0
``space_compliance_<part>``        0..1     share of the time outside every present
                                            person's personal space, d_k >= 0.45 m (Francis
                                            et al.'s personal-space compliance, with Hall's
                                            intimate bound as the space, surface to surface);
                                            NaN when D = 0
``agf_time_<part>``                s        trapezoid integral over time of the part's
                                            thresholded AGF sum over the present people at
                                            their logged poses (the part's value as in
                                            :func:`part_agf`: the point, or the largest over
                                            a capsule's axis); with ``social.speed_scaling``
                                            each person's sigma_h = max(2 |v|, 0.5) m
=================================  =======  ==================================================
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.cost.agf import PersonalSpace, agf_xy, apply_threshold, gaussian
from drake_social.cost.social import SocialCost
from drake_social.kinematics import ArmGeometry, config_distance
from drake_social.people import people_model, proximity
from drake_social.people.proximity import part_names
from drake_social.experiments.records import path_costs
from drake_social.experiments.time_series import episodes, held_time, motion_stats, trapezoid_mean
from drake_social.people.log import PeopleLog

__all__ = [
    "HEADING_STEP",
    "RUN_PARTS",
    "SHAPE_SPACING",
    "ZONES",
    "HallZones",
    "base_irregularity",
    "executed_metrics",
    "part_agf",
    "part_distances",
    "part_names",
    "path_metrics",
    "run_metrics",
    "trajectory_metrics",
    "zone_shares",
]

#: Spacing of the points sampled along a capsule's axis for its AGF, metres.
SHAPE_SPACING = 0.05
#: Resampling step of the base track before heading changes are summed, metres.
HEADING_STEP = 0.05


@dc.dataclass(frozen=True)
class HallZones:
    """Upper bounds of Hall's proxemic zones (surface-to-surface), metres.

    Attributes:
        intimate: below this, intimate (0.45 m).
        personal: below this, personal (1.2 m).
        social: below this, social (3.6 m); beyond, public.
    """

    intimate: float = 0.45
    personal: float = 1.2
    social: float = 3.6

    @property
    def names(self) -> tuple[str, ...]:
        return ("intimate", "personal", "social", "public")

    def classify(self, distance: np.ndarray) -> np.ndarray:
        """Zone index (0 intimate .. 3 public) of each distance."""
        return np.searchsorted([self.intimate, self.personal, self.social], np.asarray(distance, float), side="right")


#: The zones used by the studies.
ZONES = HallZones()


def part_distances(geometry: ArmGeometry, people: np.ndarray, radii: np.ndarray, q: np.ndarray) -> dict[str, np.ndarray]:
    """Surface-to-surface distance (M,) of every part to the nearest person's
    body disc at configurations q (M, 4), metres, people standing at
    ``people`` (P, 3) rows [x, y, theta]; +inf in an empty room."""
    people = np.asarray(people, float).reshape(-1, 3)
    return proximity.part_distances(geometry, q, people[:, :2], radii)


def _shape_points(geometry: ArmGeometry, q: np.ndarray, which: slice) -> np.ndarray:
    """Points (M, n, 2) every <= SHAPE_SPACING metres along the capsule axes ``which``."""
    seg = geometry.segments(q)[:, which]  # (M, S', 2, 2)
    lengths = np.linalg.norm(seg[0, :, 1] - seg[0, :, 0], axis=-1)  # rigid: the same at every q
    pieces = []
    for s, length in enumerate(lengths):
        t = np.linspace(0.0, 1.0, max(2, int(np.ceil(length / SHAPE_SPACING)) + 1))
        pieces.append(seg[:, s, 0, None, :] + t[None, :, None] * (seg[:, s, 1, None, :] - seg[:, s, 0, None, :]))
    return np.concatenate(pieces, axis=1)


def part_agf(cost: SocialCost, q: np.ndarray) -> dict[str, np.ndarray]:
    """Thresholded AGF sum over people (M,) met by every part at configurations q (M, 4).

    Interest points: their value; ``arm`` and ``object``: the largest over
    their axis; ``robot``: the largest over every part.
    """
    q = np.asarray(q, float).reshape(-1, 4)
    g = cost.geometry
    values = cost.point_costs(q)  # (M, K)
    out = {n: values[:, k] for k, n in enumerate(g.interest_names)}
    for name, which in (("arm", slice(0, 2)), ("object", slice(2, None))):
        pts = _shape_points(g, q, which)
        out[name] = agf_xy(pts[..., 0], pts[..., 1], cost.people, cost.space).sum(-1).max(-1)
    out["robot"] = np.max([out[n] for n in g.interest_names + ["arm", "object"]], axis=0)
    return out


def zone_shares(distance: np.ndarray, weights: np.ndarray, zones: HallZones = ZONES) -> dict[str, float]:
    """Share of the total weight spent in each zone.

    Args:
        distance: (M,) distances at the samples, metres.
        weights: (M - 1,) weight of each step between samples (arc length, time).

    Returns:
        zone name -> share in [0, 1] (NaN each when the weights sum to 0).
    """
    distance = np.asarray(distance, float)
    w = np.asarray(weights, float)
    total = float(w.sum())
    if len(distance) < 2 or not total > 0:
        return {z: float("nan") for z in zones.names}
    zone = zones.classify(0.5 * (distance[:-1] + distance[1:]))
    share = np.bincount(zone, weights=w, minlength=4) / total
    return {z: float(share[k]) for k, z in enumerate(zones.names)}


def base_irregularity(xy: np.ndarray, step: float = HEADING_STEP) -> float:
    """Total absolute heading change of a base track per metre of it, rad/m.

    The track (M, 2) is resampled every ``step`` metres of arc length (its
    end kept) so that steps far below the resolution do not count; 0 for a
    straight or motionless track.
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))]) if len(xy) else np.zeros(0)
    if len(xy) < 2 or s[-1] <= step:
        return 0.0
    keep = np.concatenate([[True], np.diff(s) > 0])
    xy, s = xy[keep], s[keep]
    targets = np.append(np.arange(0.0, s[-1], step), s[-1])
    r = np.stack([np.interp(targets, s, xy[:, 0]), np.interp(targets, s, xy[:, 1])], -1)
    d = np.diff(r, axis=0)
    d = d[np.hypot(d[:, 0], d[:, 1]) > 1e-12]
    heading = np.arctan2(d[:, 1], d[:, 0])
    turn = np.abs(np.angle(np.exp(1j * np.diff(heading))))
    return float(turn.sum() / s[-1])


def trajectory_metrics(
    scenario, q: np.ndarray, s: np.ndarray | None = None, times: np.ndarray | None = None, zones: HallZones = ZONES
) -> dict[str, float]:
    """Per-part distances, zone shares and AGF of dense samples of a trajectory.

    Args:
        scenario: gives the robot, object and people.
        q: (M, 4) configurations, dense enough that a part moves little between them.
        s: (M,) configuration arc length at the samples (None: the plain norm
            of the differences, summed).
        times: (M,) seconds; given, the zone shares by time are added and
            each sample is measured against the people at its time (None:
            against the people at t = 0).
        zones: the zone bounds.

    Returns:
        ``min_dist_<part>``, ``zone_<zone>_<part>``, (``zone_time_<zone>_<part>``),
        ``agf_max_<part>``, ``agf_mean_<part>`` for every part of :func:`part_names`.
    """
    q = np.asarray(q, float).reshape(-1, 4)
    g = ArmGeometry.from_scenario(scenario)
    ones = np.ones(g.num_interest_points)
    if s is None:
        s = np.concatenate([[0.0], np.cumsum(config_distance(q[:-1], q[1:]))]) if len(q) else np.zeros(0)
    model = people_model(scenario)
    if times is None or model.static:
        # A planned path has no times: it is measured against the people at
        # t = 0, where the planner saw them; static people are there always.
        state = model.state_at(0.0)
        dist = part_distances(g, state.poses(), state.radii, q)
        values = part_agf(SocialCost.from_scenario(scenario, ones, people=state), q)
    else:
        # Moving people: each sample against the people at its own time.
        per_sample = []
        for qi, ti in zip(q, np.asarray(times, float)):
            state = model.state_at(float(ti))
            per_sample.append((part_distances(g, state.poses(), state.radii, qi),
                               part_agf(SocialCost.from_scenario(scenario, ones, people=state), qi)))
        parts = part_names(g)
        dist = {n: np.array([d[n][0] for d, _ in per_sample], float).reshape(-1) for n in parts}
        values = {n: np.array([v[n][0] for _, v in per_sample], float).reshape(-1) for n in parts}
    base_steps = np.hypot(*np.diff(q[:, :2], axis=0).T) if len(q) > 1 else np.zeros(0)
    length = float(s[-1] - s[0]) if len(s) else 0.0
    out: dict[str, float] = {}
    for part in part_names(g):
        out[f"min_dist_{part}"] = float(dist[part].min()) if len(q) else float("nan")
        for z, v in zone_shares(dist[part], base_steps, zones).items():
            out[f"zone_{z}_{part}"] = v
        if times is not None:
            for z, v in zone_shares(dist[part], np.diff(np.asarray(times, float)), zones).items():
                out[f"zone_time_{z}_{part}"] = v
        out[f"agf_max_{part}"] = float(values[part].max()) if len(q) else float("nan")
        out[f"agf_mean_{part}"] = float(np.trapezoid(values[part], s) / length) if length > 0 else float("nan")
    return out


def path_metrics(scenario, waypoints: np.ndarray, planner_weights: np.ndarray | None = None,
                 refine: int = 2) -> dict[str, float]:
    """Every metric of a planned waypoint path (see the module docstring).

    Args:
        scenario: the planned scenario (people, robot, object).
        waypoints: (N, 4), start to goal; straight motions between them.
        planner_weights: the interest-point weights the planner used (for
            ``F_planner``); None = the scenario's ``social.weights``.
        refine: samples per integration step of the cost (each interest point
            moves at most ``social.resolution / refine`` metres between samples).

    Returns:
        :func:`path_costs` (``F_multi``, ``F_base``, ``F_planner``,
        ``path_length``, ``base_length``), ``irregularity`` and
        :func:`trajectory_metrics`.
    """
    from drake_social.viz.path import sample_path  # the sampling of the cost-profile figure

    wp = np.asarray(waypoints, float).reshape(-1, 4)
    n = ArmGeometry.from_scenario(scenario).num_interest_points
    out = path_costs(scenario, wp, planner_weights)
    out["irregularity"] = base_irregularity(wp[:, :2])
    s, q = sample_path(wp, SocialCost.from_scenario(scenario, np.ones(n)), refine)
    out.update(trajectory_metrics(scenario, q, s))
    return out


def executed_metrics(scenario, times: np.ndarray, q: np.ndarray) -> dict[str, float]:
    """Per-part metrics of an executed trajectory (times (T,), q (T, 4)),
    with zone shares by time too, and its F and lengths; keys prefixed ``exec_``."""
    q = np.asarray(q, float).reshape(-1, 4)
    n = ArmGeometry.from_scenario(scenario).num_interest_points
    multi = SocialCost.from_scenario(scenario, np.ones(n))
    out = {
        "F_multi": float(multi.motion_cost(q[:-1], q[1:]).sum()) if len(q) > 1 else 0.0,
        "path_length": float(config_distance(q[:-1], q[1:]).sum()) if len(q) > 1 else 0.0,
        "base_length": float(np.hypot(*np.diff(q[:, :2], axis=0).T).sum()) if len(q) > 1 else 0.0,
        "irregularity": base_irregularity(q[:, :2]),
    }
    out.update(trajectory_metrics(scenario, q, None, np.asarray(times, float)))
    return {f"exec_{k}": v for k, v in out.items()}


#: The parts :func:`run_metrics` measures against people: the base disc, the
#: arm's capsules, the object's capsules and the whole robot.
RUN_PARTS = ("base", "arm", "object", "robot")
#: Samples per block when the AGF over time is summed (bounds the memory of a long run).
_AGF_BLOCK = 2048


def _part_points(geometry: ArmGeometry, q: np.ndarray) -> dict[str, np.ndarray]:
    """The points (M, n, 2) whose largest AGF is each part's: the base
    centre, the arm's and the object's capsule axes (as :func:`part_agf`)."""
    pts = {"base": geometry.interest_points(q)[:, :1], "arm": _shape_points(geometry, q, slice(0, 2)),
           "object": _shape_points(geometry, q, slice(2, None))}
    pts["robot"] = np.concatenate([geometry.interest_points(q), pts["arm"], pts["object"]], axis=1)
    return pts


def _agf_over_time(scenario, geometry: ArmGeometry, q: np.ndarray, people: PeopleLog) -> dict[str, np.ndarray]:
    """Each part's thresholded AGF sum over the present people (M,) at their
    logged poses, sample by sample (Kirby's speed scaling when the scenario asks)."""
    options = scenario.social
    space = PersonalSpace.from_options(options)
    out = {part: np.zeros(len(q)) for part in RUN_PARTS}
    if people.count == 0:
        return out
    for lo in range(0, len(q), _AGF_BLOCK):
        k = slice(lo, lo + _AGF_BLOCK)
        pos, heading = people.positions[k], people.headings[k]  # (B, P, 2), (B, P)
        sp = space
        if options.speed_scaling:
            sigma_h = np.maximum(2.0 * np.hypot(*np.moveaxis(people.velocities[k], -1, 0)), 0.5)[:, None, :]
            sp = dc.replace(space, sigma_h=sigma_h, sigma_s=sigma_h * options.side_ratio,
                            sigma_r=sigma_h * options.rear_ratio)
        cos, sin = np.cos(heading)[:, None, :], np.sin(heading)[:, None, :]
        present = people.present[k][:, None, :]
        for part, pts in _part_points(geometry, q[k]).items():
            value = gaussian(pts[..., 0, None] - pos[:, None, :, 0], pts[..., 1, None] - pos[:, None, :, 1],
                             cos, sin, sp)  # (B, n, P)
            out[part][k] = np.where(present, apply_threshold(value, space), 0.0).sum(-1).max(-1)
    return out


def run_metrics(scenario, times: np.ndarray, q: np.ndarray, people: PeopleLog | None, stopped: np.ndarray | None,
                reached: bool, time_limit: float, *, time_to_goal: float | None = None,
                zones: HallZones = ZONES) -> dict[str, float]:
    """The social-navigation metrics of an executed run against where people
    were (the table of the module docstring).

    Args:
        scenario: gives the robot, the object and the AGF's options.
        times: (T,) strictly increasing sample times, seconds (T >= 1).
        q: (T, 4) executed configurations at ``times``.
        people: the people at the same times (``people.times`` equal to
            ``times``); None = nobody.
        stopped: (T,) True while the safety monitor held the robot; None =
            not recorded (the stop metrics are NaN).
        reached: the goal was reached.
        time_limit: the run's time limit, seconds (for ``timeout``).
        time_to_goal: the simulator's goal time, seconds; None = ``D``.
        zones: Hall's zone bounds.

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
    if stopped is not None and np.asarray(stopped).shape != (t,):
        raise ValueError(f"run_metrics: stopped must be (T,) = ({t},) booleans, got {np.asarray(stopped).shape}")
    g = ArmGeometry.from_scenario(scenario)
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
    object_points = g.interest_points(q)[:, 3:]
    out.update({f"{k}_object": v for k, v in motion_stats(times, object_points).items()})
    if stopped is None:
        out.update(stopped_time=float("nan"), stop_count=float("nan"), stopped_share=float("nan"))
    else:
        count, seconds = episodes(np.asarray(stopped, bool), times)
        out.update(stopped_time=seconds, stop_count=float(count), stopped_share=share(seconds))
    out["people_count"] = float(people.count if people is not None else 0)
    out["people_moving"] = float(people is not None and people.count > 0 and not people.static)
    if people is None or people.count == 0:
        dist = {p: np.full(t, np.inf) for p in RUN_PARTS}
        agf = {p: np.zeros(t) for p in RUN_PARTS}
    else:
        dist = proximity.part_distances(g, q, people.positions, people.radii, people.present)
        agf = _agf_over_time(scenario, g, q, people)
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
        out[f"collision_time_{part}"] = seconds
        out[f"space_compliance_{part}"] = share(held_time(d >= zones.intimate, times))
        out[f"agf_time_{part}"] = float(np.trapezoid(agf[part], times)) if t > 1 else 0.0
    return out
