"""Constants shared across the package: the bounds of a scenario and a run,
and the names of the planners and the validity checkers. One home each.

A module of its own, with no imports, so that every layer may read it (the
scenario check, the command line, the studies) and the compiled kernels can
compile its constants in; :mod:`drake_social._kernel_cache` drops their cached
code when this file changes (it hashes it with the kernel sources).
"""

#: Largest iteration budget K of a planner (``planner.iterations``,
#: ``--iterations``, ``RrtStarOptions.iterations``): the tree grows with the
#: nodes added, but K samples still take time (10^7 is hours of planning).
MAX_ITERATIONS = 10_000_000

#: The most trapezoid steps of ``social.resolution`` one motion's social cost
#: may take (its samples are held in memory): 100 km at the default 0.1 m.
#: ``validate_scenario`` refuses a resolution that a motion in the room could
#: need more steps of.
MAX_MOTION_STEPS = 1_000_000

#: The most waypoints a path to execute may have (``simulate --path``, the
#: ``waypoints`` of ``simulate`` and ``build_diagram``). The sequencer moves
#: on at most once per control period and stops at every waypoint of a
#: synchronized run: a densified 10,000-waypoint path cannot be executed within
#: the longest time limit (600 s; one reached waypoint 1,501 in 300 s), so
#: this bounds the checks and the analysis (whose memory does not grow with
#: the path), not what a run can finish.
MAX_WAYPOINTS = 10_000

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

#: Replanning while executing (``planner.replan_*``), so that one replan and
#: one run stay bounded. At most this many replans per control period
#: (``1 / planner.replan_rate >= execution.control_period``): the sequencer
#: takes a new path once per period, and a run has at most MAX_CONTROL_STEPS
#: periods, so at most that many replans.
MAX_REPLANS_PER_CONTROL_PERIOD = 1
#: Most samples of one replan's search (``planner.replan_iterations``, the
#: replanner's ``iterations``): 20 times the default 500. A search of
#: 10,000 samples on lobby_crowd.yaml takes 1.6 s (2-core AMD EPYC); its
#: tree and its per-sample history are allocated for the cap at every replan.
MAX_REPLAN_ITERATIONS = 10_000
#: Largest wall-clock budget of one replan, seconds (``planner.replan_budget``).
#: Far above what MAX_REPLAN_ITERATIONS samples take, so that a run whose
#: every replan stops at the iteration cap (reproducible on any machine;
#: docs/replanning.md) can still be asked for.
MAX_REPLAN_BUDGET = 60.0
#: Longest prediction horizon of a replan, seconds (``planner.replan_horizon``):
#: no run lasts longer (MAX_TIME_LIMIT). The prediction holds one sample per
#: 0.1 s per person (6,001 samples here).
MAX_REPLAN_HORIZON = MAX_TIME_LIMIT
#: Largest courtesy bound on the deceleration a plan may ask of a person,
#: m/s^2 (``planner.courtesy_deceleration``): a person's braking in the
#: social force model reaches about v / tau, 1.34 / 0.5 = 2.7 m/s^2 from a
#: walk to a stop, and a hard stop about 10 m/s^2; 20 leaves the bound off in effect.
MAX_COURTESY_DECELERATION = 20.0
#: Largest courtesy bound on a person's deviation, metres (``planner.courtesy_deviation``):
#: farther than anyone walks over the longest useful horizon at a walking pace.
MAX_COURTESY_DEVIATION = 100.0
#: Largest weight of the planners' objectives (``social.weights``,
#: ``social.length_weight``, ``planner.replan_length_weight``): a motion's cost
#: sums weight x AGF (at most 1) x metres over every point and person, so with
#: weights up to 10^6 the costs of any room stay far below the largest float
#: (1e308 made them inf: every path equally dear, the robot never left).
MAX_COST_WEIGHT = 1e6

#: Planner names accepted in ``planner.algorithm`` (see ``drake_social.planning``).
ALGORITHMS = (
    "rrt_star",
    "social_rrt_star",
    "base_rrt_star",
    "informed_social_rrt_star",
    "informed_base_rrt_star",
)
#: The planners of ALGORITHMS that sample in the informed ellipse (a test keeps
#: it equal to the informed samplers of ``planning.algorithms.ALGORITHM_SPECS``).
INFORMED_ALGORITHMS = ("informed_social_rrt_star", "informed_base_rrt_star")

#: Validity checkers (``drake_social.collision.drake_checker.make_checker``; the first is
#: the default of the planner): the exact planar one, Drake's SceneGraph and
#: the pure-numpy reference. Named here so that the command line and
#: studies can name them without importing Drake.
CHECKERS = ("planar", "drake", "numpy")

#: The values of ``execution.contact_approximation``: Drake's discrete contact
#: approximations (``MultibodyPlantConfig.discrete_contact_approximation``).
CONTACT_APPROXIMATIONS = ("tamsi", "sap", "similar", "lagged")
#: The values of ``execution.integration_scheme``: the names
#: ``pydrake.systems.analysis.GetIntegrationSchemes()`` returns, written out so
#: that the scenario check need not import Drake (a test keeps them equal).
INTEGRATION_SCHEMES = (
    "bogacki_shampine3",
    "cenic",
    "explicit_euler",
    "implicit_euler",
    "radau1",
    "radau3",
    "runge_kutta2",
    "runge_kutta3",
    "runge_kutta5",
    "semi_explicit_euler",
    "velocity_implicit_euler",
)

#: The paper's planner settings (``--set`` text over a scenario file): the raw
#: RRT* path (no optimisation) and the fixed near radius of Algorithm 2. The
#: paper study applies it over every group and ``bench`` over every scenario
#: (its last override), so both run the planner OMPL's RRTstar is compared with.
PAPER_PLANNER = "planner: {optimize: false, near_radius_mode: fixed}"
#: The paper's objective (``--set`` text): the social integral alone, without
#: the default's length tie-break (``social.length_weight`` 0.001). The paper
#: study applies it over every group, after :data:`PAPER_PLANNER`; ``bench``
#: keeps each file's objective (an ``informed_mode: admissible`` file needs its
#: length weight).
PAPER_OBJECTIVE = "social: {length_weight: 0.0}"

#: The paper's algorithms, in its order (the non-social baseline first).
PAPER_ALGORITHMS = ("rrt_star", "social_rrt_star", "base_rrt_star", "informed_social_rrt_star",
                    "informed_base_rrt_star")
#: The weightings of the paper's study D (``experiments.study.paper_weights``).
PAPER_WEIGHTINGS = ("object", "base", "equal")
#: Most runs per (group, algorithm) of a study (each run's seed is drawn up front).
MAX_RUNS = 10_000
#: Most tasks of a study (groups x algorithms x runs): every run's record is
#: kept in memory until the study is written (a few kilobytes each).
MAX_STUDY_TASKS = 100_000
#: (group, algorithm) pairs of the paper study (``experiments.study.paper_study``):
#: A and B with the paper's five planners, D with Social Risk-RRT* under
#: three weightings (a test counts them in the study).
PAPER_PAIRS = 2 * len(PAPER_ALGORITHMS) + len(PAPER_WEIGHTINGS)
#: Most runs of the paper study (``experiment paper --runs``): its
#: PAPER_PAIRS pairs x runs stay within MAX_STUDY_TASKS.
MAX_PAPER_RUNS = min(MAX_RUNS, MAX_STUDY_TASKS // PAPER_PAIRS)
#: Backends of a study (``experiments.study.executors.map_tasks``, ``experiment --executor``).
EXECUTORS = ("process", "dask")

#: Values of ``planner.near_radius_mode`` and ``RrtStarOptions.near_radius_mode``:
#: the near set's radius is r_near, or shrinks with the tree (capped at r_near).
NEAR_RADIUS_MODES = ("fixed", "shrinking")

#: The crowd study's variants (``experiment crowd --variants``; their overrides:
#: ``drake_social.experiments.study.crowd.VARIANTS``), its default scenarios
#: (shipped scenario files, found beside the package:
#: ``drake_social.scenario.shipped``) and the most episodes per scenario and variant.
CROWD_VARIANTS = ("plan_once", "replan_base", "replan_multi", "replan_speed")
CROWD_SCENARIOS = ("office_walkers.yaml", "lobby_crowd.yaml")
MAX_EPISODES = 10_000
#: Largest start delay of a crowd study's scripted walker (``experiment crowd
#: --jitter``), seconds: a walker delayed longer than the longest run
#: (MAX_TIME_LIMIT) never walks in it.
MAX_JITTER = MAX_TIME_LIMIT

#: The recorded-crowd benchmark (``experiment crowd --recording``): its
#: variants (their overrides: ``drake_social.experiments.study.recorded.VARIANTS``;
#: ``replan`` replans with every other setting the scenario's default), the
#: most windows of a recording (each a scenario written into the output set,
#: and ``variants x episodes`` runs of it) and the shortest window, seconds
#: (the longest: MAX_TIME_LIMIT, the longest run).
RECORDED_VARIANTS = ("plan_once", "replan", "replan_base", "replan_multi", "replan_speed")
MAX_WINDOWS = 1_000
MIN_WINDOW_LENGTH = 1.0

#: Most seeds of ``bench --seeds``: as many as a study's runs per planner
#: (MAX_RUNS); each seed plans every algorithm on every scenario.
MAX_BENCH_SEEDS = 10_000
#: Most timings of one run in ``bench --repeats``: the median of 100 already
#: filters the machine's noise, and each repeat replans the whole path.
MAX_BENCH_REPEATS = 100
#: Most simulated runs of ``bench --sim-runs`` (per mode and execution) and
#: ``bench --replan-runs``: each is a whole run of the scenario (up to
#: MAX_TIME_LIMIT simulated seconds); as many as ``--repeats``.
MAX_BENCH_RUNS = MAX_BENCH_REPEATS
#: Most replans of the replanning benchmark's rollout (``bench
#: --replan-count``): the most a run can make (one per control period,
#: MAX_CONTROL_STEPS periods).
MAX_BENCH_REPLAN_COUNT = MAX_CONTROL_STEPS
#: Most worker processes of ``experiment --workers``: each holds Drake and a
#: scenario's checker (a few hundred MB), so 64 already needs tens of GB; a
#: cluster is the place for more (``--executor dask --scheduler``).
MAX_WORKERS = 64
