"""The scenario schema: a typed tree of dataclasses, the one description of the YAML format.

In the style of Drake's ``examples/hardware_sim``: every field has a comment
with its unit and the values it may take, defaults are the paper's values, and
files are loaded into these classes by :mod:`drake_social.scenario.load`
(with :func:`pydrake.common.yaml.yaml_load_typed`, which rejects unknown keys)
and checked by :mod:`drake_social.scenario.validate`.

Angles are radians, lengths metres. Configurations are ``q = [x, y, psi1,
psi2]``: base position, the angle of link 1 from the world x axis (the base
does not rotate) and the angle of link 2 relative to link 1.

Pure Python and numpy: the pure-numpy core uses these classes without Drake.
The names of the planners and checkers and the numeric bounds live in
:mod:`drake_social.limits`; the values of the schema's own choice fields
(modes, executions) live here.
"""

import dataclasses as dc
import math
from typing import Optional, Union

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.limits import ALGORITHMS, CHECKERS, NEAR_RADIUS_MODES
from drake_social.maps import MAP_UNKNOWN_CHOICES

__all__ = [
    "ALGORITHMS",
    "CHECKERS",
    "EXECUTIONS",
    "INFORMED_MODES",
    "PREDICTIONS",
    "NEAR_RADIUS_MODES",
    "SIM_MODES",
    "Bar",
    "Box",
    "Crowd",
    "CrowdPerson",
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
    "interest_point_count",
]

#: Modes of the informed sampler (see ``drake_social.planning.sampling``).
INFORMED_MODES = ("paper", "admissible")
#: How the replanner predicts people (``planner.prediction``).
PREDICTIONS = ("constant_velocity", "perfect", "interactive")

#: Simulation modes (see ``drake_social.sim``): the base integrates its
#: commanded velocity and the arm follows its reference exactly, or the
#: MultibodyPlant is simulated with actuated joints.
SIM_MODES = ("kinematic", "dynamic")

#: How a path is executed (see ``drake_social.sim``): one phase-synchronized
#: 4-DoF reference per segment (stays on the straight segment the planner
#: checked), or the paper's independent base P-controller and arm trajectory.
EXECUTIONS = ("synchronized", "paper")

#: What a map's unknown cells are (``world.unknown``).
MAP_UNKNOWN = MAP_UNKNOWN_CHOICES


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
    # With a map and no bounds given: the map's extent.
    bounds: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 10.0, 10.0])
    # Static obstacles (desks, walls, shelves), added to the map's.
    obstacles: list[Box] = dc.field(default_factory=list)
    # Thickness of the four boundary walls, metres, built outside the bounds.
    wall_thickness: float = 0.1
    # An occupancy-grid map in the ROS map_server format: its YAML file
    # (naming the PGM, PNG or BMP image), relative to the scenario file.
    # Occupied cells become obstacle boxes. None = no map.
    map: Optional[str] = None
    # What the map's unknown cells are: "obstacle" or "free".
    unknown: str = "obstacle"


@dc.dataclass
class Person:
    """A person: a body disc and a facing direction, standing or walking a script."""

    # Position of the body centre in the world frame, metres. With a
    # trajectory, leave both at 0 or give the trajectory's first point.
    x: float = 0.0
    y: float = 0.0
    # Facing direction, radians, counter-clockwise from world +x; with a
    # trajectory, the facing while standing before the first motion.
    theta: float = 0.0
    # Body radius, metres (> 0); the body is an obstacle too.
    radius: float = 0.25
    # Optional label used in figures and error messages.
    name: str = ""
    # Timed waypoints [[t, x, y], ...] (seconds >= 0, strictly increasing;
    # metres), walked in straight lines at constant speed between them; the
    # person stands at the first point before its time and at the last after
    # it. While walking they face the direction of motion, turning toward it
    # at up to pi rad/s (drake_social.scenario.heading), and keep the last
    # walking direction while standing. None = the person stands at (x, y)
    # throughout.
    trajectory: Optional[list[list[float]]] = None
    # Repeat the trajectory every t_last - t_first seconds; its last point must
    # be its first (a closed route).
    loop: bool = False


@dc.dataclass
class CrowdPerson:
    """A pedestrian of the simulated crowd: a start, goals and a body."""

    # Start position of the body centre, metres.
    x: float = 0.0
    y: float = 0.0
    # Goals [[x, y], ...] visited in order, metres (at least one).
    goals: list[list[float]] = dc.field(default_factory=list)
    # After the last goal, head for the first again (forever).
    cycle: bool = False
    # Body radius, metres (> 0).
    radius: float = 0.25
    # Preferred walking speed, m/s (in (0.1, 3]); None = drawn from the scenario's
    # seed, normal with mean crowd.speed_mean and deviation crowd.speed_std
    # (a draw <= 0.1 m/s is drawn again).
    desired_speed: Optional[float] = None
    # Optional label used in figures and error messages.
    name: str = ""


@dc.dataclass
class Crowd:
    """People driven by the social force model (Helbing and Molnar 1995, with
    the interaction term of Moussaid et al. 2009), walking to their goals and
    reacting to each other, the walls and obstacles, and the robot."""

    # The pedestrians.
    people: list[CrowdPerson] = dc.field(default_factory=list)
    # Time step of the model's explicit integration, seconds (in (0, 0.1],
    # and < relaxation_time).
    time_step: float = 0.05
    # Mean and standard deviation of the drawn preferred speeds, m/s (in (0.1, 3], >= 0).
    speed_mean: float = 1.34
    speed_std: float = 0.26
    # Largest speed, as a multiple of each person's preferred speed (>= 1).
    max_speed_factor: float = 1.3
    # Relaxation time tau of the goal force, seconds (> 0).
    relaxation_time: float = 0.5
    # A goal counts as reached within this distance of the body centre, metres (> 0).
    goal_radius: float = 0.3
    # Moussaid et al. 2009 interaction: lambda (weight of the relative
    # velocity), gamma, n and n' (dimensionless, > 0), and its strength A, m/s^2 (>= 0).
    interaction_lambda: float = 2.0
    interaction_gamma: float = 0.35
    interaction_n: float = 2.0
    interaction_n_prime: float = 3.0
    interaction_strength: float = 4.5
    # Helbing-Molnar obstacle force A exp(-d / B) of walls, obstacles and the
    # robot (base, arm and object) at surface distance d: A m/s^2 (>= 0), B metres (> 0).
    obstacle_strength: float = 10.0
    obstacle_range: float = 0.2


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

    def polyline(self) -> np.ndarray:
        """Its vertices in the gripper frame, shape (2, 2), metres: the two ends."""
        h = self.length / 2
        return np.array([[0.0, -h], [0.0, h]])

    def default_interest_points(self) -> np.ndarray:
        """The interest points when ``interest_points`` is None, shape (2, 2): the two ends."""
        return self.polyline()


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

    def polyline(self) -> np.ndarray:
        """Its vertices in the gripper frame, shape (3, 2), metres: the free
        end of the first bar, the corner, the free end of the second."""
        la, lb = self.lengths
        return np.array([[0.0, -la / 2], [0.0, la / 2], [lb, la / 2]])

    def default_interest_points(self) -> np.ndarray:
        """The interest points when ``interest_points`` is None, shape (3, 2): the three vertices."""
        return self.polyline()


@dc.dataclass
class Polyline:
    """A general object: an open polyline in the gripper frame."""

    # Vertices [[x, y], ...] in the gripper frame, metres (at least two).
    points: list[list[float]] = dc.field(default_factory=lambda: [[0.0, -0.5], [0.0, 0.5]])
    # Thickness, metres (> 0); every segment is a capsule of radius thickness/2.
    thickness: float = 0.05
    # Interest points [[x, y], ...] in the gripper frame; None = first and last vertex.
    interest_points: Optional[list[list[float]]] = None

    def polyline(self) -> np.ndarray:
        """Its vertices in the gripper frame, shape (M, 2), metres."""
        return np.asarray(self.points, dtype=float).reshape(-1, 2)

    def default_interest_points(self) -> np.ndarray:
        """The interest points when ``interest_points`` is None, shape (2, 2): the first and last vertex."""
        return self.polyline()[[0, -1]]


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
    # One weight in [0, 1e6] per interest point, in the order base, link-1 tip,
    # link-2 tip, then the object's points. None = 1 for every point.
    weights: Optional[list[float]] = None
    # Path-length weight lambda in [0, 1e6] added to the social integral
    # (0 = the paper's pure social cost). The default breaks ties by length:
    # where the social cost is 0 (nobody near) every route costs the same
    # without it, and the planner's path wanders; 0.001 per unit of length is
    # far below any social cost a route could save (a route 10 m longer costs
    # 0.01 more), so it decides only among routes of about equal social cost.
    length_weight: float = 0.001
    # Largest workspace displacement of any weighted interest point between two
    # samples of the trapezoid rule along a motion, metres (> 0). Threshold
    # crossings are located inside steps, so 0.1 m keeps Msc within ~0.5% of
    # a 2000-step reference on nearly every edge.
    resolution: float = 0.1
    # Kirby 2010's speed scaling: each person's sigma_h = max(2 v, 0.5) with v
    # their speed, m/s (sigma_s and sigma_r keep their ratios to it); false =
    # sigma_h for everyone, walking or not.
    speed_scaling: bool = False


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
    # Replan while executing (``simulate --replan``): a periodic event plans
    # from the robot's configuration against the people predicted over
    # ``replan_horizon`` (drake_social.control.ReplanningPlannerSystem).
    replan: bool = False
    # Replans per second of simulated time, Hz (> 0; a run that replans makes
    # at most one per execution.control_period: 1 / replan_rate >= control_period).
    replan_rate: float = 10.0
    # Wall-clock budget of one replan, seconds (in (0, MAX_REPLAN_BUDGET]):
    # the search stops there with the best path found so far.
    replan_budget: float = 0.08
    # Samples drawn per replan at most (1 .. MAX_REPLAN_ITERATIONS); the budget may stop it earlier.
    replan_iterations: int = 500
    # How far ahead people are predicted, seconds (in (0, MAX_REPLAN_HORIZON]).
    # Beyond it the safety check ignores them and the cost holds them where
    # they are predicted at the horizon.
    replan_horizon: float = 5.0
    # Seconds of the prediction over which a path must keep the safety
    # distance from everyone (> 0; the hard safety horizon: min(safety_horizon,
    # replan_horizon)). The social cost looks over the whole replan_horizon.
    safety_horizon: float = 2.0
    # A new path replaces the current one only when its cost is lower by at
    # least this fraction of the current one's (in [0, 1)).
    replan_margin: float = 0.05
    # Seconds of simulated time between two searches while the current path
    # stays safe (>= 0; 0 = a search at every replan). Every replan judges the
    # current path against the new prediction; one that finds it unsafe
    # searches at once.
    replan_search_period: float = 1.0
    # Added to social.length_weight in the replanner's objective (in [0, 1e6]): while
    # the robot drives, time passes for everyone, and a path should pay for
    # its length (with social.length_weight's tie-break alone, 0.001, a replan
    # may take any of many near-zero-cost detours: the replan margin of a
    # route's cost by length alone is too small to hold it; docs/replanning.md).
    replan_length_weight: float = 0.1
    # Cost of each second a judged path takes to the goal at the execution
    # limits (in [0, 1e6], per second): waiting and detours cost time. A
    # replan may also wait for the current path to clear, at this price per
    # second waited, rather than take a new route (docs/replanning.md,
    # "Progress and commitment").
    time_weight: float = 0.2
    # Cost of leaving the current route, per metre of the new path's mean
    # distance from it over its first replan_horizon seconds (in [0, 1e6]):
    # a new route must be cheaper by this too, so the robot does not swing
    # between routes of about equal cost.
    switch_weight: float = 1.0
    # How people are predicted: "interactive" (a social-force rollout in
    # which the people react to each judged path; docs/replanning.md,
    # "Interactive prediction"), "constant_velocity" (from their state now)
    # or "perfect" (scripted and recorded people as they will walk; a crowd
    # at constant velocity).
    prediction: str = "interactive"
    # Interactive prediction only: a path is not safe when it makes a person
    # brake harder than this beyond what they do without the robot, m/s^2
    # (in (0, MAX_COURTESY_DECELERATION]) ...
    courtesy_deceleration: float = 1.5
    # ... or moves a person further than this off their way, metres (in
    # (0, MAX_COURTESY_DEVIATION]): from where they would be without the
    # robot, across the way they would walk (lagging behind is braking; the
    # whole distance for who would stand), unless the robot holding still
    # asks as much of them.
    courtesy_deviation: float = 1.0
    # Weight of the people's effort (sum of their squared deviations over
    # the horizon, m^2 s) in a judged path's cost (in [0, 1e6]).
    courtesy_weight: float = 0.1


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
    # Discrete contact approximation of that plant (Drake's
    # MultibodyPlantConfig.discrete_contact_approximation): "tamsi", "sap",
    # "similar" or "lagged".
    contact_approximation: str = "tamsi"
    # Drake's SimulatorConfig of a run: the integration scheme (one of
    # pydrake.systems.analysis.GetIntegrationSchemes()), its accuracy (> 0,
    # with error control) and the target realtime rate (0 = as fast as
    # possible, 1 = wall-clock time, e.g. to watch Meshcat live).
    integration_scheme: str = "runge_kutta3"
    accuracy: float = 1e-4
    target_realtime_rate: float = 0.0
    # A run that has not reached the goal after this long stops and says so,
    # seconds (> 0, <= MAX_TIME_LIMIT = 600; at most MAX_CONTROL_STEPS control
    # periods and MAX_PLANT_STEPS plant steps).
    time_limit: float = 300.0
    # Frames per second of the Meshcat recording (> 0, <= MAX_REPLAY_FPS = 60).
    replay_fps: float = 30.0
    # The safety monitor holds the robot (base stopped, base and arm reference
    # held) while any part of it (base, arm, object) is within this distance
    # of a person's body, surface to surface, and lets it go when clear,
    # metres (>= 0; 0 stops on contact only). Only in a scenario with people.
    safety_distance: float = 0.05
    # Slowing down near people (synchronized execution, when people move; see
    # docs/execution.md): a limit on the speed of the robot's fastest point
    # that falls with the distance from its nearest part to the nearest
    # person, so that it brakes (jerk-limited, on the path) and stops before
    # the safety distance. false = the paper's behaviour: full speed until
    # the safety monitor's stop.
    slow_down: bool = True
    # The limit plans the robot's rest this far outside safety_distance,
    # metres (>= 0).
    stop_margin: float = 0.05
    # Within this distance of a person (surface to surface) the limit falls
    # linearly from max_base_speed to slow_speed at safety_distance +
    # stop_margin, metres (> safety_distance + stop_margin).
    slow_distance: float = 1.0
    # The ramp's speed at its near end and the speed the limit must allow
    # before a stop is released, m/s (> 0, <= max_base_speed).
    slow_speed: float = 0.2
    # Minimum hold: the limit is the lowest of the last release_time seconds,
    # so it rises only when the lower values are that old, seconds (>= 0).
    release_time: float = 0.5


@dc.dataclass
class Scenario:
    """Everything needed to plan and simulate one transport task."""

    # Free text shown in figures and reports.
    description: str = ""
    # The room and its obstacles.
    world: World = dc.field(default_factory=World)
    # People standing or walking a script.
    people: list[Person] = dc.field(default_factory=list)
    # People simulated by the social force model; None = no crowd.
    crowd: Optional[Crowd] = None
    # Recorded pedestrians: a CSV file with the header t,id,x,y (optional
    # theta, radius and v columns), a row per person and time; a path relative
    # to the scenario file (made absolute when the scenario is loaded). None =
    # no recording.
    people_file: Optional[str] = None
    # Keep only these ids of people_file (each must occur in it); None = all.
    people_file_ids: Optional[list[str]] = None
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


def interest_point_count(obj: Union[Bar, LShape, Polyline]) -> int:
    """The number of the object's interest points (explicit or default)."""
    if obj.interest_points is not None:
        return len(obj.interest_points)
    return len(obj.default_interest_points())
