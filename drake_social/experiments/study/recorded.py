"""The recorded-crowd benchmark (``drake-social experiment crowd --recording``):
windows of a real pedestrian recording, the robot carrying its bar across
the flow, planning once against replanning.

A :class:`RecordedCrowdStudy` reads an ETH/UCY recording (as ``people
import`` does: :mod:`drake_social.people.eth_ucy`), cuts ``windows``
windows of ``window_length`` seconds with at least ``min_people`` people
present on average, the densest first
(:func:`~drake_social.people.windows.cut_windows`), and makes each a
scenario (:func:`~.recorded_scene.window_scene`: the flow turned across the
robot's task, the start and the goal outside the flow and clear of everyone
at t = 0, a room around them; checked with the exact planar checker by
:func:`~.recorded_scene.verify_scene`).

Each window runs every variant (:data:`VARIANTS`) for ``episodes``
episodes: a closed-loop kinematic run of the window's scenario with the
study's ``--set`` overrides, then the variant's, then ``planner.prediction:
<prediction>`` for a variant that replans when a prediction is named.
Episode ``k`` of every window and variant has the seed ``s_k``
(``SeedSequence(seed).spawn(episodes)``, as the crowd study's episodes):
``random_seed = s_k`` (the planner's samples). The records **pair** over
(window, episode): a record's ``episode`` is ``window * episodes + k``.

The variants: ``plan_once`` (the paper's Social Risk-RRT*, planned once at
t = 0), ``replan`` (``planner.replan: true`` and nothing else: the
replanner as its defaults and ``--set`` make it, with whatever prediction is
the default) and the crowd study's ``replan_base``, ``replan_multi``,
``replan_speed``.

A task carries its window's scenario and people file as text (plain data:
any worker, any executor, the same records); the run of one
(:func:`run_window_episode`) writes them into a temporary folder, runs the
episode as the crowd study does
(:func:`~drake_social.experiments.study.crowd_episode.episode_record`) and
adds what a crossing measures: ``crossed`` (the goal reached while the
window still has people: ``time_to_goal <= people_end``),
``goal_distance_start`` and ``goal_distance_end`` (the base's distance to
the goal at t = 0 and when the episode ended, metres) and the window's
numbers. As in the crowd study, a replan that hits its wall-clock budget
(``replan_deadline_hits`` > 0) stops at an iteration the machine decides.
"""

from __future__ import annotations

import dataclasses as dc
import math
import tempfile
from pathlib import Path

from drake_social.arguments import (Rule, check_arguments, require_choice, require_choices, require_file_name,
                                    require_instance, require_int, require_number, require_strings)
from drake_social.errors import ScenarioError
from drake_social.experiments.study.crowd import (NO_REPLANNING, VARIANTS as CROWD_VARIANTS, check_trace_episode,
                                                  episode_seeds, perturb, replanning_available)
from drake_social.experiments.study.recorded_scene import WindowScene, verify_scene, window_scene, write_scene
from drake_social.limits import MAX_EPISODES, MAX_TIME_LIMIT, MAX_WINDOWS, MIN_WINDOW_LENGTH, RECORDED_VARIANTS
from drake_social.people.eth_ucy import ETH_UCY_FPS, ETH_UCY_LAYOUTS, MAX_RECORDING_BYTES, parse_eth_ucy
from drake_social.people.windows import cut_windows
from drake_social.scenario import PREDICTIONS, Scenario, load_scenario_text, time_limit_problem

__all__ = ["DEFAULT_VARIANTS", "RECORDED_SETTINGS", "VARIANTS", "RecordedCrowdStudy", "check_recorded_settings",
           "check_recorded_study", "recorded_scenes", "recorded_tasks", "run_window_episode"]

#: Variant name -> the scenario overrides that make it (the names:
#: :data:`drake_social.limits.RECORDED_VARIANTS`).
VARIANTS: dict[str, tuple[str, ...]] = {"plan_once": CROWD_VARIANTS["plan_once"],
                                        "replan": ("planner: {replan: true}",),
                                        **{v: CROWD_VARIANTS[v] for v in ("replan_base", "replan_multi",
                                                                          "replan_speed")}}
#: The variants run by default: planning once against the default replanning.
DEFAULT_VARIANTS = ("plan_once", "replan")

#: The command's option of each setting of :func:`~drake_social.people.windows.cut_windows`, for its messages.
WINDOW_OPTIONS = {"length": "--window-length", "count": "--windows", "min_people": "--min-people"}

#: The rule of each setting (:class:`RecordedCrowdStudy`'s fields): :func:`check_recorded_settings`.
RECORDED_SETTINGS: dict[str, Rule] = {
    "name": lambda v, who, name: require_instance(v, str, who, name, "a string"),
    "recording": require_file_name,
    "layout": lambda v, who, name: require_choice(v, who, name, tuple(ETH_UCY_LAYOUTS)),
    "fps": lambda v, who, name: require_number(v, who, name, positive=True, unit="frames per second"),
    "windows": lambda v, who, name: require_int(v, who, name, minimum=1, maximum=MAX_WINDOWS),
    "window_length": lambda v, who, name: require_number(v, who, name, minimum=MIN_WINDOW_LENGTH,
                                                         maximum=MAX_TIME_LIMIT, unit="seconds"),
    "min_people": lambda v, who, name: require_int(v, who, name, minimum=1),
    "variants": lambda v, who, name: require_choices(v, who, name, RECORDED_VARIANTS),
    "prediction": lambda v, who, name: require_choice(v, who, name, PREDICTIONS, optional=True),
    "sets": require_strings,
    "episodes": lambda v, who, name: require_int(v, who, name, minimum=1, maximum=MAX_EPISODES),
    "seed": lambda v, who, name: require_int(v, who, name, minimum=0),
    "time_limit": lambda v, who, name: require_number(v, who, name, positive=True, maximum=MAX_TIME_LIMIT,
                                                      unit="seconds", optional=True),
    "trace_episode": lambda v, who, name: require_int(v, who, name, minimum=0, optional=True),
}


def check_recorded_settings(who: str, settings: dict) -> None:
    """Checks a recorded-crowd study's settings (:data:`RECORDED_SETTINGS`, and
    ``trace_episode`` below ``episodes``) as ``who``'s arguments.

    Raises:
        TypeError: an unknown setting or one of the wrong kind; ValueError: a
            value out of range; each naming ``who`` and the setting.
    """
    check_arguments(who, RECORDED_SETTINGS, settings)
    check_trace_episode(who, settings, RecordedCrowdStudy.episodes)


@dc.dataclass(frozen=True)
class RecordedCrowdStudy:
    """What a recorded-crowd benchmark runs.

    Attributes:
        recording: the ETH/UCY recording file.
        name: the study's name.
        layout, fps: how to read it (:mod:`drake_social.people.eth_ucy`).
        windows: how many windows, in [1, MAX_WINDOWS].
        window_length: seconds of each, in [MIN_WINDOW_LENGTH, MAX_TIME_LIMIT].
        min_people: the least mean number of people present in a window (>= 1).
        variants: names of :data:`VARIANTS`, in the report's order.
        prediction: ``planner.prediction`` of the variants that replan
            (one of ``drake_social.scenario.PREDICTIONS``); None = the default.
        sets: scenario overrides (YAML, as ``--set``) for every window, before the variant's.
        episodes: seeded episodes per window and variant, in [1, MAX_EPISODES].
        seed: the study seed (>= 0).
        time_limit: simulated seconds per episode (in (0, MAX_TIME_LIMIT]);
            None = the window's length.
        trace_episode: the episode (in [0, episodes)) whose trace every
            window and variant keeps for the snapshots; None = none.
    """

    recording: str
    name: str = "recorded_crowd"
    layout: str = "xy"
    fps: float = ETH_UCY_FPS
    windows: int = 5
    window_length: float = 60.0
    min_people: int = 1
    variants: tuple[str, ...] = DEFAULT_VARIANTS
    prediction: str | None = None
    sets: tuple[str, ...] = ()
    episodes: int = 1
    seed: int = 0
    time_limit: float | None = None
    trace_episode: int | None = 0

    def __post_init__(self) -> None:
        check_recorded_settings("RecordedCrowdStudy", dc.asdict(self))

    @property
    def stem(self) -> str:
        """The recording's file name without its suffix (the records' ``scenario``)."""
        return Path(self.recording).stem

    def window_names(self) -> list[str]:
        return [f"window_{k}" for k in range(self.windows)]

    def run_seeds(self) -> list[int]:
        """Episode k's seed, shared by every window and variant."""
        return episode_seeds(self.seed, self.episodes)

    def to_json_dict(self) -> dict:
        return {**dc.asdict(self), "recording": str(self.recording)}

    def overrides(self, variant: str) -> tuple[str, ...]:
        """The overrides of ``variant``'s episodes: the study's ``sets``, the
        variant's, then the prediction for a variant that replans."""
        own = VARIANTS[variant]
        replans = variant != "plan_once"
        prediction = (f"planner: {{prediction: {self.prediction}}}",) if replans and self.prediction else ()
        return (*self.sets, *own, *prediction)

    def scenario(self, name: str, text: str, *, folder: str | Path, variant: str = "plan_once") -> Scenario:
        """Window ``name``'s scenario from its ``text`` with ``variant``'s
        overrides; its people file is read from ``folder``."""
        return load_scenario_text(text, str(Path(folder) / f"{name}.yaml"), list(self.overrides(variant)),
                                  overrides_name=f"variant {variant}", base_dir=folder)


def recorded_scenes(study: RecordedCrowdStudy) -> list[WindowScene]:
    """The windows of the study's recording made scenarios (read, cut and
    placed now), each loaded with the study's ``--set`` and every variant and
    its start and goal checked with the exact planar checker.

    Raises:
        ScenarioError: the recording cannot be read or parsed, is too short,
            has too few dense windows, or a window's scenario with the
            overrides is invalid (naming ``--set`` or the variant).
    """
    from drake_social.io.textfile import read_text_file

    text = read_text_file(study.recording, "recording", "--recording", limit=MAX_RECORDING_BYTES)
    recording = parse_eth_ucy(text, str(study.recording), study.layout)
    windows = cut_windows(recording, fps=study.fps, length=study.window_length, count=study.windows,
                          min_people=study.min_people, options=WINDOW_OPTIONS)
    scenes = [window_scene(recording, w, fps=study.fps, sets=tuple(study.sets)) for w in windows]
    with tempfile.TemporaryDirectory(prefix="drake-social-windows-") as folder:
        for scene in scenes:
            path = write_scene(scene, folder)
            source = f"{study.recording}: {scene.name}"
            try:
                base = load_scenario_text(scene.scenario_text, source, list(study.sets), overrides_name="--set",
                                          base_dir=folder)
                for v in study.variants:
                    load_scenario_text(scene.scenario_text, source, list(study.overrides(v)),
                                       overrides_name=f"variant {v}", base_dir=folder)
            except ScenarioError as e:
                raise ScenarioError(str(e).replace(str(path), source)) from None
            verify_scene(base, source)
            if study.time_limit is not None:
                problem = time_limit_problem(study.time_limit, base.execution, "time_limit")
                if problem:
                    raise ScenarioError(f"{source}: --time-limit {problem[1]}")
    return scenes


def recorded_tasks(study: RecordedCrowdStudy, scenes: list[WindowScene] | None = None) -> list[dict]:
    """Plain-data tasks, one per (window, variant, episode), in that order.

    Raises:
        ScenarioError: as :func:`recorded_scenes`.
    """
    scenes = recorded_scenes(study) if scenes is None else scenes
    seeds = study.run_seeds()
    tasks = []
    for w, scene in enumerate(scenes):
        summary = scene.summary()
        for variant in study.variants:
            for k, seed in enumerate(seeds):
                tasks.append({"index": len(tasks), "scenario": study.stem, "window": w, "window_name": scene.name,
                              "source": f"{study.recording}: {scene.name}", "scenario_text": scene.scenario_text,
                              "people_name": scene.people_name, "people_text": scene.people_text,
                              "window_summary": summary, "variant": variant,
                              "overrides": list(study.overrides(variant)), "episode": w * study.episodes + k,
                              "window_episode": k, "seed": seed, "jitter": 0.0, "time_limit": study.time_limit,
                              "trace": k == study.trace_episode})
    return tasks


def check_recorded_study(study: RecordedCrowdStudy) -> list[dict]:
    """The study's tasks (:func:`recorded_tasks`), once the simulator is known
    to replan when a variant asks for it.

    Raises:
        ScenarioError: as :func:`recorded_tasks`; a replanning variant where
            replanning is not available.
    """
    if any(v != "plan_once" for v in study.variants) and not replanning_available():
        raise ScenarioError(f"--variants {' '.join(study.variants)}: {NO_REPLANNING}")
    return recorded_tasks(study)


#: The window's numbers copied into every record.
_WINDOW_FIELDS = ("start", "end", "people_mean", "people_min", "people_max", "people_t0", "people_end",
                  "flow_angle", "rotation", "task_length", "clearance_start", "clearance_goal")


def run_window_episode(task: dict) -> dict:
    """Runs one episode of a window (closed loop, kinematic) and measures it;
    a record of plain data: the crowd study's
    (:func:`~drake_social.experiments.study.crowd_episode.episode_record`)
    with ``window``, ``window_episode``, the window's numbers
    (``window_start``, ``window_people_mean``, ...), ``crossed``,
    ``goal_distance_start`` and ``goal_distance_end``."""
    import numpy as np

    from drake_social.experiments.study.crowd_episode import episode_record

    with tempfile.TemporaryDirectory(prefix="drake-social-window-") as folder:
        (Path(folder) / task["people_name"]).write_text(task["people_text"])
        base = load_scenario_text(task["scenario_text"], task["source"], task["overrides"],
                                  overrides_name=f"variant {task['variant']}", base_dir=folder)
        scenario, delays = perturb(base, task["seed"], 0.0)
        record, run = episode_record(task, scenario, delays)
    summary = task["window_summary"]
    goal = np.asarray(scenario.goal[:2], float)
    q = np.asarray(run.q, float).reshape(-1, 4)
    ttg = record["time_to_goal"]
    out = {key: record.pop(key) for key in ("index", "scenario", "variant", "episode", "seed")}
    out.update({"window": task["window"], "window_episode": task["window_episode"]})
    out.update({f"window_{key}": summary[key] for key in _WINDOW_FIELDS})
    out.update({
        "crossed": float(bool(record["reached"]) and math.isfinite(ttg) and ttg <= summary["people_end"]),
        "goal_distance_start": float(np.hypot(*(np.asarray(scenario.start[:2], float) - goal))),
        "goal_distance_end": float(np.hypot(*(q[-1, :2] - goal))) if len(q) else math.nan,
    })
    out.update(record)
    return out
