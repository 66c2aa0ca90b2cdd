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

Over time, against where people actually were: :func:`run_metrics` and
:func:`execution_metrics` (the ``nav_*`` fields of ``sim.json`` and the
studies), defined in :mod:`drake_social.evaluation.nav_metrics` and
re-exported here; the zones and the track measures shared by both live in
:mod:`drake_social.evaluation.proxemics`.
"""

from __future__ import annotations

import numpy as np

from drake_social.cost.social import SocialCost
from drake_social.evaluation.nav_metrics import RUN_PARTS, execution_metrics, run_metrics
from drake_social.evaluation.proxemics import (
    HEADING_STEP,
    SHAPE_SPACING,
    ZONES,
    HallZones,
    base_irregularity,
    shape_points,
    zone_shares,
)
from drake_social.evaluation.records import path_costs
from drake_social.kinematics import ArmGeometry, config_distance
from drake_social.people import PeopleLog, people_model, proximity
from drake_social.people.proximity import part_names
from drake_social.scenario.geometry import arm_geometry

__all__ = [
    "HEADING_STEP",
    "RUN_PARTS",
    "SHAPE_SPACING",
    "ZONES",
    "HallZones",
    "base_irregularity",
    "executed_metrics",
    "execution_metrics",
    "part_agf",
    "part_distances",
    "part_names",
    "path_metrics",
    "run_metrics",
    "trajectory_metrics",
    "zone_shares",
]


def part_distances(geometry: ArmGeometry, people: np.ndarray, radii: np.ndarray, q: np.ndarray,
                   present: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Surface-to-surface distance (M,) of every part to the nearest person's
    body disc at configurations q (M, 4), metres, people standing at
    ``people`` (P, 3) rows [x, y, theta]; only the people whose ``present``
    (P,) flag is set count (None = everyone); +inf when nobody counts."""
    people = np.asarray(people, float).reshape(-1, 3)
    return proximity.part_distances(geometry, q, people[:, :2], radii, present)


def part_agf(cost: SocialCost, q: np.ndarray) -> dict[str, np.ndarray]:
    """Thresholded AGF sum over people (M,) met by every part at configurations q (M, 4).

    Interest points: their value; ``arm`` and ``object``: the largest over
    their axis; ``robot``: the largest over every part. Every part with the
    same per-person variances (:meth:`SocialCost.agf_values`).
    """
    q = np.asarray(q, float).reshape(-1, 4)
    g = cost.geometry
    values = cost.point_costs(q)  # (M, K)
    out = {n: values[:, k] for k, n in enumerate(g.interest_names)}
    for name, which in (("arm", slice(0, 2)), ("object", slice(2, None))):
        pts = shape_points(g, q, which)
        # Each person's own variances (speed-scaled under social.speed_scaling), as the points'.
        out[name] = cost.agf_values(pts[..., 0], pts[..., 1]).sum(-1).max(-1)
    out["robot"] = np.max([out[n] for n in g.interest_names + ["arm", "object"]], axis=0)
    return out


def trajectory_metrics(
    scenario, q: np.ndarray, s: np.ndarray | None = None, times: np.ndarray | None = None, zones: HallZones = ZONES,
    people: PeopleLog | None = None,
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
        people: where the people were during an executed run (the run's
            :class:`~drake_social.people.PeopleLog`, a crowd that met the
            robot included); None = the scenario's people model (a crowd
            stepped without the robot). Read at ``times`` when the people
            move; people not present at a sample do not count there.

    Returns:
        ``min_dist_<part>``, ``zone_<zone>_<part>``, (``zone_time_<zone>_<part>``),
        ``agf_max_<part>``, ``agf_mean_<part>`` for every part of :func:`part_names`.
    """
    q = np.asarray(q, float).reshape(-1, 4)
    g = arm_geometry(scenario)
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
        times = np.asarray(times, float)
        if people is None:
            states = [model.state_at(float(t)) for t in times]
        elif len(people.times) == len(times) and np.array_equal(people.times, times):
            states = [people.state(k) for k in range(len(times))]  # the log's own samples
        else:
            states = [people.state_at(float(t)) for t in times]
        per_sample = []
        for qi, state in zip(q, states):
            per_sample.append((part_distances(g, state.poses(), state.radii, qi, state.present),
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
    n = arm_geometry(scenario).num_interest_points
    out = path_costs(scenario, wp, planner_weights)
    out["irregularity"] = base_irregularity(wp[:, :2])
    s, q = sample_path(wp, SocialCost.from_scenario(scenario, np.ones(n)), refine)
    out.update(trajectory_metrics(scenario, q, s))
    return out


def executed_metrics(scenario, times: np.ndarray, q: np.ndarray, people: PeopleLog | None = None) -> dict[str, float]:
    """Per-part metrics of an executed trajectory (times (T,), q (T, 4)),
    with zone shares by time too, and its F and lengths; keys prefixed ``exec_``.

    ``people``: the run's :class:`~drake_social.people.PeopleLog`
    (``SimulationResult.people``), where the people actually were; None =
    the scenario's people model (see :func:`trajectory_metrics`). ``F_multi``
    is the planner's cost function: against the people at t = 0."""
    q = np.asarray(q, float).reshape(-1, 4)
    n = arm_geometry(scenario).num_interest_points
    multi = SocialCost.from_scenario(scenario, np.ones(n))
    out = {
        "F_multi": float(multi.motion_cost(q[:-1], q[1:]).sum()) if len(q) > 1 else 0.0,
        "path_length": float(config_distance(q[:-1], q[1:]).sum()) if len(q) > 1 else 0.0,
        "base_length": float(np.hypot(*np.diff(q[:, :2], axis=0).T).sum()) if len(q) > 1 else 0.0,
        "irregularity": base_irregularity(q[:, :2]),
    }
    out.update(trajectory_metrics(scenario, q, None, np.asarray(times, float), people=people))
    return {f"exec_{k}": v for k, v in out.items()}

