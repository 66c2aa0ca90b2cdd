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

* ``planar`` (the default): :class:`~drake_social.model.planar_checker.PlanarChecker`,
  exact planar distances of the SceneGraph's own shapes, compiled, with
  sound motion checks (conservative advancement);
* ``drake``: :class:`SceneGraphChecker`, Drake alone, for comparison. Its
  motion check is **approximate**: it advances by Drake's clearance, which
  overestimates some cylinder-box distances (FCL's GJK; e.g. generic_L at
  q = [10.78156014, 5.65723962, 0.02822218, -0.18334348]: 1.0786 m where the
  exact value is 0.4043 m), and by at least ``resolution / 2`` per query;
* ``numpy``: :class:`~drake_social.planning.geometric.GeometricChecker`,
  the pure-numpy reference, sound by conservative advancement too.

:func:`verify_path` is the independent second opinion: Drake's discrete
edge check of every segment of a path at the checker's resolution.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
from pydrake.common import Parallelism
from pydrake.planning import LinearDistanceAndInterpolationProvider, SceneGraphCollisionChecker

from drake_social.arguments import require_choice, require_scenario
from drake_social.kinematics import displacement_bound
from drake_social.model.plant import ScenarioDiagram, build_robot_diagram
from drake_social.planning.geometric import CheckerBase
from drake_social.scenario import CHECKERS, Scenario, ScenarioError

__all__ = ["CHECKERS", "Contact", "SceneGraphChecker", "check_start_goal", "make_checker", "verify_path"]


@dc.dataclass(frozen=True)
class Contact:
    """A robot body touching or penetrating an environment shape.

    Attributes:
        robot_body: ``base``, ``link1``, ``link2`` or ``object``.
        other: the environment shape (``obstacle[i]``, ``person[i] 'name'``,
            ``wall_<side>``).
        distance: their signed distance, metres (<= 0).
    """

    robot_body: str
    other: str
    distance: float

    def __str__(self) -> str:
        return f"{self.robot_body} with {self.other} ({self.distance:+.3f} m)"


class SceneGraphChecker(CheckerBase):
    """Configuration and motion validity from SceneGraph collision queries.

    Args:
        scenario, resolution: see :class:`CheckerBase` (geometry, limits).
        parallelism: threads of the batched calls (:meth:`are_valid`,
            :meth:`are_motions_valid`): True = all cores, False = 1, or a count.

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

    def __init__(self, scenario: Scenario, resolution: float | None = None, parallelism: bool | int = True):
        super().__init__(scenario, resolution)
        self.parallelism = Parallelism(parallelism)
        b = scenario.world.bounds
        self.model: ScenarioDiagram = build_robot_diagram(scenario)
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
        return sorted((Contact(a, b, d) for (a, b), d in deepest.items()), key=lambda c: c.distance)


def check_start_goal(
    scenario: Scenario, checker: SceneGraphChecker | None = None, source: str = "<scenario>"
) -> None:
    """Rejects a scenario whose start or goal configuration is not valid.

    Args:
        scenario: the scenario to check.
        checker: a checker of this scenario (built if None).
        source: the file name used in the message.

    Raises:
        ScenarioError: naming ``source``, the field (``start`` or ``goal``),
            the configuration and which robot bodies collide with which
            obstacles, people or walls (or which limit is exceeded).
    """
    checker = checker or SceneGraphChecker(scenario)
    for field in ("start", "goal"):
        q = np.asarray(getattr(scenario, field), float)
        if not checker.in_limits(q):
            raise ScenarioError(
                f"{source}: {field}: configuration {q.tolist()} is outside the limits "
                f"lower={checker.lower.tolist()}, upper={checker.upper.tolist()} (world.bounds, robot.joint_*)"
            )
        contacts = checker.contacts(q)
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
        from drake_social.planning.geometric import GeometricChecker

        return GeometricChecker(scenario)
    if kind == "planar":
        from drake_social.model.planar_checker import PlanarChecker  # it imports this module

        checker = PlanarChecker(scenario)
        if source is not None:
            check_start_goal(scenario, checker.drake_checker, source)
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
            scenario at its resolution; a ``PlanarChecker`` lends its own
            ``drake_checker``).
        waypoints: (N, 4) configurations; a single waypoint is checked as a
            configuration (segment 0 = that configuration).

    Returns:
        The index i of the first failing segment, or None when all pass.
    """
    x = scenario_or_checker
    if isinstance(x, Scenario):
        drake = SceneGraphChecker(x)
    elif isinstance(x, SceneGraphChecker):
        drake = x
    elif hasattr(x, "drake_checker"):
        drake = x.drake_checker
    elif isinstance(x, CheckerBase):
        drake = SceneGraphChecker(x.scenario, x.resolution)
    else:
        raise TypeError(f"verify_path needs a Scenario or a checker, got {type(x).__name__}")
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    if len(wp) == 1:
        return None if drake.are_valid(wp)[0] else 0
    bad = np.flatnonzero(~drake.are_motions_valid(wp[:-1], wp[1:]))
    return int(bad[0]) if len(bad) else None
