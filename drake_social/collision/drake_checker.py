"""A :class:`ValidityChecker` backed by Drake's SceneGraphCollisionChecker.

Configurations ``q = [x, y, psi1, psi2]`` are the plant's positions. A
configuration is valid when it lies within the room bounds (base centre) and
the joint limits, and no robot body (base, link 1, link 2, object) touches
the environment: SceneGraph reports a collision when a signed distance is
<= 0. Robot-robot pairs are filtered in the model (the arm carries the object
above the base; see :mod:`drake_social.model.robot_model`).

Motions. Drake checks an edge at ``ceil(d / edge_step_size)`` equal steps of
its configuration distance d. We use a
``LinearDistanceAndInterpolationProvider`` with weights
``w = ArmGeometry.reach(include_body=True) = (1, 1, c1, c2)`` (the lever arm of
each coordinate), so ``d = sqrt(dx^2 + dy^2 + (c1 dpsi1)^2 + (c2 dpsi2)^2)``.
Any body point moves at most ``hypot(dx, dy) + c1 |dpsi1| + c2 |dpsi2|``,
which is <= sqrt(3) d (Cauchy-Schwarz over three terms). Hence
``edge_step_size = resolution / sqrt(3)`` guarantees that no point moves more
than ``resolution`` between two checked configurations. The limits are a box,
so a motion between two configurations within them stays within them.

Which checker (:data:`CHECKERS`, :func:`make_checker`):

* ``planar`` (the default): :class:`~drake_social.collision.planar_checker.PlanarChecker`,
  exact planar distances of the SceneGraph's own shapes, compiled, with
  sound motion checks (conservative advancement);
* ``drake``: :class:`SceneGraphChecker`, Drake alone, for comparison. Its
  motion check is **approximate**: it advances by Drake's clearance, which
  overestimates some cylinder-box distances (FCL's GJK; e.g. generic_L at
  q = [10.78156014, 5.65723962, 0.02822218, -0.18334348]: 1.0786 m where the
  exact value is 0.4043 m), and by at least ``resolution / 2`` per query;
* ``numpy``: :class:`~drake_social.collision.geometric.GeometricChecker`,
  the pure-numpy reference, sound by conservative advancement too.

:func:`verify_path` is the independent second opinion: Drake's discrete
edge check of every segment of a path at the checker's resolution, from
SceneGraphs that each hold only the shapes near a group of segments
(:func:`local_checkers`): SceneGraph keeps a filter state for every pair of
its shapes, in every context, so one SceneGraph of a room of thousands of
boxes would take gigabytes.
"""

from __future__ import annotations

import math
from typing import Iterator, Sequence

import numpy as np
from pydrake.common import Parallelism
from pydrake.planning import LinearDistanceAndInterpolationProvider, SceneGraphCollisionChecker

from drake_social.arguments import require_choice, require_scenario
from drake_social.kinematics import ArmGeometry, displacement_bound
from drake_social.model import plant
from drake_social.model.plant import (
    ScenarioDiagram,
    build_robot_diagram,
    environment_discs,
    environment_parts,
    registration_order,
    shape_label,
)
from drake_social.collision.geometric import CheckerBase, GeometricChecker
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.collision.validity import Contact
from drake_social.scenario import CHECKERS, Scenario, ScenarioError
from drake_social.scenario.geometry import arm_geometry, configuration_limits

__all__ = ["CHECKERS", "MAX_DRAKE_CHECKER_SHAPES", "Contact", "SceneGraphChecker", "check_start_goal", "local_checkers", "make_checker",
           "near_environment", "valid_configurations", "verify_path"]


#: Most environment shapes of a :class:`SceneGraphChecker` of the whole room
#: (its one SceneGraph keeps a filter state for every pair of shapes, about
#: 60 N^2 bytes: 240 MB at 2,000, per context). Parts (:func:`local_checkers`)
#: have no such bound.
MAX_DRAKE_CHECKER_SHAPES = 2_000


class SceneGraphChecker(CheckerBase):
    """Configuration and motion validity from SceneGraph collision queries.

    Args:
        scenario, resolution: see :class:`CheckerBase` (geometry, limits).
        parallelism: threads of the batched calls (:meth:`are_valid`,
            :meth:`are_motions_valid`): True = all cores, False = 1, or a count.
        environment: indices into
            :func:`~drake_social.model.plant.environment_names` of the shapes
            checked against (a part of the room, see :func:`local_checkers`);
            None = all.

    Attributes:
        edge_step_size: Drake's step in its weighted configuration distance,
            ``resolution / sqrt(3)``.
        model: the :class:`ScenarioDiagram` checked.
        drake: the underlying ``SceneGraphCollisionChecker``.
    """

    #: Clearance queries report distances up to this far, metres; beyond it a
    #: configuration counts as this far from everything.
    influence: float = 1.0
    #: Clearances are trusted to this many metres (Drake's distance between a
    #: cylinder and a box is iterative, ~2e-5 m from exact).
    CLEARANCE_MARGIN: float = 1e-4
    #: Configurations whose clearance is remembered (oldest forgotten first).
    cache_size: int = 100_000

    def __init__(self, scenario: Scenario, resolution: float | None = None, parallelism: bool | int = True,
                 environment: Sequence[int] | None = None):
        super().__init__(scenario, resolution)
        self.parallelism = Parallelism(parallelism)
        b = scenario.world.bounds
        if environment is None:
            count = len(registration_order(scenario))
            if count > MAX_DRAKE_CHECKER_SHAPES:
                raise ScenarioError(
                    f"world: {count:,} shapes (obstacles, the boxes of world.map, people, walls) are too many for "
                    f"Drake's SceneGraphCollisionChecker, which holds them in one SceneGraph (a filter state for "
                    f"every pair: about {60 * count**2 / 1e9:.1f} GB); at most {MAX_DRAKE_CHECKER_SHAPES:,}: use the "
                    f"planar checker (--checker planar), which reads the room in parts")
        self.model: ScenarioDiagram = build_robot_diagram(scenario, environment=environment)
        plant = self.model.diagram.plant()
        provider = LinearDistanceAndInterpolationProvider(plant, self.geometry.reach(include_body=True))
        self.edge_step_size = self.resolution / math.sqrt(3.0)
        self.drake = SceneGraphCollisionChecker(
            model=self.model.diagram,
            robot_model_instances=[self.model.robot],
            distance_and_interpolation_provider=provider,
            edge_step_size=self.edge_step_size,
            env_collision_padding=0.0,
            self_collision_padding=0.0,
        )
        self._report_context = self.drake.MakeStandaloneModelContext()
        self._clearance_cache: dict[bytes, float] = {}
        self._body_lever = self.geometry.lever(include_body=True)
        # The robot (when valid) and every shape lie in the walled room: no clearance exceeds this.
        self._influence = float(np.hypot(b[2] - b[0], b[3] - b[1])) + 2 * scenario.world.wall_thickness

    # ---- ValidityChecker ------------------------------------------------------

    def is_valid(self, q: np.ndarray) -> bool:
        """One configuration (4,); remembers its clearance for motion checks."""
        q = np.asarray(q, float)
        return bool(self.in_limits(q)) and self._capped_clearance(q, remember=True) > 0.0

    def clear_cache(self) -> None:
        """Forgets the remembered clearances (for fair timing)."""
        self._clearance_cache.clear()

    def _capped_clearance(self, q: np.ndarray, remember: bool = False) -> float:
        """``min(clearance(q), influence)``; cached for configurations checked
        by :meth:`is_valid` (tree nodes are checked once, then used as motion
        ends many times)."""
        key = q.tobytes()
        c = self._clearance_cache.get(key)
        if c is None:
            d = self.drake.CalcRobotClearance(q, self.influence).distances()
            c = float(d.min()) if len(d) else self.influence
            c = min(c, self.influence)
            if remember:
                if len(self._clearance_cache) >= self.cache_size:
                    self._clearance_cache.pop(next(iter(self._clearance_cache)))  # oldest first
                self._clearance_cache[key] = c
        return c

    def are_valid(self, qs: np.ndarray) -> np.ndarray:
        """Many configurations (N, 4) -> (N,) bool, checked in parallel."""
        qs = np.asarray(qs, float).reshape(-1, 4)
        ok = self.in_limits(qs)
        if ok.any():
            free = self.drake.CheckConfigsCollisionFree(list(qs[ok]), self.parallelism)
            ok[ok] = np.asarray(free, bool)
        return ok

    def is_motion_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """The straight motion from q_a to q_b (4,), ends included.

        Conservative advancement on clearance: if the robot is ``c`` metres
        from everything at ``q(t)``, no configuration whose body points moved
        less than ``c`` from there can collide, and along this motion body
        points move at most ``D |t' - t|`` (``D`` from
        :meth:`ArmGeometry.max_displacement`). Each clearance query therefore
        clears an interval of t around it; uncovered intervals are bisected
        until none is left or a query finds a collision. A query clears at
        least ``resolution / 2`` either side, which is exactly the guarantee
        of discrete checking at ``resolution`` (every configuration within
        ``resolution / 2`` of a checked one), so this accepts no motion that
        discrete checking would reject for want of samples, and needs a few
        queries instead of ``D / resolution`` in open space. In the planner
        (motion ends cached by :meth:`is_valid`) this is 3-4x faster than
        Drake's discrete edge check on office_bar and generic_L (RRT*, K =
        2000, 0.58-0.72 s against 1.7-2.7 s), with identical paths; a
        fallback to discrete checking in tight spots measured slower.
        """
        q_a, q_b = np.asarray(q_a, float), np.asarray(q_b, float)
        cached = self._clearance_cache
        # Only configurations within the limits are cached (by is_valid).
        if not (q_a.tobytes() in cached and q_b.tobytes() in cached) and not (
            self.in_limits(q_a) and self.in_limits(q_b)
        ):
            return False
        c_a = self._capped_clearance(q_a)
        c_b = self._capped_clearance(q_b)
        if c_a <= 0.0 or c_b <= 0.0:
            return False
        span = float(displacement_bound(q_b - q_a, self._body_lever))
        if span == 0.0:
            return True
        dq = q_b - q_a
        floor = 0.5 * self.resolution

        def cover(c: float) -> float:  # fraction of t cleared either side of a query
            return max(c - self.CLEARANCE_MARGIN, floor) / span

        stack = [(cover(c_a), 1.0 - cover(c_b))]
        while stack:
            lo, hi = stack.pop()
            if lo > hi:
                continue
            t = 0.5 * (lo + hi)
            c = self._capped_clearance(q_a + t * dq)
            if c <= 0.0:
                return False
            r = cover(c)
            stack.append((t + r, hi))
            stack.append((lo, t - r))
        return True

    def are_motions_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Many motions (E, 4), (E, 4) -> (E,) bool, checked in parallel."""
        q_a = np.asarray(q_a, float).reshape(-1, 4)
        q_b = np.asarray(q_b, float).reshape(-1, 4)
        ok = self.in_limits(q_a) & self.in_limits(q_b)
        if ok.any():
            free = self.drake.CheckEdgesCollisionFree(list(zip(q_a[ok], q_b[ok])), self.parallelism)
            ok[ok] = np.asarray(free, bool)
        return ok

    def clearance(self, q: np.ndarray) -> float:
        """Smallest signed distance (metres) from a robot body to the environment.

        Negative when penetrating; ignores the limits (see :meth:`in_limits`).
        """
        result = self.drake.CalcRobotClearance(np.asarray(q, float), self._influence)
        d = result.distances()
        return float(d.min()) if len(d) else math.inf

    # ---- reports --------------------------------------------------------------

    def contacts(self, q: np.ndarray) -> list[Contact]:
        """The (robot body, environment shape) pairs at signed distance <= 0.

        One entry per pair (the deepest of its shapes), deepest first.
        """
        context = self._report_context
        self.drake.UpdateContextPositions(context, np.asarray(q, float))
        query = context.GetQueryObject()
        inspector = query.inspector()
        plant = self.model.diagram.plant()
        world = plant.world_body().index()
        deepest: dict[tuple[str, str], float] = {}
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(max_distance=0.0):
            if pair.distance > 0.0:
                continue
            bodies = [plant.GetBodyFromFrameId(inspector.GetFrameId(g)) for g in (pair.id_A, pair.id_B)]
            if bodies[0].index() == world:
                bodies.reverse()
                ids = (pair.id_B, pair.id_A)
            else:
                ids = (pair.id_A, pair.id_B)
            if bodies[1].index() != world:  # robot-robot pairs are filtered in the model
                continue
            key = (bodies[0].name(), inspector.GetName(ids[1]))
            deepest[key] = min(pair.distance, deepest.get(key, math.inf))
        return sorted((Contact(a, shape_label(self.scenario, b), d) for (a, b), d in deepest.items()),
                      key=lambda c: c.distance)


def near_environment(scenario: Scenario, a_xy: np.ndarray, b_xy: np.ndarray, margin: float = 0.01) -> np.ndarray:
    """Indices into :func:`~drake_social.model.plant.environment_names` of the
    shapes the robot can touch while its base moves on the straight tracks
    ``a_xy[i] -> b_xy[i]`` ((M, 2) each), in :func:`registration_order`.

    A shape is kept when its bounding disc (:func:`environment_discs`) comes
    within the robot's extent from its base centre (base radius, or the
    arm's and object's reach with their capsule radii) plus ``margin`` metres
    of a track: every other shape is farther than any robot point at any
    configuration on the tracks, whatever the arm angles.
    """
    return _near_function(scenario, margin)(a_xy, b_xy)


def _near_function(scenario: Scenario, margin: float = 0.01, *, per_track: bool = False):
    """:func:`near_environment` of ``scenario`` as a function of the tracks
    (the room's discs and the robot's extent computed once); with
    ``per_track``, the function gives an (M, S) bool matrix instead: shape
    ``registration_order(scenario)[j]`` is near track i."""
    geometry = arm_geometry(scenario)
    extent = max(float(scenario.robot.base_radius), float(np.sum(geometry.lever(include_body=True))))
    discs = environment_discs(scenario)
    order = np.asarray(registration_order(scenario), int)

    rows = max(1, (1 << 16) // max(1, len(discs)))  # tracks per block: memory bounded whatever the room

    def near_tracks(a_xy: np.ndarray, b_xy: np.ndarray) -> np.ndarray:
        a = np.asarray(a_xy, float).reshape(-1, 2)
        d = np.asarray(b_xy, float).reshape(-1, 2) - a
        hit = np.zeros((len(a), len(discs)), dtype=bool)
        for r0 in range(0, len(a), rows):
            start, step = a[r0:r0 + rows, None, :], d[r0:r0 + rows, None, :]  # (m, 1, 2)
            rel = discs[None, :, :2] - start  # (m, D, 2)
            length2 = step[..., 0] * step[..., 0] + step[..., 1] * step[..., 1]  # (m, 1)
            along = rel[..., 0] * step[..., 0] + rel[..., 1] * step[..., 1]
            with np.errstate(invalid="ignore", divide="ignore"):
                t = np.where(length2 > 0, np.clip(along / np.where(length2 > 0, length2, 1.0), 0.0, 1.0), 0.0)
            gap = np.hypot(rel[..., 0] - t * step[..., 0], rel[..., 1] - t * step[..., 1]) - discs[:, 2]
            hit[r0:r0 + rows] = ~(gap > extent + margin)  # NaN keeps the shape
        return hit

    def near(a_xy: np.ndarray, b_xy: np.ndarray) -> np.ndarray:
        hit = near_tracks(a_xy, b_xy).any(axis=0)
        return order[hit[order]]

    return (lambda a_xy, b_xy: near_tracks(a_xy, b_xy)[:, order]) if per_track else near


def local_checkers(scenario: Scenario, a_xy: np.ndarray, b_xy: np.ndarray, resolution: float | None = None,
                   parallelism: bool | int = True) -> Iterator[SceneGraphChecker]:
    """Drake checkers that together hold every shape near the base tracks
    ``a_xy[i] -> b_xy[i]`` (:func:`near_environment`), at most
    :data:`~drake_social.model.plant.ENVIRONMENT_PART` shapes each, built one
    at a time (at least one, with the robot alone when nothing is near).

    A configuration on the tracks collides with the room exactly when it
    collides with a shape of one of them: Drake's answers for the room,
    from SceneGraphs whose memory does not grow with the room.
    """
    for part in environment_parts(near_environment(scenario, a_xy, b_xy)):
        yield SceneGraphChecker(scenario, resolution, parallelism=parallelism, environment=part)


def check_start_goal(
    scenario: Scenario, checker: SceneGraphChecker | None = None, source: str = "<scenario>"
) -> None:
    """Rejects a scenario whose start or goal configuration is not valid.

    Args:
        scenario: the scenario to check.
        checker: a checker of this scenario; None = Drake checkers of the
            shapes near the start and the goal (:func:`local_checkers`).
        source: the file name used in the message.

    Raises:
        ScenarioError: naming ``source``, the field (``start`` or ``goal``),
            the configuration and which robot bodies collide with which
            obstacles, people or walls (or which limit is exceeded).
    """
    lower, upper = configuration_limits(scenario)
    for field in ("start", "goal"):
        q = np.asarray(getattr(scenario, field), float)
        if not np.all((q >= lower) & (q <= upper)):
            raise ScenarioError(
                f"{source}: {field}: configuration {q.tolist()} is outside the limits "
                f"lower={lower.tolist()}, upper={upper.tolist()} (world.bounds, robot.joint_*)"
            )
        checkers = [checker] if checker is not None else local_checkers(scenario, q[None, :2], q[None, :2])
        contacts: list[Contact] = []
        for part in checkers:
            contacts += part.contacts(q)
        contacts.sort(key=lambda c: c.distance)
        if contacts:
            raise ScenarioError(
                f"{source}: {field}: configuration {q.tolist()} is in collision: "
                + "; ".join(str(c) for c in contacts)
            )


def make_checker(
    scenario: Scenario, kind: str = "planar", *, parallelism: bool | int = True, source: str | None = None
):
    """A validity checker of ``scenario``: ``"planar"`` (exact, compiled, the
    default), ``"drake"`` (SceneGraph alone) or ``"numpy"`` (see the module docstring).

    Args:
        parallelism: threads of the Drake checker's batched calls.
        source: the scenario's file name; when given, the planar and Drake
            checkers first reject a start or goal in collision with a
            :class:`ScenarioError` naming the file and Drake's touching
            bodies (:func:`check_start_goal`).

    Raises:
        TypeError: ``scenario`` is not a Scenario, ``kind`` not a string.
        ValueError: an unknown ``kind``.
    """
    require_scenario(scenario, "make_checker")
    require_choice(kind, "make_checker", "kind", CHECKERS)
    if kind == "numpy":
        return GeometricChecker(scenario)
    if kind == "planar":
        checker = PlanarChecker(scenario)
        if source is not None:
            check_start_goal(scenario, None, source)
        return checker
    if kind != "drake":
        raise ValueError(f"unknown checker {kind!r}; allowed: {', '.join(CHECKERS)}")
    checker = SceneGraphChecker(scenario, parallelism=parallelism)
    if source is not None:
        check_start_goal(scenario, checker, source)
    return checker


def verify_path(scenario_or_checker, waypoints: np.ndarray) -> int | None:
    """Drake's second opinion on a path: the first segment that fails, or None.

    Every segment ``waypoints[i] -> waypoints[i + 1]`` is checked by Drake's
    ``SceneGraphCollisionChecker`` alone (``CheckEdgesCollisionFree``: the
    limits, then discrete collision checks at the checker's resolution, ends
    included; see the module docstring), independently of the checker that
    planned it.

    Args:
        scenario_or_checker: a :class:`Scenario` (checked at its
            ``planner.collision_resolution``), a :class:`SceneGraphChecker`
            (used as is), or any other checker of this package (its
            scenario at its resolution). Without a SceneGraphChecker, the
            segments are checked in consecutive groups against Drake
            checkers of the shapes near each group (:func:`local_checkers`,
            at most :data:`~drake_social.model.plant.ENVIRONMENT_PART`
            shapes per SceneGraph), which give the same answers as one
            checker of the whole room in bounded memory.
        waypoints: (N, 4) configurations; a single waypoint is checked as a
            configuration (segment 0 = that configuration).

    Returns:
        The index i of the first failing segment, or None when all pass.
    """
    x = scenario_or_checker
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    if isinstance(x, SceneGraphChecker):
        if len(wp) == 1:
            return None if x.are_valid(wp)[0] else 0
        bad = np.flatnonzero(~x.are_motions_valid(wp[:-1], wp[1:]))
        return int(bad[0]) if len(bad) else None
    if isinstance(x, Scenario):
        scenario, resolution = x, None
    elif isinstance(x, CheckerBase):
        scenario, resolution = x.scenario, x.resolution
    else:
        raise TypeError(f"verify_path needs a Scenario or a checker, got {type(x).__name__}")
    if len(wp) == 1:
        ok = all(part.are_valid(wp)[0] for part in local_checkers(scenario, wp[:, :2], wp[:, :2], resolution))
        return None if ok else 0
    for first, stop in _segment_groups(scenario, wp):
        a, b = wp[first:stop], wp[first + 1 : stop + 1]
        ok = np.ones(len(a), dtype=bool)
        for part in local_checkers(scenario, a[:, :2], b[:, :2], resolution):
            ok &= part.are_motions_valid(a, b)
        bad = np.flatnonzero(~ok)
        if len(bad):
            return first + int(bad[0])
    return None


def valid_configurations(scenario: Scenario, qs: np.ndarray, resolution: float | None = None) -> np.ndarray:
    """Drake's verdicts on configurations (N, 4) -> (N,) bool (within the
    limits and collision-free, :meth:`SceneGraphChecker.are_valid`), from
    SceneGraphs of the shapes near runs of consecutive configurations (a
    trajectory's samples): the same answers as one checker of the whole room,
    in memory that does not grow with the room (see :func:`verify_path`)."""
    qs = np.asarray(qs, float).reshape(-1, 4)
    ok = np.ones(len(qs), dtype=bool)
    groups = _segment_groups(scenario, qs) if len(qs) > 1 else [(0, len(qs) - 1)] if len(qs) else []
    for first, stop in groups:
        run = qs[first : stop + 1]
        a, b = (run[:-1, :2], run[1:, :2]) if len(run) > 1 else (run[:, :2], run[:, :2])
        for part in local_checkers(scenario, a, b, resolution):
            ok[first : stop + 1] &= np.asarray(part.are_valid(run), bool)
    return ok


def _segment_groups(scenario: Scenario, wp: np.ndarray) -> list[tuple[int, int]]:
    """Consecutive segments ``[first, stop)`` of the path ``wp`` grouped so
    that the shapes near a group fit in one part
    (:data:`~drake_social.model.plant.ENVIRONMENT_PART`) where they can: a
    group grows while its shapes do; a segment near more shapes is a group
    alone (checked in several parts)."""
    groups: list[tuple[int, int]] = []
    near_of = _near_function(scenario, per_track=True)
    first, shapes = 0, 0  # the group's near shapes as a bit set
    block = 4096  # segments whose near shapes are computed at once
    for b0 in range(0, len(wp) - 1, block):
        b1 = min(b0 + block, len(wp) - 1)
        near = near_of(wp[b0:b1, :2], wp[b0 + 1 : b1 + 1, :2])  # (m, S)
        packed = np.packbits(near, axis=1)
        for i in range(b0, b1):
            row = int.from_bytes(packed[i - b0].tobytes(), "big")
            if i > first and (shapes | row).bit_count() > plant.ENVIRONMENT_PART:
                groups.append((first, i))
                first, shapes = i, 0
            shapes |= row
    groups.append((first, len(wp) - 1))
    return groups
