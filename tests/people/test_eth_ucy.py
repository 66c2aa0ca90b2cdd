"""``people import``: an ETH/UCY recording to a people CSV, against hand values."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from drake_social.errors import ScenarioError
from drake_social.people.eth_ucy import convert, parse_eth_ucy, people_csv_text

# Two pedestrians, frames every 10 (0.4 s at 25 fps), tab-separated as in
# biwi_eth.txt: id 1 walks -x at 1 m per step (2.5 m/s), id 2 walks +y and
# stops between frames 800 and 810; id 3 appears once at frame 820.
ETH = """\
780\t1\t10.0\t2.0
780\t2\t0.0\t0.0
790\t1\t9.0\t2.0
790\t2\t0.0\t0.5
800\t1\t8.0\t2.0
800\t2\t0.0\t1.0
810\t2\t0.0\t1.0
820\t3\t5.0\t5.0
"""


def rows(**options):
    return convert(parse_eth_ucy(ETH, "eth.txt"), **options)


def test_plain_conversion_by_hand():
    """t = (frame - 780) / 25, ids in order of first appearance, theta along the motion."""
    got = rows()
    assert [(t, i) for t, i, *_ in got] == [(0.0, "1"), (0.0, "2"), (0.4, "1"), (0.4, "2"), (0.8, "1"), (0.8, "2"),
                                            (1.2, "2"), (1.6, "3")]
    expected = {(0.0, "1"): (10.0, 2.0, math.pi), (0.4, "1"): (9.0, 2.0, math.pi), (0.8, "1"): (8.0, 2.0, math.pi),
                (0.0, "2"): (0.0, 0.0, math.pi / 2), (0.4, "2"): (0.0, 0.5, math.pi / 2),
                (0.8, "2"): (0.0, 1.0, math.pi / 2),  # (0, 1) - (0, 0.5): still +y
                (1.2, "2"): (0.0, 1.0, math.pi / 2),  # standing: keeps its heading
                (1.6, "3"): (5.0, 5.0, 0.0)}  # one row, never moves: faces +x
    for t, i, x, y, theta in got:
        np.testing.assert_allclose([x, y, theta], expected[(t, i)], rtol=0, atol=1e-15)


def test_rotation_then_offset_and_crop_against_hand_values():
    """--rotate pi/2 maps (x, y) to (-y, x), then --offset (1, -2); the window
    0.4 .. 0.8 s of the recording's time (31.6 .. 32.0 s: frames 790 .. 800)
    re-based to start at t = 0."""
    got = rows(rotate=math.pi / 2, offset=(1.0, -2.0), start=790 / 25, end=800 / 25)
    assert [(t, i) for t, i, *_ in got] == [(0.0, "1"), (0.0, "2"), (0.4, "1"), (0.4, "2")]
    # id 1 at (9, 2), (8, 2) -> (-2, 9), (-2, 8) -> (-1, 7), (-1, 6), walking -y;
    # id 2 at (0, 0.5), (0, 1) -> (-0.5, 0), (-1, 0) -> (0.5, -2), (0, -2), walking -x.
    hand = [(-1.0, 7.0, -math.pi / 2), (0.5, -2.0, math.pi), (-1.0, 6.0, -math.pi / 2), (0.0, -2.0, math.pi)]
    for (_, _, x, y, theta), (hx, hy, ht) in zip(got, hand):
        np.testing.assert_allclose([x, y], [hx, hy], rtol=0, atol=1e-12)
        assert math.isclose(math.remainder(theta - ht, 2 * math.pi), 0.0, abs_tol=1e-12)


def test_a_start_between_frames_rebases_to_the_start():
    """--start 31.5 s: the first kept frame (790 = 31.6 s) is at t = 0.1 s."""
    got = rows(start=31.5, end=31.7, ids=["1"])
    assert len(got) == 1 and got[0][1] == "1"
    assert got[0][0] == pytest.approx(0.1, abs=1e-12) and got[0][2:4] == (9.0, 2.0)


def test_id_selection_and_other_fps():
    got = rows(ids=["2.0"], fps=10.0)  # 2.0 names id 2; t = (frame - 780) / 10
    assert [t for t, *_ in got] == [0.0, 1.0, 2.0, 3.0] and {i for _, i, *_ in got} == {"2"}


def test_layout_xzy_reads_x_and_the_third_coordinate():
    text = "0 7 1.5 9.9 -2.0 0.1 0.0 0.2\n10 7 1.6 9.9 -1.8 0.1 0.0 0.2\n"
    got = convert(parse_eth_ucy(text, "obsmat.txt", "xzy"))
    assert [r[2:4] for r in got] == [(1.5, -2.0), (1.6, -1.8)]
    assert got[1][0] == 0.4


def test_csv_text_exact_numbers_and_optional_theta():
    got = rows(ids=["3"])
    assert people_csv_text(got) == "t,id,x,y,theta\n0.0,3,5.0,5.0,0.0\n"
    assert people_csv_text(got, theta=False) == "t,id,x,y\n0.0,3,5.0,5.0\n"


@pytest.mark.parametrize("text, message", [
    ("", "no rows"),
    ("\n  \n", "no rows"),
    ("0 1 2.0 3.0\n10 1 2.0\n", "line 2: 3 columns"),
    ("0 1 2.0 3.0\n10 1 2.0 3.0 0.1 0.1\n", "line 2: 6 columns, the rows before have 4"),
    ("0 1 2.0 3.0\n10 1 2.0 abc\n", "line 2, column 4: not a number; a recording has numbers only"),
    ("0 1 2.0 nan\n", "line 1, column 4: nan is not finite; values must be finite"),
    ("0 1 2.0 3.0\n10 2 2.0 3.0\n0 1 1.0 3.0\n", "line 3: frame 0 of id 1 does not come after its frame 0 on line 1"),
    ("10 1 2.0 3.0\n10 1 2.5 3.0\n", "line 2: frame 10 of id 1 does not come after"),
    ("-10 1 2.0 3.0\n", "frame -10 is negative"),
])
def test_bad_recordings_are_named_by_line(text, message):
    with pytest.raises(ScenarioError, match=message.replace("(", r"\(")) as e:
        convert(parse_eth_ucy(text, "bad.txt"))
    assert str(e.value).startswith("bad.txt")


@pytest.mark.parametrize("options, message", [
    (dict(ids=["9"]), "id 9 is not in the recording"),
    (dict(ids=["1", "3"], end=32.0), "id 3 has no rows in the window"),
    (dict(start=40.0, end=50.0), "no rows in the window"),
    (dict(start=32.0, end=31.0), "is empty; --start must be before --end"),
    (dict(fps=0.0), "--fps must be a finite number > 0"),
    (dict(rotate=math.inf), "--rotate a finite angle"),
])
def test_bad_options(options, message):
    with pytest.raises(ScenarioError, match=message):
        rows(**options)


def test_unknown_layout():
    with pytest.raises(ScenarioError, match="unknown layout 'yx'; allowed: xy, xzy"):
        parse_eth_ucy(ETH, "eth.txt", "yx")


def test_cli_end_to_end(tmp_path, capsys):
    """main(): the file written atomically (no temporary left), exit 2 for bad input and nothing written."""
    from drake_social.cli import main

    src = tmp_path / "biwi.txt"
    src.write_text(ETH)
    out = tmp_path / "sub" / "people.csv"
    code = main(["people", "import", str(src), "--out", str(out), "--rotate", str(math.pi / 2), "--offset", "1", "-2",
                 "--start", "31.6", "--end", "32", "--ids", "1"])
    assert code == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "t,id,x,y,theta" and len(lines) == 3
    t, i, x, y, theta = lines[2].split(",")
    assert (float(t), i) == (0.4, "1")
    np.testing.assert_allclose([float(x), float(y), float(theta)], [-1.0, 6.0, -math.pi / 2], atol=1e-12)
    assert sorted(p.name for p in out.parent.iterdir()) == ["people.csv"]
    assert "wrote" in capsys.readouterr().out
    before = out.read_text()
    bad = tmp_path / "bad.txt"
    bad.write_text("0 1 2.0 3.0\n10 1 x 3.0\n")
    assert main(["people", "import", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "bad.txt, line 2, column 3: not a number" in err
    assert out.read_text() == before
    assert main(["people", "import", str(tmp_path / "missing.txt"), "--out", str(out)]) == 2
    assert "no such recording file" in capsys.readouterr().err
    assert main(["people", "import", str(src), "--out", str(out), "--ids", "42"]) == 2
    assert "id 42 is not in the recording" in capsys.readouterr().err
    assert main(["people", "import", str(src), "--out", str(out), "--fps", "nan"]) == 2


def test_import_reports_the_span_of_the_rows_when_start_is_before_the_first_row(tmp_path, capsys):
    """--start 30 s is 1.2 s before the first kept row (frame 780: 31.2 s), so
    the rows run from t = 1.2 to t = 2.4 s (frame 810: 32.4 s): 1.2 s."""
    from drake_social.app import run_people_import
    from drake_social.cli import main

    src = tmp_path / "biwi.txt"
    src.write_text(ETH)
    done = run_people_import(file=src, out=tmp_path / "p.csv", start=30.0, end=32.4)
    assert (done.rows, done.id_count) == (7, 2)
    np.testing.assert_allclose([done.first, done.last, done.duration], [1.2, 2.4, 1.2], atol=1e-12)
    assert main(["people", "import", str(src), "--out", str(tmp_path / "q.csv"), "--start", "30", "--end", "32.4"]) == 0
    assert capsys.readouterr().out.strip().endswith("7 rows, 2 people, 1.2 s (t = 1.2 .. 2.4 s)")
    done = run_people_import(file=src, out=tmp_path / "r.csv")  # no --start: the first row at t = 0
    np.testing.assert_allclose([done.first, done.last, done.duration], [0.0, 1.6, 1.6], atol=1e-12)


# ---- times and positions must be finite: a tiny --fps, a far --start or --offset (issue 29, item 9)


def _finite_quotient(frame: int, fps: float) -> bool:
    """Whether the float division frame / fps is finite, from exact arithmetic:
    the quotient rounds to the largest float below MAX + ulp(MAX) / 2 (at the
    midpoint it rounds to even, 2**1024: infinite)."""
    from fractions import Fraction

    top = Fraction(sys.float_info.max) + Fraction(math.ulp(sys.float_info.max)) / 2
    return Fraction(frame) / Fraction(fps) < top


def test_a_fps_that_makes_times_infinite_is_refused_at_its_bound():
    with pytest.raises(ScenarioError) as info:
        rows(fps=1e-320)
    message = str(info.value)
    assert message.startswith("eth.txt: --fps 1e-320 makes frame 820 at t = frame / fps = inf s; times must be "
                              "finite: --fps must be at least ")
    bound = float(message.split("at least ")[1].split(" ")[0])
    # The bound is the smallest fps at which the last frame's time is finite.
    assert _finite_quotient(820, bound) and not _finite_quotient(820, math.nextafter(bound, 0.0))
    dut = rows(fps=bound)
    times = np.array([r[0] for r in dut])
    assert np.isfinite(times).all() and times.max() == (820 - 780) / bound
    with pytest.raises(ScenarioError, match="--fps must be at least"):
        rows(fps=math.nextafter(bound, 0.0))
    with pytest.raises(ScenarioError, match="--fps must be at least"):
        rows(fps=5e-324)


def test_a_start_or_offset_that_makes_times_or_positions_infinite_is_refused():
    huge = parse_eth_ucy("0 1 1e308 0\n10 1 1e308 1\n", "huge.txt")
    with pytest.raises(ScenarioError, match=r"^huge.txt: --offset 1e\+308 0 and --rotate 0 put positions beyond the "
                                            r"finite numbers; positions must be finite$"):
        convert(huge, offset=(1e308, 0.0))
    late = parse_eth_ucy("0 1 0 0\n790 1 1 0\n", "late.txt")
    fps = 790 / 1e308
    with pytest.raises(ScenarioError, match=r"^late.txt: --start -1e\+308 s puts the rows at t = frame / fps - start "
                                            r"beyond the finite numbers; times must be finite$"):
        convert(late, fps=fps, start=-1e308)


def test_cli_refuses_a_tiny_fps_and_writes_nothing(tmp_path, capsys):
    from drake_social.cli import main

    src = tmp_path / "biwi.txt"
    src.write_text(ETH)
    out = tmp_path / "people.csv"
    assert main(["people", "import", str(src), "--out", str(out), "--fps", "1e-320"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"drake-social: error: {src}: --fps 1e-320 makes frame 820 at t = frame / fps = inf s")
    assert len(err.splitlines()) == 1 and not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["biwi.txt"]
