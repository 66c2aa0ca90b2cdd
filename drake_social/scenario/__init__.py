"""The scenario schema and its loading: the one place that knows the YAML format.

A scenario is a typed tree of dataclasses (in the style of Drake's
``examples/hardware_sim``): every field has a comment with its unit, defaults are
the paper's values, and files are loaded with
:func:`pydrake.common.yaml.yaml_load_typed`, which already rejects unknown
keys. :func:`load_scenario` then validates the values and raises one
:class:`ScenarioError` naming the file, the field and what is allowed.

Angles are radians, lengths metres. Configurations are ``q = [x, y, psi1,
psi2]``: base position, the angle of link 1 from the world x axis (the base
does not rotate) and the angle of link 2 relative to link 1.

This module imports pydrake lazily (only inside :func:`load_scenario`), so the
pure-numpy core may use the dataclasses without importing Drake.
"""


import dataclasses as dc
import functools
import math
import typing
from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from drake_social.limits import MAX_ITERATIONS, MAX_MOTION_STEPS
from drake_social.io.textfile import read_yaml_file, shorten

__all__ = [
    "ALGORITHMS",
    "CHECKERS",
    "EXECUTIONS",
    "MAX_CONTROL_STEPS",
    "MAX_PLANT_STEPS",
    "MAX_REPLAY_FPS",
    "MAX_TIME_LIMIT",
    "MAX_YAML_DEPTH",
    "MAX_YAML_NODES",
    "MIN_CONTROL_PERIODS",
    "INFORMED_MODES",
    "SIM_MODES",
    "Bar",
    "Box",
    "ExecutionOptions",
    "LShape",
    "Person",
    "PlannerOptions",
    "Polyline",
    "Robot",
    "Scenario",
    "ScenarioError",
    "SocialCostOptions",
    "World",
    "check_node",
    "check_yaml",
    "compose_yaml",
    "load_scenario",
    "load_scenario_text",
    "period_count",
    "validate_planner_choice",
    "validate_scenario",
]

#: Largest ``execution.time_limit``, seconds: twice the default (300 s) and
#: eight times the longest run of the shipped scenarios (office_bar reaches
#: its goal at 73-76 s in both modes and executions). Logs and the replay grow with it (a 1,200 s run held
#: 0.75 GB and wrote a 19.7 MB replay).
MAX_TIME_LIMIT = 600.0
#: Most control periods in one run (``time_limit / control_period``): the
#: logs keep one sample per period, about 3 kB each (the default 300 s /
#: 0.01 s is 30,000; this is MAX_TIME_LIMIT at the default period, a run that
#: peaked at 0.55 GB).
MAX_CONTROL_STEPS = 60_000
#: Most plant steps in one dynamic run (``time_limit / plant_time_step``):
#: MAX_TIME_LIMIT at the default 0.002 s step.
MAX_PLANT_STEPS = 300_000
#: The dynamic mode's servo (:func:`drake_social.sim.diagram.servo_gains`):
#: the arm joints' critically damped bandwidth, rad/s, and the base joints'
#: velocity time constant, seconds.
SERVO_BANDWIDTH = 60.0
SERVO_BASE_TIME_CONSTANT = 0.02
#: Largest ``execution.plant_time_step`` of a dynamic run, seconds: the
#: discrete plant applies the servo's force explicitly, stable while its
#: largest damping gain times the step, ``max(2 * SERVO_BANDWIDTH, 1 /
#: SERVO_BASE_TIME_CONSTANT) * dt``, is at most 1 (1/120 s; tiny.yaml's run
#: still tracked at 1.5 and blew up at 1.92).
MAX_DYNAMIC_PLANT_TIME_STEP = 1.0 / max(2.0 * SERVO_BANDWIDTH, 1.0 / SERVO_BASE_TIME_CONSTANT)
#: Fewest control periods in one run (``time_limit / control_period``). The
#: sequencer and the controllers act once per period and the time to goal
#: is known to one period; with fewer than 10 a run is decided by its
#: sampling (the time to goal would be off by more than a tenth of the
#: limit). The shipped scenarios run 30,000.
MIN_CONTROL_PERIODS = 10
#: Largest ``execution.replay_fps``, frames per second (the replay keeps every frame).
MAX_REPLAY_FPS = 60.0
#: Most vertices of a ``!Polyline`` object. Each segment is a box and each
#: vertex a cylinder of the Drake model, and Drake's second-opinion check of a
#: plan, the model's parsing and the figures take time in proportion: ``plan``
#: of scenarios/tiny.yaml carrying a smooth polyline takes 9 s with 100
#: vertices, 23 s with 300 and 160 s (2.6 GB) with 1,000, for a 0.1 s search.
MAX_OBJECT_POINTS = 200
#: Values of ``planner.near_radius_mode``.
NEAR_RADIUS_MODES = ("fixed", "shrinking")
#: Planner names accepted in ``planner.algorithm`` (see ``drake_social.planning``).
ALGORITHMS = (
    "rrt_star",
    "social_rrt_star",
    "base_rrt_star",
    "informed_social_rrt_star",
    "informed_base_rrt_star",
)

#: Validity checkers (``drake_social.collision.drake_checker.make_checker``; the first is
#: the default of the planner): the exact planar one, Drake's SceneGraph and
#: the pure-numpy reference. Here, not in that module, so that the command
#: line and studies can name them without importing Drake.
CHECKERS = ("planar", "drake", "numpy")

#: Modes of the informed sampler (see ``drake_social.planning.sampling``).
INFORMED_MODES = ("paper", "admissible")

#: Simulation modes (see ``drake_social.sim``): the base integrates its
#: commanded velocity and the arm follows its reference exactly, or the
#: MultibodyPlant is simulated with actuated joints.
SIM_MODES = ("kinematic", "dynamic")

#: How a path is executed (see ``drake_social.sim``): one phase-synchronized
#: 4-DoF reference per segment (stays on the straight segment the planner
#: checked), or the paper's independent base P-controller and arm trajectory.
EXECUTIONS = ("synchronized", "paper")


class ScenarioError(ValueError):
    """A scenario file or override is invalid; the message names file and field."""


@dc.dataclass
class Box:
    """A rectangular obstacle, extruded over the robot's height."""

    # Centre [x, y] of the box in the world frame, metres.
    center: list[float] = dc.field(default_factory=lambda: [0.0, 0.0])
    # Side lengths [along its own x axis, along its own y axis], metres (> 0).
    size: list[float] = dc.field(default_factory=lambda: [1.0, 1.0])
    # Rotation of the box about z, radians, counter-clockwise from world +x.
    yaw: float = 0.0


@dc.dataclass
class World:
    """The room: its walls and the obstacles inside it."""

    # Room bounds [x_min, y_min, x_max, y_max], metres; walls stand on them.
    bounds: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 10.0, 10.0])
    # Static obstacles (desks, walls, shelves).
    obstacles: list[Box] = dc.field(default_factory=list)
    # Thickness of the four boundary walls, metres, built outside the bounds.
    wall_thickness: float = 0.1


@dc.dataclass
class Person:
    """A static person: a body disc and a facing direction."""

    # Position of the body centre in the world frame, metres.
    x: float = 0.0
    y: float = 0.0
    # Facing direction, radians, counter-clockwise from world +x.
    theta: float = 0.0
    # Body radius, metres (> 0); the body is an obstacle too.
    radius: float = 0.25
    # Optional label used in figures and error messages.
    name: str = ""


@dc.dataclass
class Robot:
    """The planar mobile manipulator: a holonomic disc base and a 2-link arm."""

    # Radius of the (non-rotating) base disc, metres (> 0).
    base_radius: float = 0.35
    # Lengths [l1, l2] of the two links, metres (> 0). Link 1 starts at the
    # base centre; the gripper frame sits at the tip of link 2.
    link_lengths: list[float] = dc.field(default_factory=lambda: [0.6, 0.5])
    # Width of both links, metres (> 0); links are capsules of radius width/2.
    link_width: float = 0.08
    # Lower joint limits [psi1, psi2], radians.
    joint_lower: list[float] = dc.field(default_factory=lambda: [-math.pi, -math.pi])
    # Upper joint limits [psi1, psi2], radians (> lower).
    joint_upper: list[float] = dc.field(default_factory=lambda: [math.pi, math.pi])


@dc.dataclass
class Bar:
    """A straight bar held at its middle, across link 2 (gripper y axis).

    In the gripper frame its ends are (0, -length/2) and (0, +length/2), and
    these two ends are its default interest points.
    """

    # Bar length, metres (> 0).
    length: float = 1.5
    # Bar thickness, metres (> 0); the bar is a capsule of radius thickness/2.
    thickness: float = 0.05
    # Interest points [[x, y], ...] in the gripper frame, metres; None = the ends.
    interest_points: Optional[list[list[float]]] = None


@dc.dataclass
class LShape:
    """Two bars joined at a right angle.

    The first bar (``lengths[0]``) is held at its middle across link 2, from
    (0, -l_a/2) to (0, +l_a/2) in the gripper frame; the second
    (``lengths[1]``) leaves its +y end along the gripper x axis, to
    (l_b, +l_a/2). Default interest points: the three vertices.
    """

    # Lengths [first bar, second bar], metres (> 0).
    lengths: list[float] = dc.field(default_factory=lambda: [3.0, 2.0])
    # Bar thickness, metres (> 0).
    thickness: float = 0.05
    # Interest points [[x, y], ...] in the gripper frame, metres; None = vertices.
    interest_points: Optional[list[list[float]]] = None


@dc.dataclass
class Polyline:
    """A general object: an open polyline in the gripper frame."""

    # Vertices [[x, y], ...] in the gripper frame, metres (at least two).
    points: list[list[float]] = dc.field(default_factory=lambda: [[0.0, -0.5], [0.0, 0.5]])
    # Thickness, metres (> 0); every segment is a capsule of radius thickness/2.
    thickness: float = 0.05
    # Interest points [[x, y], ...] in the gripper frame; None = first and last vertex.
    interest_points: Optional[list[list[float]]] = None


@dc.dataclass
class SocialCostOptions:
    """Kirby's asymmetric Gaussian personal space and the multi-point sum."""

    # Variance along the facing direction, metres (the paper: 2).
    sigma_h: float = 2.0
    # sigma_s = side_ratio * sigma_h (the paper: 2/3).
    side_ratio: float = 2.0 / 3.0
    # sigma_r = rear_ratio * sigma_h (the paper: 1/2).
    rear_ratio: float = 0.5
    # AGF values <= threshold count as 0 (the paper: 0.2), in [0, 1).
    threshold: float = 0.2
    # One weight >= 0 per interest point, in the order base, link-1 tip,
    # link-2 tip, then the object's points. None = 1 for every point.
    weights: Optional[list[float]] = None
    # Path-length weight lambda >= 0 added to the social integral
    # (0 = the paper's pure social cost).
    length_weight: float = 0.0
    # Largest workspace displacement of any weighted interest point between two
    # samples of the trapezoid rule along a motion, metres (> 0). Threshold
    # crossings are located inside steps, so 0.1 m keeps Msc within ~0.5% of
    # a 2000-step reference on nearly every edge.
    resolution: float = 0.1


@dc.dataclass
class PlannerOptions:
    """Options of the RRT* family (the paper's Algorithm 2)."""

    # One of ALGORITHMS.
    algorithm: str = "social_rrt_star"
    # Number of samples drawn, K (>= 1).
    iterations: int = 2000
    # Steer distance delta in configuration space (> 0).
    planning_range: float = 1.5
    # Near-set radius r_near in configuration space (> 0).
    near_radius: float = 2.5
    # Probability in [0, 1) of sampling the goal instead of a random state.
    goal_bias: float = 0.05
    # Informed variants: "paper" (ellipse from the best path's XY length) or
    # "admissible" (from best cost / length_weight; needs length_weight > 0).
    informed_mode: str = "paper"
    # Per-coordinate weights (> 0, 4 values) of the configuration distance.
    distance_weights: list[float] = dc.field(default_factory=lambda: [1.0, 1.0, 1.0, 1.0])
    # Largest displacement of any robot or object point between two checked
    # configurations of a motion, metres (> 0).
    collision_resolution: float = 0.05
    # Near-set radius rule: "shrinking" (standard RRT*: min(r_near,
    # gamma (log n / n)^(1/4)) with n the tree's size, so the near set stops
    # growing with the tree: office, K = 32,000, 5 seeds, 1.35 s against
    # 15.4 s, time ~ K^1.2 against K^1.89) or "fixed" (r_near, the paper's
    # Algorithm 2; `experiment paper` pins it).
    near_radius_mode: str = "shrinking"
    # gamma of the shrinking radius, configuration-space units (> 0), or 0 for
    # OMPL's choice: 1.1 * 2 (1 + 1/d)^(1/d) (volume / unit-ball volume)^(1/d)
    # of the weighted configuration box, d = 4 (8.9 on office_bar, whose
    # radius then falls below r_near = 3 from about 490 nodes).
    near_radius_gamma: float = 0.0
    # Optimise the returned path (shortcuts and a local descent on the
    # waypoints, drake_social.planning.optimize): never raises the cost, keeps
    # every motion valid (office, K = 2000, 5 seeds: mean cost 3.4 against
    # the raw 6.0). false returns the raw RRT* path of the paper
    # (`experiment paper` pins it).
    optimize: bool = True


@dc.dataclass
class ExecutionOptions:
    """How a planned path is executed and simulated (the paper's Section IV-C).

    Defaults are the paper's values where it gives one (Kp = 1.5, four
    mecanum wheels); the rest are those of a small indoor mobile manipulator.
    """

    # "kinematic" or "dynamic" (see SIM_MODES).
    mode: str = "kinematic"
    # "synchronized" or "paper" (see EXECUTIONS).
    execution: str = "synchronized"
    # Proportional gain Kp of the base controller, 1/s (> 0; the paper: 1.5).
    kp: float = 1.5
    # Largest base speed (norm of [vx, vy]), m/s (> 0). The synchronized
    # reference also keeps to what the wheels give along each segment,
    # max_wheel_speed * wheel_radius * |d| / (|dx| + |dy|), whichever is lower.
    max_base_speed: float = 0.5
    # Largest base acceleration and jerk per axis of the synchronized
    # reference, m/s^2 and m/s^3 (> 0).
    max_base_acceleration: float = 1.0
    max_base_jerk: float = 5.0
    # Mecanum wheel radius r, metres (> 0).
    wheel_radius: float = 0.05
    # Largest wheel speed, rad/s (> 0); commands beyond it are scaled down
    # uniformly, keeping the direction.
    max_wheel_speed: float = 20.0
    # Arm joint limits [psi1, psi2] of the Ruckig trajectories: velocity
    # rad/s, acceleration rad/s^2, jerk rad/s^3 (> 0).
    arm_max_velocity: list[float] = dc.field(default_factory=lambda: [1.0, 1.0])
    arm_max_acceleration: list[float] = dc.field(default_factory=lambda: [2.0, 2.0])
    arm_max_jerk: list[float] = dc.field(default_factory=lambda: [10.0, 10.0])
    # The sequencer advances when the base is within base_tolerance (metres)
    # and both arm joints within joint_tolerance (radians) of the target (> 0).
    base_tolerance: float = 0.05
    joint_tolerance: float = 0.05
    # Period of the sequencer, controller and trajectory updates, seconds (> 0).
    control_period: float = 0.01
    # Time step of the discrete MultibodyPlant in "dynamic" mode, seconds (> 0).
    plant_time_step: float = 0.002
    # A run that has not reached the goal after this long stops and says so,
    # seconds (> 0, <= MAX_TIME_LIMIT = 600; at most MAX_CONTROL_STEPS control
    # periods and MAX_PLANT_STEPS plant steps).
    time_limit: float = 300.0
    # Frames per second of the Meshcat recording (> 0, <= MAX_REPLAY_FPS = 60).
    replay_fps: float = 30.0


@dc.dataclass
class Scenario:
    """Everything needed to plan and simulate one transport task."""

    # Free text shown in figures and reports.
    description: str = ""
    # The room and its obstacles.
    world: World = dc.field(default_factory=World)
    # Static people.
    people: list[Person] = dc.field(default_factory=list)
    # The mobile manipulator.
    robot: Robot = dc.field(default_factory=Robot)
    # The carried object, tagged in YAML as !Bar, !LShape or !Polyline.
    object: Union[Bar, LShape, Polyline] = dc.field(default_factory=Bar)
    # Start configuration [x, y, psi1, psi2] (metres, radians).
    start: list[float] = dc.field(default_factory=lambda: [1.0, 1.0, 0.0, 0.0])
    # Goal configuration [x, y, psi1, psi2] (metres, radians).
    goal: list[float] = dc.field(default_factory=lambda: [9.0, 9.0, 0.0, 0.0])
    # Social cost options.
    social: SocialCostOptions = dc.field(default_factory=SocialCostOptions)
    # Planner options.
    planner: PlannerOptions = dc.field(default_factory=PlannerOptions)
    # Execution and simulation options.
    execution: ExecutionOptions = dc.field(default_factory=ExecutionOptions)
    # Seed of every random choice (planner sampling, studies), an integer >= 0.
    random_seed: int = 0


def load_scenario(path: str | Path, overrides: str | Sequence[str] | None = None, *,
                  overrides_name: str = "overrides") -> Scenario:
    """Loads and validates a scenario file.

    The YAML is read first with PyYAML and checked against the schema field by
    field (:func:`check_yaml`: duplicate keys, unknown keys, types), so that
    every error names its source, line and dotted field (``world.bounds[2]``,
    ``robot.wheels``) before Drake's loader builds the dataclasses.

    Args:
        path: a YAML file following the :class:`Scenario` schema.
        overrides: optional YAML text, or several applied in turn (a later
            one merges into what the earlier ones left), on top of the file, e.g.
            ``"random_seed: 3\\nsocial: {weights: [1, 0, 0, 0, 0]}"``.
        overrides_name: how errors name an override, e.g. ``"--set"``: an
            error caused by one reads ``<path> (--set '<text>'): ...``.

    Returns:
        The validated scenario.

    Raises:
        ScenarioError: the file is missing, not a regular file, larger than
            :data:`~drake_social.io.textfile.MAX_YAML_FILE_BYTES` (4 MiB), malformed, has
            duplicate or unknown keys or invalid values; the message names
            the file (or the override at fault), the line and the field.
    """
    text = read_yaml_file(path, "scenario")  # refuses "" before Path("") could make it the working directory
    return load_scenario_text(text, str(Path(path)), overrides,
                              overrides_name=overrides_name)


def load_scenario_text(text: str, source: str, overrides: str | Sequence[str] | None = None, *,
                       overrides_name: str = "overrides") -> Scenario:
    """Loads and validates a scenario from its YAML text, as :func:`load_scenario` does a file.

    Args:
        text: the scenario's YAML.
        source: how errors name it (the file it came from).
        overrides, overrides_name: as :func:`load_scenario`.

    Raises:
        ScenarioError: as :func:`load_scenario`, naming ``source``.
    """
    from pydrake.common.yaml import yaml_load_typed  # lazy: keep pydrake out of the core

    sources = [(source, text)]
    for extra in [overrides] if isinstance(overrides, str) else list(overrides or []):
        sources.append((f"{source} ({overrides_name} {shorten(repr(extra))})", extra))
    stages = []
    scenario = None
    for where, data in sources:
        check_yaml(data, where)
        try:
            scenario = yaml_load_typed(schema=Scenario, data=data, **({} if scenario is None else
                                                                        {"defaults": scenario}))
        except Exception as e:  # what check_yaml lets through; Drake's message has no file name: add it
            raise ScenarioError(f"{where}: {e}") from e
        stages.append(scenario)
    # Blame the source after which the scenario stopped being valid: a bad
    # --set is named, not the file it was applied to.
    culprit = len(stages) - 1
    try:
        validate_scenario(stages[culprit], source=sources[culprit][0])
    except ScenarioError:
        while culprit > 0 and not _is_valid(stages[culprit - 1]):
            culprit -= 1
        validate_scenario(stages[-1], source=sources[culprit][0])
    return scenario


def _is_valid(scenario: Scenario) -> bool:
    try:
        validate_scenario(scenario)
    except ScenarioError:
        return False
    return True


# --------------------------------------------------------------------------
# Schema check of the YAML text, before Drake's loader: each error names the
# source, the line and the dotted field, and says what is allowed.


def _describe(tp) -> str:
    """What a value of schema type ``tp`` looks like, for error messages."""
    origin = typing.get_origin(tp)
    if origin is Union:
        alts = [a for a in typing.get_args(tp) if a is not type(None)]
        text = " or ".join(_describe(a) if not dc.is_dataclass(a) else f"!{a.__name__} {{...}}" for a in alts)
        return text + (" or null" if len(alts) < len(typing.get_args(tp)) else "")
    if origin is list:
        return "a list of " + _plural(typing.get_args(tp)[0])
    if origin is dict:
        return "a mapping of names to " + _plural(typing.get_args(tp)[1])
    if dc.is_dataclass(tp):
        return f"a mapping ({tp.__name__}: {', '.join(f.name for f in dc.fields(tp))})"
    return {float: "a number", int: "an integer", bool: "true or false", str: "a string"}.get(tp, str(tp))


def _plural(tp) -> str:
    if typing.get_origin(tp) is Union:
        alts = [a for a in typing.get_args(tp) if a is not type(None)]
        return " or ".join(_plural(a) for a in alts) + (" or nulls" if len(alts) < len(typing.get_args(tp)) else "")
    if typing.get_origin(tp) is list:
        return "lists of " + _plural(typing.get_args(tp)[0])
    if dc.is_dataclass(tp):
        return f"mappings ({tp.__name__}: {', '.join(f.name for f in dc.fields(tp))})"
    return {float: "numbers", int: "integers", bool: "booleans", str: "strings"}.get(tp, str(tp))


#: Deepest nesting of YAML nodes accepted in a scenario, sweep or override,
#: counted as the loader counts it (the document's mapping is level 1, a
#: scalar one more than its collection): the shipped scenarios and
#: studies/example_sweep.yaml need 6, a sweep variant that sets an obstacle's
#: centre 8. Deeper documents are refused before Python's recursion limit is
#: reached.
MAX_YAML_DEPTH = 32
#: Most nodes (mappings, lists, keys and values) of one YAML document, an
#: alias counted as the nodes it stands for: a "billion laughs" of nested
#: aliases is refused while it is read. A 2,000-obstacle room has about 25,000;
#: PyYAML composes about 15,000 nodes a second.
MAX_YAML_NODES = 100_000


class _YamlLimit(Exception):
    def __init__(self, mark, message: str):
        super().__init__(message)
        self.mark = mark


@functools.lru_cache(maxsize=1)
def _limited_loader(yaml):
    """PyYAML's SafeLoader with :data:`MAX_YAML_DEPTH` and :data:`MAX_YAML_NODES` enforced while composing."""

    class Loader(yaml.SafeLoader):
        def __init__(self, stream):
            super().__init__(stream)
            self._depth = 0  # collections open around the node being composed
            self._total = 0  # nodes so far, aliases expanded
            self._size: dict[int, int] = {}  # id(node) -> its expanded node count
            self._height: dict[int, int] = {}  # id(node) -> its expanded nesting depth

        def _count(self, nodes: int, height: int, mark) -> None:
            self._total += nodes
            if self._total > MAX_YAML_NODES:
                raise _YamlLimit(mark, f"more than {MAX_YAML_NODES:,} YAML nodes (aliases counted as the nodes "
                                       f"they repeat); a document may have at most {MAX_YAML_NODES:,}")
            if self._depth + height > MAX_YAML_DEPTH:
                raise _YamlLimit(mark, f"nested more than {MAX_YAML_DEPTH} levels deep (aliases included); "
                                       f"at most {MAX_YAML_DEPTH} are allowed")

        def compose_node(self, parent, index):
            mark = self.peek_event().start_mark
            if self.check_event(yaml.AliasEvent):
                node = super().compose_node(parent, index)
                if id(node) not in self._size:  # its anchor is still open: the alias repeats itself
                    raise _YamlLimit(mark, "an alias inside the node it refers to (a recursive YAML structure)")
                self._count(self._size[id(node)], self._height[id(node)], mark)
                # A node of its own at the alias's place, so that errors name the alias's line (the
                # content, shared, keeps its own lines).
                style = node.style if isinstance(node, yaml.ScalarNode) else node.flow_style
                here = type(node)(node.tag, node.value, mark, mark, style)
                self._size[id(here)], self._height[id(here)] = self._size[id(node)], self._height[id(node)]
                return here
            self._depth += 1
            self._count(0, 0, mark)
            before = self._total
            node = super().compose_node(parent, index)
            self._depth -= 1
            children = (node.value if isinstance(node, yaml.SequenceNode) else
                        [n for pair in node.value for n in pair] if isinstance(node, yaml.MappingNode) else [])
            self._height[id(node)] = 1 + max((self._height[id(c)] for c in children), default=0)
            self._count(1, 0, mark)
            self._size[id(node)] = self._total - before
            return node

    return Loader


def compose_yaml(text: str, source: str):
    """Parses YAML ``text`` into PyYAML's node tree, within the limits.

    The one YAML parser of scenario files, sweep files and overrides
    (``--set``, sweep variants): the document may nest at most
    :data:`MAX_YAML_DEPTH` levels and have at most :data:`MAX_YAML_NODES`
    nodes, aliases counted as the nodes they repeat.

    Args:
        text: the YAML document.
        source: how errors name it (a file, or a file and an override).

    Returns:
        The root node, or None for an empty document.

    Raises:
        ScenarioError: ``<source>: not valid YAML: ...`` or ``<source>: line <n>: <the limit exceeded>``.
    """
    import yaml  # PyYAML, as Drake's Python loader uses; lazy like pydrake

    loader = None
    try:
        loader = _limited_loader(yaml)(text)  # its reader refuses control characters and NULs at once
        return loader.get_single_node()
    except yaml.YAMLError as e:
        raise ScenarioError(f"{source}: not valid YAML: {e}") from None
    except _YamlLimit as e:
        raise ScenarioError(f"{source}: line {e.mark.line + 1}: {e}") from None
    finally:
        if loader is not None:
            loader.dispose()


def check_yaml(text: str, source: str, schema: type = Scenario) -> None:
    """Checks YAML ``text`` against the dataclass ``schema`` before it is loaded.

    Parses it with :func:`compose_yaml` (its nesting and size limits), then
    refuses duplicate keys (PyYAML and Drake keep the last one silently),
    keys the schema does not have and values of the wrong type (a word for a
    number, null or a mapping for a list, an unknown ``!Tag``). Values are
    not range-checked here (see :func:`validate_scenario`).

    Raises:
        ScenarioError: ``<source>: line <n>: <dotted field>: <what is allowed>, got <value>``.
    """
    import yaml

    root = compose_yaml(text, source)
    if root is None:
        raise ScenarioError(f"{source}: empty; a {schema.__name__.lower()} is a mapping "
                            f"({', '.join(f.name for f in dc.fields(schema))})")
    check_node(schema, root, source)


def check_node(schema: type, node, source: str, field: str = "") -> None:
    """Checks one composed YAML node (of :func:`compose_yaml`) against ``schema``, as :func:`check_yaml`.

    Args:
        schema: a dataclass, or ``list[...]``, ``dict[str, ...]``, ``Optional[...]`` of the schema types.
        node: the node.
        source: how errors name the document.
        field: the dotted field of ``node`` in its document ("" at the top).
    """
    import yaml

    _check_node(schema, node, field, source, yaml)


#: PyYAML's tags of untagged mappings, lists and strings, and the prefix of its standard (``!!``) tags.
_MAP_TAG = "tag:yaml.org,2002:map"
_SEQ_TAG = "tag:yaml.org,2002:seq"
_STR_TAG = "tag:yaml.org,2002:str"
_YAML_TAG = "tag:yaml.org,2002:"


#: Longest key an error message repeats whole in a dotted field: a name of a
#: sweep's variants may have 100 characters (``experiments.study.NAME_PATTERN``).
_SHOWN_KEY_CHARACTERS = 100


def _unprintable(text: str) -> str | None:
    """The first character of ``text`` that a YAML file may not hold (a control
    character other than tab and line breaks, DEL, a lone surrogate, U+FFFE/U+FFFF),
    as ``U+XXXX``, or None. A quoted scalar's escapes (``"\\0"``, ``"\\ud800"``)
    can make them, which the YAML reader refuses in the file's text."""
    import yaml

    match = yaml.reader.Reader.NON_PRINTABLE.search(text)
    return None if match is None else f"U+{ord(match.group()):04X}"


def _key_shown(key: str) -> str:
    """A mapping key as a dotted field repeats it: its repr if it holds a character
    that does not print on one line, else as written, whole up to
    :data:`_SHOWN_KEY_CHARACTERS` characters (longer: shortened)."""
    if not key.isprintable():
        return shorten(repr(key))
    return key if len(key) <= _SHOWN_KEY_CHARACTERS else shorten(key)


def _check_node(tp, node, field: str, source: str, yaml, tag_checked: bool = False) -> None:
    """:func:`check_node` of one node; ``tag_checked``: its ``!Tag`` chose ``tp`` (an object type)."""

    def fail(message: str, at=node) -> None:
        name = f"{field}: " if field else ""
        raise ScenarioError(f"{source}: line {at.start_mark.line + 1}: {name}{message}")

    def shown(n) -> str:
        if isinstance(n, yaml.MappingNode):
            return "a mapping"
        if isinstance(n, yaml.SequenceNode):
            return "a list"
        if n.tag == "tag:yaml.org,2002:null":
            return "null"
        tag = "" if n.tag in (_STR_TAG, yaml.resolver.Resolver().resolve(yaml.ScalarNode, n.value, (True, False)))\
            else n.tag.replace(_YAML_TAG, "!!") + " "
        return tag + shorten(repr(n.value))

    is_null = isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:null"
    origin = typing.get_origin(tp)
    if origin is Union:
        args = typing.get_args(tp)
        if type(None) in args and is_null:
            return
        alts = [a for a in args if a is not type(None)]
        if len(alts) == 1:
            return _check_node(alts[0], node, field, source, yaml)
        tags = {f"!{a.__name__}": a for a in alts}
        if node.tag in tags:
            return _check_node(tags[node.tag], node, field, source, yaml, tag_checked=True)
        if node.tag.startswith("!"):
            fail(f"unknown type {node.tag}; allowed: {', '.join(tags)}")
        return _check_node(alts[0], node, field, source, yaml)  # untagged: the first alternative
    # Elsewhere a mapping or list carries no tag (Drake's loader would read a
    # !Tag as an unknown field "_tag", PyYAML's !!set or !!omap as another type).
    default_tag = {yaml.MappingNode: _MAP_TAG, yaml.SequenceNode: _SEQ_TAG}.get(type(node))
    if default_tag is not None and node.tag != default_tag and not tag_checked:
        fail(f"must be {_describe(tp)} without a tag, got {node.tag.replace(_YAML_TAG, '!!')} {shown(node)}")
    if origin is list:
        if not isinstance(node, yaml.SequenceNode):
            fail(f"must be {_describe(tp)}, got {shown(node)}")
        (item,) = typing.get_args(tp)
        for i, child in enumerate(node.value):
            _check_node(item, child, f"{field}[{i}]", source, yaml)
        return
    if origin is dict:
        if not isinstance(node, yaml.MappingNode):
            fail(f"must be {_describe(tp)}, got {shown(node)}")
        key_type, value_type = typing.get_args(tp)
        seen: dict[str, int] = {}
        for key_node, value_node in node.value:
            line = key_node.start_mark.line + 1
            if (not isinstance(key_node, yaml.ScalarNode) or key_node.tag != "tag:yaml.org,2002:str"
                    or key_node.value == ""):
                raise ScenarioError(f"{source}: line {line}: {field}: names must be non-empty strings, got "
                                    f"{shown(key_node)}")
            sub = f"{field}.{_key_shown(key_node.value)}" if field else _key_shown(key_node.value)
            bad = _unprintable(key_node.value)
            if bad is not None:
                raise ScenarioError(f"{source}: line {line}: {sub}: names must be printable text, got {bad} in "
                                    f"{shown(key_node)}")
            if key_node.value in seen:
                raise ScenarioError(f"{source}: line {line}: {sub}: duplicate key (first at line "
                                    f"{seen[key_node.value]})")
            seen[key_node.value] = line
            _check_node(value_type, value_node, sub, source, yaml)
        return
    if dc.is_dataclass(tp):
        if not isinstance(node, yaml.MappingNode):
            fail(f"must be {_describe(tp)}, got {shown(node)}")
        hints = typing.get_type_hints(tp)  # resolves string annotations (from __future__ import annotations)
        types = {f.name: hints[f.name] for f in dc.fields(tp)}
        seen: dict[str, int] = {}
        for key_node, value_node in node.value:
            line = key_node.start_mark.line + 1
            if not isinstance(key_node, yaml.ScalarNode):
                where = f"{field}: " if field else ""
                raise ScenarioError(f"{source}: line {line}: {where}a key must be a field name ({', '.join(types)}), "
                                    f"got {shown(key_node)}")
            key = key_node.value
            if key_node.tag != _STR_TAG and (key in types or key == ""):  # `!!int random_seed:`, `? !!null`
                where = f"{field}: " if field else ""
                raise ScenarioError(f"{source}: line {line}: {where}a key must be a field name ({', '.join(types)}) "
                                    f"as plain text, without a tag, got {shown(key_node)}")
            sub = f"{field}.{_key_shown(key)}" if field else _key_shown(key)
            if key in seen:  # YAML loaders keep the last silently
                raise ScenarioError(f"{source}: line {line}: {sub}: duplicate key (first at line {seen[key]})")
            seen[key] = line
            if key_node.tag != _STR_TAG or key not in types:
                where = f"in {field}" if field else "at the top level"
                raise ScenarioError(f"{source}: line {line}: {sub}: unknown field {where}; allowed: "
                                    f"{', '.join(types)}")
            _check_node(types[key], value_node, sub, source, yaml)
        return
    if not isinstance(node, yaml.ScalarNode) or is_null:
        fail(f"must be {_describe(tp)}, got {shown(node)}")
    if not node.tag.startswith(_YAML_TAG):  # e.g. `description: !Foo x`
        fail(f"must be {_describe(tp)} without a tag, got {shown(node)}")
    try:  # a standard tag whose text does not fit it (`!!int abc`, `!!bool maybe`), or Python's (`!!python/name:`)
        value = yaml.SafeLoader("").construct_object(node)
    except Exception:
        fail(f"must be {_describe(tp)}, got {shown(node)}")
    if isinstance(value, str) and _unprintable(value) is not None:
        fail(f"must be printable text (the characters a YAML file may hold), got {_unprintable(value)} in "
             f"{shown(node)}")
    if tp is bool:
        ok = isinstance(value, bool)
    elif tp is str:
        ok = isinstance(value, str)
    elif isinstance(value, bool):
        ok = False
    elif tp is int:
        ok = isinstance(value, int) or (isinstance(value, float) and value.is_integer()) or _parses(int, value)
    elif tp is float:
        ok = isinstance(value, (int, float)) or _parses(float, value)
    else:
        ok = True
    if not ok:
        fail(f"must be {_describe(tp)}, got {shown(node)}")


def _parses(kind, value) -> bool:
    if not isinstance(value, str):
        return False
    try:
        kind(value)
    except ValueError:
        return False
    return True


# --------------------------------------------------------------------------
# Validation. Each check names the field by its dotted path.


class _Checker:
    def __init__(self, source: str):
        self.source = source

    def fail(self, field: str, message: str):
        raise ScenarioError(f"{self.source}: {field}: {message}")

    def finite(self, field: str, value) -> None:
        arr = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(arr)):
            self.fail(field, f"must be finite numbers, got {_shown(value)}")

    def positive(self, field: str, value) -> None:
        self.finite(field, value)
        if not np.all(np.asarray(value, dtype=float) > 0):
            self.fail(field, f"must be > 0, got {_shown(value)}")

    def nonnegative(self, field: str, value) -> None:
        self.finite(field, value)
        if not np.all(np.asarray(value, dtype=float) >= 0):
            self.fail(field, f"must be >= 0, got {_shown(value)}")

    def length(self, field: str, value, n: int) -> None:
        if len(value) != n:
            self.fail(field, f"must have {n} values, got {len(value)}: {_shown(value)}")

    def points(self, field: str, value, min_count: int) -> None:
        if len(value) < min_count:
            self.fail(field, f"needs at least {min_count} points [x, y], got {len(value)}")
        for i, p in enumerate(value):
            self.length(f"{field}[{i}]", p, 2)
            self.finite(f"{field}[{i}]", p)


def _shown(value) -> str:
    """A value of the scenario as an error message repeats it (:func:`~drake_social.io.textfile.shorten`)."""
    return shorten(repr(value) if isinstance(value, str) else str(value))


def period_count(duration: float, period: float) -> int:
    """How many periods of ``period`` seconds a run of ``duration`` seconds
    takes (the ratio rounded up; a ratio within 1e-9 of an integer counts as
    that integer, so 270 s / 0.0045 s is 60,000 periods although it computes
    to 60000.00000000001)."""
    ratio = duration / period
    nearest = round(ratio)
    return int(nearest) if abs(ratio - nearest) <= 1e-9 * max(1.0, ratio) else math.ceil(ratio)


def interest_point_count(obj: Union[Bar, LShape, Polyline]) -> int:
    """The number of object interest points (explicit or default)."""
    if obj.interest_points is not None:
        return len(obj.interest_points)
    return 3 if isinstance(obj, LShape) else 2


def _longest_motion_bound(scenario: Scenario) -> float:
    """The largest displacement bound of any motion in the scenario's
    configuration space (metres): :func:`~drake_social.kinematics.displacement_bound`
    with every interest point's lever, the room's extent and both joints'
    full turns (the social cost's own bound never exceeds it)."""
    from drake_social.kinematics import ArmGeometry, displacement_bound  # kinematics imports this module

    x_min, y_min, x_max, y_max = scenario.world.bounds
    lower, upper = scenario.robot.joint_lower, scenario.robot.joint_upper
    extent = np.array([x_max - x_min, y_max - y_min, upper[0] - lower[0], upper[1] - lower[1]])
    return float(displacement_bound(extent, ArmGeometry.from_scenario(scenario).lever()))


def plant_time_step_problem(execution: ExecutionOptions, mode: str) -> tuple[str, str] | None:
    """What is wrong with ``execution.plant_time_step`` for a run in ``mode``
    (a dynamic run's servo is stable only up to
    :data:`MAX_DYNAMIC_PLANT_TIME_STEP`), or None.

    Returns:
        (the field at fault, what is allowed and what was given), or None.
    """
    step = execution.plant_time_step
    if mode == "dynamic" and step > MAX_DYNAMIC_PLANT_TIME_STEP:
        return "execution.plant_time_step", (
            f"must be <= {MAX_DYNAMIC_PLANT_TIME_STEP:.6g} s in dynamic mode (the servo's damping gain "
            f"{2 * SERVO_BANDWIDTH:g} /s times the step must be <= 1 for the plant to stay stable), got {step}")
    return None


def time_limit_problem(time_limit: float, execution: ExecutionOptions, argument: str | None = None
                       ) -> tuple[str, str] | None:
    """What is wrong with a run of ``time_limit`` seconds under ``execution``
    (the rules of a run's length), or None.

    The rules: ``0 < time_limit <= MAX_TIME_LIMIT``, at least
    :data:`MIN_CONTROL_PERIODS` and at most :data:`MAX_CONTROL_STEPS` control
    periods, at most :data:`MAX_PLANT_STEPS` plant steps. Both
    :func:`validate_scenario` (``execution.time_limit``) and
    :func:`drake_social.sim.run.simulate` (its ``time_limit`` argument) use them.

    Args:
        time_limit: seconds.
        execution: the periods and steps of the run.
        argument: the name of a function's argument giving ``time_limit``;
            None = the scenario's own ``execution.time_limit``.

    Returns:
        (the field at fault, what is allowed and what was given), or None.
    """
    e = execution
    limit = float(time_limit)
    if not 0 < limit <= MAX_TIME_LIMIT:
        return argument or "execution.time_limit", f"must be in (0, {MAX_TIME_LIMIT:g}] seconds, got {time_limit}"
    # (periods or steps, their length, its field, the fewest, the most, why)
    rules = ((e.control_period, "execution.control_period", MIN_CONTROL_PERIODS, None,
              f"a run lasts at least {MIN_CONTROL_PERIODS} control periods: the sequencer decides once per period"),
             (e.control_period, "execution.control_period", None, MAX_CONTROL_STEPS,
              f"a run may take at most {MAX_CONTROL_STEPS:,} control periods"),
             (e.plant_time_step, "execution.plant_time_step", None, MAX_PLANT_STEPS,
              f"a run may take at most {MAX_PLANT_STEPS:,} plant steps"))
    for length, field, fewest, most, why in rules:
        if fewest is not None and limit < fewest * length * (1 - 1e-9):  # whole periods, up to rounding
            if argument:
                return argument, (f"must be >= {fewest} * {field} {length} = {fewest * length:.6g} s ({why}), "
                                  f"got {time_limit}")
            return field, f"must be <= execution.time_limit / {fewest} = {limit / fewest:.6g} s ({why}), got {length}"
        if most is not None and period_count(limit, length) > most:
            if argument:
                return argument, (f"must be <= {most:,} * {field} {length} = {most * length:.6g} s ({why}), "
                                  f"got {time_limit}")
            return field, f"must be >= execution.time_limit / {most:,} = {limit / most:.3g} s ({why}), got {length}"
    return None


def validate_planner_choice(scenario: Scenario, algorithm: str, iterations: int | None = None,
                            source: str = "<scenario>") -> None:
    """Checks ``scenario`` as a run that plans with ``algorithm`` (and
    ``iterations``) in place of its ``planner.algorithm`` (and
    ``planner.iterations``) does: a study's or a benchmark's runs choose the
    planner themselves, and a rule such as ``planner.informed_mode:
    admissible`` (which needs ``social.length_weight > 0`` for the informed
    planners) depends on it.

    Args:
        scenario: a scenario (valid with its own planner).
        algorithm: the planner of the run (one of :data:`ALGORITHMS`).
        iterations: K of the run; None = the scenario's.
        source: how errors name the scenario and the choice.

    Raises:
        ScenarioError: as :func:`validate_scenario`, naming ``source``.
    """
    planner = dc.replace(scenario.planner, algorithm=algorithm,
                         iterations=scenario.planner.iterations if iterations is None else int(iterations))
    validate_scenario(dc.replace(scenario, planner=planner), source=source)


def validate_scenario(scenario: Scenario, source: str = "<scenario>") -> None:
    """Checks values that the schema's types cannot express.

    Raises:
        ScenarioError: naming ``source``, the dotted field and what is allowed.
    """
    c = _Checker(source)
    w = scenario.world
    c.length("world.bounds", w.bounds, 4)
    c.finite("world.bounds", w.bounds)
    x_min, y_min, x_max, y_max = w.bounds
    if not (x_max > x_min and y_max > y_min):
        c.fail("world.bounds", f"must be [x_min, y_min, x_max, y_max] with max > min, got {w.bounds}")
    c.positive("world.wall_thickness", w.wall_thickness)
    for i, box in enumerate(w.obstacles):
        c.length(f"world.obstacles[{i}].center", box.center, 2)
        c.finite(f"world.obstacles[{i}].center", box.center)
        c.length(f"world.obstacles[{i}].size", box.size, 2)
        c.positive(f"world.obstacles[{i}].size", box.size)
        c.finite(f"world.obstacles[{i}].yaw", box.yaw)

    def inside(field: str, x: float, y: float) -> None:
        if not (x_min <= x <= x_max and y_min <= y <= y_max):
            c.fail(field, f"position ({x}, {y}) is outside world.bounds {w.bounds}")

    for i, p in enumerate(scenario.people):
        c.finite(f"people[{i}]", [p.x, p.y, p.theta])
        c.positive(f"people[{i}].radius", p.radius)
        inside(f"people[{i}]", p.x, p.y)

    r = scenario.robot
    c.positive("robot.base_radius", r.base_radius)
    c.length("robot.link_lengths", r.link_lengths, 2)
    c.positive("robot.link_lengths", r.link_lengths)
    c.positive("robot.link_width", r.link_width)
    c.length("robot.joint_lower", r.joint_lower, 2)
    c.finite("robot.joint_lower", r.joint_lower)
    c.length("robot.joint_upper", r.joint_upper, 2)
    c.finite("robot.joint_upper", r.joint_upper)
    if not all(u > lo for lo, u in zip(r.joint_lower, r.joint_upper)):
        c.fail("robot.joint_upper", f"must exceed robot.joint_lower {r.joint_lower}, got {r.joint_upper}")
    # A part as wide as the room's smaller side touches a wall in every
    # configuration (and Drake's distance queries stall on parts ~10^6 m wide).
    side = min(x_max - x_min, y_max - y_min)
    for field, width, what in (("robot.base_radius", 2 * r.base_radius, "the base's diameter"),
                               ("robot.link_width", r.link_width, "the links' width")):
        if not width < side:
            limit = side / 2 if field == "robot.base_radius" else side
            c.fail(field, f"must be < {limit:.6g} m in this room ({what} must be less than its smaller side, "
                          f"{side:.6g} m, or the robot touches a wall everywhere), got {getattr(r, field[6:])}")

    o = scenario.object
    if isinstance(o, Bar):
        c.positive("object.length", o.length)
    elif isinstance(o, LShape):
        c.length("object.lengths", o.lengths, 2)
        c.positive("object.lengths", o.lengths)
    else:
        c.points("object.points", o.points, 2)
        if len(o.points) > MAX_OBJECT_POINTS:
            c.fail("object.points", f"at most {MAX_OBJECT_POINTS} vertices (each is a collision shape of the model, "
                                    f"checked at every step of a motion), got {len(o.points)}; a polyline through "
                                    f"fewer of its vertices approximates a smooth curve")
    c.positive("object.thickness", o.thickness)
    if not o.thickness < side:
        c.fail("object.thickness", f"must be < {side:.6g} m in this room (the object's thickness must be less than "
                                   f"its smaller side, or the object touches a wall everywhere), got {o.thickness}")
    if o.interest_points is not None:
        c.points("object.interest_points", o.interest_points, 1)

    for name in ("start", "goal"):
        q = getattr(scenario, name)
        c.length(name, q, 4)
        c.finite(name, q)
        inside(name, q[0], q[1])
        for j in range(2):
            if not (r.joint_lower[j] <= q[2 + j] <= r.joint_upper[j]):
                c.fail(
                    f"{name}[{2 + j}]",
                    f"psi{j + 1} = {q[2 + j]} is outside the joint range "
                    f"[{r.joint_lower[j]}, {r.joint_upper[j]}]",
                )
    if np.array_equal(np.asarray(scenario.start, float), np.asarray(scenario.goal, float)):
        c.fail("goal", f"must differ from start (both are {list(scenario.goal)}): a transport from a "
                       "configuration to itself has nothing to plan or execute")

    s = scenario.social
    c.positive("social.sigma_h", s.sigma_h)
    c.positive("social.side_ratio", s.side_ratio)
    c.positive("social.rear_ratio", s.rear_ratio)
    c.finite("social.threshold", s.threshold)
    if not 0.0 <= s.threshold < 1.0:
        c.fail("social.threshold", f"must be in [0, 1), got {s.threshold}")
    n_points = 3 + interest_point_count(o)
    if s.weights is not None:
        c.length("social.weights", s.weights, n_points)
        c.nonnegative("social.weights", s.weights)
    c.nonnegative("social.length_weight", s.length_weight)
    c.positive("social.resolution", s.resolution)
    # The longest motion in the room must be sampleable in at most
    # MAX_MOTION_STEPS steps (the object and robot are checked above).
    longest = _longest_motion_bound(scenario)
    if longest > MAX_MOTION_STEPS * s.resolution:
        c.fail("social.resolution", f"must be >= {longest / MAX_MOTION_STEPS:.3g} m for this world and robot "
                                    f"(a motion may move a point {longest:.4g} m, sampled in at most "
                                    f"{MAX_MOTION_STEPS:,} steps), got {s.resolution}")

    p = scenario.planner
    if p.algorithm not in ALGORITHMS:
        c.fail("planner.algorithm", f"unknown algorithm {_shown(p.algorithm)}; allowed: {', '.join(ALGORITHMS)}")
    if not 1 <= p.iterations <= MAX_ITERATIONS:
        c.fail("planner.iterations", f"must be in [1, {MAX_ITERATIONS}], got {p.iterations}")
    if p.near_radius_mode not in NEAR_RADIUS_MODES:
        c.fail("planner.near_radius_mode",
               f"unknown mode {_shown(p.near_radius_mode)}; allowed: {', '.join(NEAR_RADIUS_MODES)}")
    c.finite("planner.near_radius_gamma", p.near_radius_gamma)
    if p.near_radius_gamma < 0:
        c.fail("planner.near_radius_gamma", f"must be >= 0 (0: computed from the space), got {p.near_radius_gamma}")
    if not isinstance(p.optimize, bool):
        c.fail("planner.optimize", f"must be true or false, got {_shown(p.optimize)}")
    c.positive("planner.planning_range", p.planning_range)
    c.positive("planner.near_radius", p.near_radius)
    c.finite("planner.goal_bias", p.goal_bias)
    if not 0.0 <= p.goal_bias < 1.0:
        c.fail("planner.goal_bias", f"must be in [0, 1), got {p.goal_bias}")
    if p.informed_mode not in INFORMED_MODES:
        c.fail("planner.informed_mode", f"unknown mode {_shown(p.informed_mode)}; allowed: {', '.join(INFORMED_MODES)}")
    if p.informed_mode == "admissible" and p.algorithm.startswith("informed") and s.length_weight <= 0:
        c.fail("planner.informed_mode", "'admissible' needs social.length_weight > 0")
    c.length("planner.distance_weights", p.distance_weights, 4)
    c.positive("planner.distance_weights", p.distance_weights)
    c.positive("planner.collision_resolution", p.collision_resolution)
    e = scenario.execution
    if e.mode not in SIM_MODES:
        c.fail("execution.mode", f"unknown mode {_shown(e.mode)}; allowed: {', '.join(SIM_MODES)}")
    if e.execution not in EXECUTIONS:
        c.fail("execution.execution", f"unknown execution {_shown(e.execution)}; allowed: {', '.join(EXECUTIONS)}")
    for name in ("kp", "max_base_speed", "max_base_acceleration", "max_base_jerk", "wheel_radius",
                 "max_wheel_speed", "base_tolerance", "joint_tolerance", "control_period",
                 "plant_time_step", "time_limit", "replay_fps"):
        c.positive(f"execution.{name}", getattr(e, name))
    for name in ("arm_max_velocity", "arm_max_acceleration", "arm_max_jerk"):
        c.length(f"execution.{name}", getattr(e, name), 2)
        c.positive(f"execution.{name}", getattr(e, name))
    if e.plant_time_step > e.control_period:
        c.fail("execution.plant_time_step",
               f"must be <= execution.control_period {e.control_period}, got {e.plant_time_step}")
    problem = time_limit_problem(e.time_limit, e)
    if problem:
        c.fail(*problem)
    problem = plant_time_step_problem(e, e.mode)
    if problem:
        c.fail(*problem)
    if e.kp * e.control_period >= 2.0:
        c.fail("execution.kp",
               f"execution.kp * execution.control_period must be < 2 (the base's sampled P-controller "
               f"multiplies its error by 1 - kp * control_period each period and converges only then), got "
               f"{e.kp} * {e.control_period} = {e.kp * e.control_period:.6g}")
    if e.replay_fps > MAX_REPLAY_FPS:
        c.fail("execution.replay_fps", f"must be <= {MAX_REPLAY_FPS:g} frames per second, got {e.replay_fps}")
    if scenario.random_seed < 0:
        c.fail("random_seed", f"must be >= 0, got {scenario.random_seed}")
