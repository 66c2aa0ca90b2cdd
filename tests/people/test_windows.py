"""Windows of a recording and the flow's axis (drake_social.people.windows), against hand counts and angles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.errors import ScenarioError
from drake_social.people.eth_ucy import parse_eth_ucy
from drake_social.people.windows import (MAX_GRID_SAMPLES, crossing_rotation, cut_windows, flow_angle, frame_step,
                                         presence_counts)


def recording(spans: dict[int, tuple[int, int]], step: int = 10, name: str = "rec.txt"):
    """A recording whose id i has a row every ``step`` frames from spans[i][0] to spans[i][1] (inclusive)."""
    lines = [f"{f}\t{i}\t{float(i)}\t{f / 100}" for i, (a, b) in spans.items() for f in range(a, b + 1, step)]
    lines.sort(key=lambda line: float(line.split()[0]))
    return parse_eth_ucy("\n".join(lines) + "\n", name)


# Frames 0..200 every 10 (0.4 s at 25 fps): id 1 throughout, id 2 at frames 0..40, id 3 at 100..200, id 4 at
# 120..160. Present per sample: 2 (frames 0-40), 1 (50-90), 2 (100, 110), 3 (120-160), 2 (170-200).
FOUR = {1: (0, 200), 2: (0, 40), 3: (100, 200), 4: (120, 160)}


def test_presence_on_the_frame_grid_by_hand():
    dut = recording(FOUR)
    assert frame_step(dut) == 10.0
    grid, counts = presence_counts(dut)
    np.testing.assert_array_equal(grid, np.arange(0, 201, 10))
    assert counts.tolist() == [2] * 5 + [1] * 5 + [2, 2] + [3] * 5 + [2] * 4


def test_the_densest_windows_first_then_in_time_order():
    # 2 s windows hold 6 samples (50 frames). Sums of the 16 starts 0..150 by hand: the densest is 17 at
    # frames 110 (and 120: the earlier wins); it blocks every start in (60, 160) frames; of the rest the
    # densest is frame 0 (2+2+2+2+2+1 = 11).
    dut = cut_windows(recording(FOUR), fps=25.0, length=2.0, count=2, min_people=1)
    assert [(w.index, w.start, w.end, w.samples) for w in dut] == [(0, 0.0, 2.0, 6), (1, 4.4, 6.4, 6)]
    assert (dut[1].people_mean, dut[1].people_min, dut[1].people_max, dut[1].people_t0) == (17 / 6, 2, 3, 2)
    assert (dut[0].people_mean, dut[0].people_min, dut[0].people_max, dut[0].people_t0) == (11 / 6, 1, 2, 2)
    # One window: the densest alone.
    assert [w.start for w in cut_windows(recording(FOUR), fps=25.0, length=2.0, count=1, min_people=1)] == [4.4]


def test_fewer_windows_than_asked_is_refused_with_the_options():
    # After frames 110 and 0, windows may touch: frame 60 (60..110, 8) fits between them; nothing else does.
    assert [w.start for w in cut_windows(recording(FOUR), fps=25.0, length=2.0, count=3, min_people=1)] == \
        [0.0, 2.4, 4.4]
    with pytest.raises(ScenarioError) as info:
        cut_windows(recording(FOUR), fps=25.0, length=2.0, count=4, min_people=1,
                    options={"count": "--windows", "length": "--window-length", "min_people": "--min-people"})
    assert str(info.value) == ("rec.txt: --windows 4: the recording has 3 windows of 2 s that do not overlap with "
                               "--min-people 1 people present on average (chosen densest first); lower --windows, "
                               "--min-people or --window-length")


@pytest.mark.parametrize("min_people, ok", [(1, True), (2, True), (3, False)])
def test_the_people_threshold_holds_exactly(min_people, ok):
    """Two people present throughout: every window's mean is exactly 2 (compared in integers)."""
    flat = recording({1: (0, 100), 2: (0, 100)})
    if ok:
        assert cut_windows(flat, fps=25.0, length=2.0, count=1, min_people=min_people)[0].people_mean == 2.0
    else:
        with pytest.raises(ScenarioError, match=r"^rec\.txt: no window of 2 s has min_people 3 people present on "
                                                r"average; the densest has 2: lower min_people or length$"):
            cut_windows(flat, fps=25.0, length=2.0, count=1, min_people=min_people)


@pytest.mark.parametrize("length, ok", [(8.0, True), (8.0 * (1 + 1e-6), False)])
def test_a_recording_shorter_than_one_window_is_refused(length, ok):
    """FOUR spans frames 0..200: 8 s at 25 fps; a window of exactly 8 s is the whole recording."""
    if ok:
        (w,) = cut_windows(recording(FOUR), fps=25.0, length=length, count=1, min_people=1)
        assert (w.start, w.samples, w.people_max) == (0.0, 21, 3)
    else:
        with pytest.raises(ScenarioError) as info:
            cut_windows(recording(FOUR), fps=25.0, length=length, count=1, min_people=1,
                        options={"length": "--window-length"})
        assert str(info.value) == ("rec.txt: the recording spans 8 s (t = 0 .. 8 s): shorter than one window; "
                                   "--window-length must be at most 8 s, got 8.00001")


def test_frames_need_not_start_at_zero_nor_be_whole():
    # ETH's frames start at 780; a start time is frame / fps.
    dut = cut_windows(recording({1: (780, 980), 2: (880, 980)}), fps=25.0, length=4.0, count=1, min_people=1)
    assert (dut[0].start, dut[0].end, dut[0].people_mean) == (35.2, 39.2, 2.0)


@pytest.mark.parametrize("steps, angle", [
    ([(1.0, 0.0), (-2.0, 0.0)], 0.0),                  # both ways along x: the axis is x
    ([(0.0, 1.0), (0.0, -0.5)], math.pi / 2),          # along y (pi/2, not -pi/2: in (-pi/2, pi/2])
    ([(1.0, 1.0)], math.pi / 4), ([(-1.0, -1.0)], math.pi / 4), ([(1.0, -1.0)], -math.pi / 4),
    # Each step counts with its length: (1, 0) and (0, 3): c = 1/1 - 9/3 = -2, s = 0 -> the y axis.
    ([(1.0, 0.0), (0.0, 3.0)], math.pi / 2), ([(3.0, 0.0), (0.0, 1.0)], 0.0),
    # (2, 0) and (0, 1) at 45 degrees: c = 2 - 1 = 1, s = 0 ... and (1, 1): c = 0, s = 2 / sqrt(2).
    ([(2.0, 0.0), (0.0, 1.0), (1.0, 1.0)], 0.5 * math.atan2(math.sqrt(2), 1.0)),
    ([], 0.0), ([(0.0, 0.0)], 0.0), ([(1.0, 0.0), (0.0, 1.0)], 0.0),  # nobody moves, or the steps cancel
])
def test_the_flow_axis_by_hand(steps, angle):
    assert flow_angle(np.array(steps, float).reshape(-1, 2)) == pytest.approx(angle, abs=1e-15)


@pytest.mark.parametrize("angle, rotation", [(0.0, math.pi / 2), (math.pi / 2, 0.0), (math.pi / 4, math.pi / 4),
                                             (-math.pi / 4, 3 * math.pi / 4), (-math.pi / 2 + 1e-9, math.pi - 1e-9)])
def test_the_turn_puts_the_flow_on_the_y_axis(angle, rotation):
    dut = crossing_rotation(angle)
    assert dut == pytest.approx(rotation, abs=1e-15) and 0.0 <= dut < math.pi
    c, s = math.cos(dut), math.sin(dut)
    d = np.array([math.cos(angle), math.sin(angle)])
    assert c * d[0] - s * d[1] == pytest.approx(0.0, abs=1e-9)  # the flow's direction turned has no x


@pytest.mark.parametrize("last, ok", [(MAX_GRID_SAMPLES - 1, True), (MAX_GRID_SAMPLES, False)])
def test_the_sample_grid_is_bounded(last, ok):
    """Id 1 steps one frame; id 2 stands alone at frame ``last``: the grid holds last + 1 samples."""
    dut = parse_eth_ucy(f"0 1 0.0 0.0\n1 1 0.5 0.0\n{last} 2 1.0 1.0\n", "far.txt")
    if ok:
        grid, counts = presence_counts(dut)
        assert len(grid) == MAX_GRID_SAMPLES and counts[:3].tolist() == [1, 1, 0] and counts[-1] == 1
    else:
        with pytest.raises(ScenarioError, match=r"^far\.txt: frames 0 \.\. 4e\+06 in steps of 1 are 4,000,001 "
                                                r"samples; a recording may span at most 4,000,000 of its steps$"):
            presence_counts(dut)
