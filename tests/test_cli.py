"""The drake-social command line: help, show on every scenario, error messages."""

from __future__ import annotations

import struct
from pathlib import Path

import matplotlib.image
import pytest

from drake_social.cli import build_parser, load_with_overrides, main
from drake_social.scenario import ScenarioError

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"
SCENARIO_FILES = sorted(SCENARIO_DIR.glob("*.yaml"))


def _png_size(path: Path) -> tuple[int, int]:
    """(width, height) from the PNG header, read independently of matplotlib."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def test_help_lists_the_show_command(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "usage: drake-social" in out and "show" in out


def test_show_help_documents_its_options(capsys):
    assert main(["show", "--help"]) == 0
    out = capsys.readouterr().out
    assert "--out DIR" in out and "--set YAML" in out and "scenario" in out


def test_no_command_prints_usage_and_fails(capsys):
    assert main([]) == 2
    assert "usage: drake-social" in capsys.readouterr().err


def test_unknown_option_is_a_usage_error(capsys):
    assert main(["show", str(SCENARIO_DIR / "tiny.yaml"), "--bogus"]) == 2
    assert "unrecognized arguments: --bogus" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("scenario", SCENARIO_FILES, ids=[p.stem for p in SCENARIO_FILES])
def test_show_writes_a_png_of_every_scenario(scenario, tmp_path, capsys):
    assert main(["show", str(scenario), "--out", str(tmp_path)]) == 0
    dut = tmp_path / "scene.png"
    assert capsys.readouterr().out.strip() == f"wrote {dut}"
    assert dut.stat().st_size > 30_000
    width, height = _png_size(dut)
    assert 1000 <= width <= 2500 and 600 <= height <= 2000
    pixels = matplotlib.image.imread(dut)
    assert pixels.shape[:2] == (height, width)
    # Not a blank canvas: the heat map's reds and the white floor both occur.
    rgb = pixels[..., :3]
    reddish = (rgb[..., 0] > 0.5) & (rgb[..., 1] < 0.3) & (rgb[..., 2] < 0.3)
    assert reddish.mean() > 0.01
    assert (rgb.min(-1) > 0.95).mean() > 0.1


@pytest.mark.slow
def test_show_writes_to_out_slash_scenario_name_by_default(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["show", str(SCENARIO_DIR / "tiny.yaml")]) == 0
    assert (tmp_path / "out" / "tiny" / "scene.png").is_file()
    assert capsys.readouterr().out.strip() == f"wrote {Path('out') / 'tiny' / 'scene.png'}"


def test_overrides_apply_over_the_file_and_keep_the_rest():
    dut = load_with_overrides(SCENARIO_DIR / "tiny.yaml", ["social: {sigma_h: 1.5, threshold: 0.1}", "random_seed: 7"])
    assert dut.social.sigma_h == 1.5 and dut.social.threshold == 0.1
    assert dut.social.side_ratio == pytest.approx(2 / 3)  # untouched default
    assert dut.random_seed == 7
    assert dut.planner.iterations == 300  # from the file
    assert load_with_overrides(SCENARIO_DIR / "tiny.yaml", None).random_seed == 1


def _error(capsys, argv: list[str]) -> str:
    """Runs a failing command; returns its stderr after checking the exit code."""
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    return captured.err


def test_missing_file_names_the_file(tmp_path, capsys):
    missing = tmp_path / "nowhere.yaml"
    err = _error(capsys, ["show", str(missing), "--out", str(tmp_path)])
    assert err.startswith("drake-social: error: ") and str(missing) in err and "no such scenario file" in err
    assert not (tmp_path / "scene.png").exists()


def test_invalid_override_value_names_the_file_and_field(tmp_path, capsys):
    tiny = SCENARIO_DIR / "tiny.yaml"
    err = _error(capsys, ["show", str(tiny), "--set", "robot: {base_radius: -0.2}", "--out", str(tmp_path)])
    assert str(tiny) in err and "robot.base_radius" in err and "> 0" in err
    err = _error(capsys, ["show", str(tiny), "--set", "planner: {algorithm: dijkstra}", "--out", str(tmp_path)])
    assert "planner.algorithm" in err and "dijkstra" in err and "social_rrt_star" in err


def test_unknown_key_in_an_override_names_the_key(tmp_path, capsys):
    tiny = SCENARIO_DIR / "tiny.yaml"
    err = _error(capsys, ["show", str(tiny), "--set", "social: {sigmah: 2}", "--out", str(tmp_path)])
    assert f"{tiny} (--set 'social: {{sigmah: 2}}'): line 1: social.sigmah: unknown field in social" in err


def test_unknown_key_in_a_file_names_the_file_and_key(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    text = (SCENARIO_DIR / "tiny.yaml").read_text()
    bad.write_text(text.replace("  link_width: 0.08\n", "  link_width: 0.08\n  wheels: 4\n"))
    assert "wheels" in bad.read_text()
    err = _error(capsys, ["show", str(bad), "--out", str(tmp_path)])
    assert str(bad) in err and "wheels" in err


def test_value_error_in_a_file_names_the_file_and_field(tmp_path, capsys):
    bad = tmp_path / "outside.yaml"
    text = (SCENARIO_DIR / "tiny.yaml").read_text()
    bad.write_text(text.replace("start: [1.0, 2.5, 0.0, 1.5708]", "start: [11.0, 2.5, 0.0, 1.5708]"))
    err = _error(capsys, ["show", str(bad), "--out", str(tmp_path)])
    assert str(bad) in err and "start" in err and "outside world.bounds" in err


def test_malformed_override_yaml_is_reported(tmp_path, capsys):
    tiny = SCENARIO_DIR / "tiny.yaml"
    err = _error(capsys, ["show", str(tiny), "--set", "social: {sigma_h: [", "--out", str(tmp_path)])
    assert "--set" in err and "not valid YAML" in err
    err = _error(capsys, ["show", str(tiny), "--set", "just text", "--out", str(tmp_path)])
    assert "must be a YAML mapping" in err


def test_overrides_apply_in_turn_and_merge(capsys, tmp_path):
    """Two --set of the same section merge; a later value wins; a bad one is named."""
    tiny = SCENARIO_DIR / "tiny.yaml"
    dut = load_with_overrides(tiny, ["social: {sigma_h: 1.5}", "{random_seed: 3}", "social: {threshold: 0.1}"])
    assert (dut.social.sigma_h, dut.social.threshold, dut.random_seed) == (1.5, 0.1, 3)
    assert load_with_overrides(tiny, ["random_seed: 1", "random_seed: 2"]).random_seed == 2
    err = _error(capsys, ["show", str(tiny), "--set", "random_seed: 1", "--set", "social: {sigmah: 2}",
                          "--out", str(tmp_path)])
    assert "social: {sigmah: 2}" in err and "sigmah" in err


def test_unwritable_output_exits_1(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    assert main(["show", str(SCENARIO_DIR / "tiny.yaml"), "--out", str(blocker)]) == 1
    assert "drake-social: error:" in capsys.readouterr().err


@pytest.mark.slow
def test_overrides_reach_the_picture(tmp_path):
    """Removing the people through --set leaves no red on the map (the left
    three quarters of the picture; the colour bar is on the right)."""
    tiny = str(SCENARIO_DIR / "tiny.yaml")
    reds = []
    for i, extra in enumerate([[], ["--set", "people: []"]]):
        assert main(["show", tiny, *extra, "--out", str(tmp_path / str(i))]) == 0
        rgb = matplotlib.image.imread(tmp_path / str(i) / "scene.png")[..., :3]
        rgb = rgb[:, : 3 * rgb.shape[1] // 4]
        reds.append(((rgb[..., 0] > 0.5) & (rgb[..., 1] < 0.3) & (rgb[..., 2] < 0.3)).mean())
    assert reds[0] > 0.05 and reds[1] == 0.0


# ---- counts and folders of the command line are bounded and named (review of the loader, "outside the loader")

_TINY = Path(__file__).resolve().parent.parent / "scenarios" / "tiny.yaml"


@pytest.mark.parametrize("argv, message", [
    (["bench", "--seeds", "1000000000"], "argument --seeds: must be an integer in [1, 10,000], got 1000000000"),
    (["bench", "--repeats", "1000000000"], "argument --repeats: must be an integer in [1, 100], got 1000000000"),
    (["experiment", "sweep", "x.yaml", "--workers", "1000000000"],
     "argument --workers: must be an integer in [1, 64], got 1000000000"),
    (["experiment", "paper", "--workers", "65"], "argument --workers: must be an integer in [1, 64], got 65"),
])
def test_counts_of_the_command_line_are_bounded(capsys, argv, message):
    assert main(argv) == 2
    assert capsys.readouterr().err.endswith(f"error: {message}\n")


@pytest.mark.parametrize("argv, message", [
    (["experiment", "crowd", "--time-limit", "1e9"], "argument --time-limit: must be a number in (0, 600], got 1e9"),
    (["experiment", "crowd", "--time-limit", "600.0000000000001"],
     "argument --time-limit: must be a number in (0, 600], got 600.0000000000001"),
    (["experiment", "crowd", "--time-limit", "0"], "argument --time-limit: must be a number in (0, 600], got 0"),
    (["experiment", "crowd", "--jitter", "600.0000000000001"],
     "argument --jitter: must be a number in [0, 600], got 600.0000000000001"),
    (["experiment", "crowd", "--jitter", "1e300"], "argument --jitter: must be a number in [0, 600], got 1e300"),
    (["experiment", "crowd", "--jitter=-5e-324"], "argument --jitter: must be a number in [0, 600], got -5e-324"),
    (["experiment", "crowd", "--variants", "plan_once", "plan_once"],
     "argument --variants: 'plan_once' given twice: each at most once"),
    (["bench", "--iterations", "10000001"], "argument --iterations: must be an integer in [1, 10,000,000], got 10000001"),
    (["bench", "--sim-runs", "101"], "argument --sim-runs: must be an integer in [0, 100], got 101"),
    (["bench", "--replan-runs", "101"], "argument --replan-runs: must be an integer in [0, 100], got 101"),
    (["bench", "--replan-count", "60001"], "argument --replan-count: must be an integer in [1, 60,000], got 60001"),
])
def test_numbers_of_experiment_crowd_and_bench_are_bounded(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.endswith(f"error: {message}\n") and "Traceback" not in err


def test_the_bounds_of_experiment_crowd_and_bench_themselves_parse():
    parse = build_parser().parse_args
    args = parse(["experiment", "crowd", "--time-limit", "600", "--jitter", "600"])
    assert (args.time_limit, args.jitter) == (600.0, 600.0)
    args = parse(["experiment", "crowd", "--time-limit", "599.9999999999999", "--jitter", "0"])
    assert (args.time_limit, args.jitter) == (599.9999999999999, 0.0)
    args = parse(["bench", "--iterations", "10000000", "--sim-runs", "100", "--replan-runs", "100",
                  "--replan-count", "60000"])
    assert (args.iterations, args.sim_runs, args.replan_runs, args.replan_count) == (10_000_000, 100, 100, 60_000)
    args = parse(["bench", "--iterations", "9999999", "--sim-runs", "0", "--replan-runs", "99", "--replan-count", "1"])
    assert (args.iterations, args.sim_runs, args.replan_runs, args.replan_count) == (9_999_999, 0, 99, 1)


def test_a_crowd_time_limit_too_short_for_a_scenario_names_the_option(capsys, tmp_path):
    """Within (0, 600] but shorter than 10 control periods of tiny.yaml (0.1 s): refused before any
    episode runs, naming the file and --time-limit; no output."""
    out = tmp_path / "crowd"
    argv = ["experiment", "crowd", "--scenarios", str(_TINY), "--episodes", "1", "--variants", "plan_once",
            "--out", str(out)]
    assert main([*argv, "--time-limit", "0.05"]) == 2
    err = capsys.readouterr().err
    assert err == (f"drake-social: error: {_TINY}: the crowd study's time_limit (--time-limit) must be >= 10 * "
                   "execution.control_period 0.01 = 0.1 s (a run lasts at least 10 control periods: the sequencer "
                   "decides once per period), got 0.05\n")
    assert not out.exists()


def test_the_bounds_are_stated_in_the_help(capsys):
    from drake_social.cli import MAX_BENCH_REPEATS, MAX_BENCH_SEEDS, MAX_WORKERS

    assert (MAX_BENCH_SEEDS, MAX_BENCH_REPEATS, MAX_WORKERS) == (10_000, 100, 64)
    assert main(["bench", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "seeds 0..N-1 per planner, at most 10,000" in text and "(at most 100)" in text
    assert main(["experiment", "sweep", "--help"]) == 0
    assert "parallel worker processes, at most 64" in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("command", [["show"], ["plan"], ["simulate"]])
def test_an_out_that_is_not_a_folder_names_the_option(tmp_path, capsys, command):
    """An output that cannot be written (exit 1), named as the option's fault."""
    assert main([*command, str(_TINY), "--out", "/dev/null"]) == 1
    assert capsys.readouterr().err == ("drake-social: error: /dev/null: --out must be a folder (its outputs are written "
                                       "inside it); it is a character device\n")
    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    assert main([*command, str(_TINY), "--out", str(plain / "sub")]) == 1
    assert capsys.readouterr().err == (f"drake-social: error: {plain / 'sub'}: --out must be a folder (its outputs are "
                                       f"written inside it); {plain} is a file\n")


@pytest.mark.parametrize("command", [["show"], ["plan"], ["simulate"]])
def test_an_out_through_a_link_to_nothing_names_the_link(tmp_path, capsys, command):
    """A dangling symbolic link as --out (or as a folder above it) is named,
    not reported as 'File exists' (exit 1)."""
    link = tmp_path / "out"
    link.symlink_to(tmp_path / "gone")
    assert main([*command, str(_TINY), "--out", str(link)]) == 1
    assert capsys.readouterr().err == (f"drake-social: error: {link}: --out must be a folder (its outputs are written "
                                       f"inside it); it is a symbolic link to {tmp_path / 'gone'}, which does not "
                                       "exist\n")
    assert main([*command, str(_TINY), "--out", str(link / "sub")]) == 1
    assert capsys.readouterr().err == (f"drake-social: error: {link / 'sub'}: --out must be a folder (its outputs are "
                                       f"written inside it); {link} is a symbolic link to {tmp_path / 'gone'}, which "
                                       "does not exist\n")
    assert not (tmp_path / "gone").exists()


def test_an_experiment_out_that_is_a_file_is_refused_before_any_run(tmp_path, capsys):
    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    assert main(["experiment", "sweep", str(tmp_path / "none.yaml"), "--out", str(plain)]) == 1
    assert capsys.readouterr().err == (f"drake-social: error: {plain}: --out must be a folder (its outputs are written "
                                       f"inside it); it is a file\n")


def test_a_long_argument_is_not_repeated_whole(capsys):
    for text in ("x" * 5000, "9" * 5000, "1" * 100):
        assert main(["experiment", "paper", "--runs", text]) == 2
        err = capsys.readouterr().err.splitlines()[-1]
        assert len(err) < 250 and err.endswith("characters)"), err


def test_a_long_api_argument_is_not_repeated_whole():
    from drake_social.arguments import require_choice

    with pytest.raises(ValueError) as info:
        require_choice("x" * 5000, "make_checker", "kind", ("planar", "drake"))
    assert str(info.value) == (f"make_checker: unknown kind {repr('x' * 5000)[:80]}... (5,002 characters); allowed: "
                               f"planar, drake")


def test_plan_checks_the_scenario_with_the_chosen_algorithm(tmp_path, capsys):
    """--algorithm replaces planner.algorithm: the scenario is validated with it, the option named."""
    sets = ["planner: {informed_mode: admissible}", "social: {length_weight: 0}"]
    argv = ["plan", str(_TINY), "--set", sets[0], "--set", sets[1], "--algorithm", "informed_social_rrt_star",
            "--iterations", "20", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert capsys.readouterr().err == (f"drake-social: error: {_TINY} (--algorithm and --iterations): "
                                       "planner.informed_mode: 'admissible' needs social.length_weight > 0\n")
    assert not (tmp_path / "o").exists()
