"""drake_social.viz.study and the study report's boxplot rule: what is drawn,
what is left out, and that every label stays readable."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.lines import Line2D

from drake_social.experiments.study.report import OFF_SCALE_FACTOR, axis_stretch, boxplot_values
from drake_social.viz.study import boxplot_figure, paths_side_by_side


def _records(group: str, costs: dict[str, list[float]], failed: int = 0) -> list[dict]:
    out = [{"group": group, "algorithm": a, "success": True, "F_multi": float(v)} for a, vs in costs.items() for v in vs]
    out += [{"group": group, "algorithm": a, "success": False, "F_multi": 1e9} for a in costs for _ in range(failed)]
    return out


def _lobby_costs() -> dict[str, list[float]]:
    """A 10-person lobby: the social planners span 20-92, RRT*'s median is 55.9."""
    return {
        "rrt_star": [41.0, 48.5, 55.9, 61.2, 70.3],
        "social_rrt_star": [20.0, 24.0, 31.5, 44.0, 92.0],
        "base_rrt_star": [26.0, 35.0, 40.0, 52.0, 60.0],
    }


def test_rrt_star_is_shown_when_it_fits_the_others_axis():
    costs = _lobby_costs()
    values, note = boxplot_values(_records("lobby", costs, failed=2), "lobby", list(costs))
    assert note is None
    assert list(values) == ["rrt_star", "social_rrt_star", "base_rrt_star"]
    assert values["rrt_star"] == costs["rrt_star"]  # failed runs are not drawn
    # The axis stays 20-92 (72) against the others' size 92.
    assert axis_stretch(costs["rrt_star"], costs["social_rrt_star"] + costs["base_rrt_star"]) == pytest.approx(72 / 92)


def test_rrt_star_is_left_out_only_beyond_the_stated_stretch():
    costs = _lobby_costs()
    others = costs["social_rrt_star"] + costs["base_rrt_star"]  # range 20-92 (72), largest 92: size 92
    # RRT* reaching 20 + 92 * 3 = 296 stretches the axis exactly 3x: still shown.
    costs["rrt_star"] = [100.0, 150.0, 20.0 + 92.0 * OFF_SCALE_FACTOR]
    assert axis_stretch(costs["rrt_star"], others) == pytest.approx(OFF_SCALE_FACTOR)
    values, note = boxplot_values(_records("lobby", costs), "lobby", list(costs))
    assert note is None and "rrt_star" in values
    # Beyond it (the axis would be 20-2000: 1980 / 92 = 21.5x): left out, and the note says why with the median.
    costs["rrt_star"] = [900.0, 1500.0, 2000.0]
    values, note = boxplot_values(_records("lobby", costs), "lobby", list(costs))
    assert list(values) == ["social_rrt_star", "base_rrt_star"]
    assert note == ("RRT* not shown: its median F = 1500; its runs would stretch the axis 21.5x the others' "
                    "size (range 20 to 92; shown up to 3x)")


@pytest.mark.parametrize("rrt, others", [
    ([16.6], [10.3]),                 # runs: 1, two algorithms: an axis 10.3-16.6
    ([2.5], [1.0]),                   # one other run at 1.0: an axis 1-2.5
    ([16.6], [10.3, 10.3, 10.3]),     # equal runs of the others
    ([40.0, 41.0], [10.0, 10.5, 11.0]),  # the others nearly equal: an axis 10-41
    ([3.0], [0.0, 0.0]),              # the others all 0: drawn at 0 on any axis
    ([-1.0], [-2.0, -2.0]),           # negative values: an axis -2 to -1
])
def test_rrt_star_is_shown_when_the_combined_axis_is_readable(rrt, others):
    costs = {"rrt_star": rrt, "social_rrt_star": others}
    values, note = boxplot_values(_records("g", costs), "g", list(costs))
    assert note is None and values["rrt_star"] == rrt
    assert axis_stretch(rrt, others) <= OFF_SCALE_FACTOR


@pytest.mark.parametrize("rrt, others, note", [
    ([1500.0], [10.0, 10.0], "RRT* not shown: its median F = 1500; its runs would stretch the axis 149x the "
                              "others' size (runs all at 10; shown up to 3x)"),
    ([30.0], [-2.0, -1.0], "RRT* not shown: its median F = 30; its runs would stretch the axis 16x the "
                            "others' size (range -2 to -1; shown up to 3x)"),
    ([500.0], [10.0, 10.0001], "RRT* not shown: its median F = 500; its runs would stretch the axis 49x the "
                                "others' size (runs all near 10; shown up to 3x)"),
])
def test_note_names_the_others_runs_without_degenerate_ranges(rrt, others, note):
    costs = {"rrt_star": rrt, "social_rrt_star": others}
    values, got = boxplot_values(_records("g", costs), "g", list(costs))
    assert list(values) == ["social_rrt_star"] and got == note


def test_axis_stretch_edges():
    assert axis_stretch([5.0], []) == 1.0 and axis_stretch([], [5.0]) == 1.0
    assert axis_stretch([None, float("nan")], [1.0, 2.0]) == 1.0
    # Equal other values: their size is their magnitude (50 beside 52 or 100 fits, 250 does not).
    assert axis_stretch([52.0], [50.0, 50.0]) == pytest.approx(2.0 / 50.0)
    assert axis_stretch([100.0], [50.0, 50.0]) == pytest.approx(1.0)
    assert axis_stretch([250.0], [50.0, 50.0]) == pytest.approx(4.0)
    assert axis_stretch([0.0], [0.0]) == 1.0 and axis_stretch([1.0], [0.0]) == 1.0


def _markers(ax) -> int:
    """Marker points drawn on the axes (lines with a marker and visible data)."""
    return sum(len(line.get_xdata()) for line in ax.get_lines()
               if line.get_marker() not in (None, "", "None", " ") and line.get_visible())


def test_boxplot_draws_each_run_once_outliers_included():
    rng = np.random.default_rng(3)
    values = {"a": list(rng.normal(30, 2, 25)) + [80.0, -20.0],  # two far outliers
              "b": list(rng.normal(40, 2, 12)) + [None, float("nan")],  # left out: not runs
              "c": []}
    fig = boxplot_figure(values, title="t", ylabel="F")
    ax = fig.axes[0]
    assert _markers(ax) == 27 + 12
    dots = [line for line in ax.get_lines() if line.get_marker() == "o"]
    drawn = np.sort(np.concatenate([np.asarray(line.get_ydata(), float) for line in dots]))
    expected = np.sort([v for vs in values.values() for v in vs if v is not None and np.isfinite(v)])
    np.testing.assert_array_equal(drawn, expected)


def _text_boxes(fig) -> list[tuple[object, object, object]]:
    """(axes or None, text artist, its rendered box) of every visible non-empty text."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    out = [(None, t, t.get_window_extent(renderer)) for t in fig.texts if t.get_visible() and t.get_text()]
    if fig._suptitle is not None:
        out.append((None, fig._suptitle, fig._suptitle.get_window_extent(renderer)))
    for ax in fig.axes:
        texts = [ax.xaxis.label, ax.yaxis.label, ax.title]
        for axis in (ax.xaxis, ax.yaxis):  # the tick labels drawn: those of ticks within the view
            lo, hi = sorted(axis.get_view_interval())
            texts += [tick.label1 for tick in axis.get_major_ticks() if lo <= tick.get_loc() <= hi]
        for t in texts:
            if t.get_visible() and t.get_text():
                out.append((ax, t, t.get_window_extent(renderer)))
    return out


def test_paths_side_by_side_labels_inside_the_figure_and_off_the_other_maps(tiny_scenario):
    wp = np.array([tiny_scenario.start, [3.0, 2.5, 0.5, 1.5], tiny_scenario.goal], float)
    fig = paths_side_by_side(tiny_scenario, {"rrt_star: F = 12.3": wp, "social_rrt_star: F = 8.1": wp,
                                             "base_rrt_star: no path": np.zeros((0, 4))}, title="tiny: best paths")
    FigureCanvasAgg(fig)
    boxes = _text_boxes(fig)
    assert len(fig.axes) == 3
    labels = [t.get_text() for ax, t, _ in boxes if ax is not None and t is ax.yaxis.label]
    assert labels == ["y [m]"]  # once, on the left map: the maps share their y axis
    fig_box = fig.bbox
    for owner, text, box in boxes:
        inside = (box.x0 >= fig_box.x0 - 0.5 and box.x1 <= fig_box.x1 + 0.5
                  and box.y0 >= fig_box.y0 - 0.5 and box.y1 <= fig_box.y1 + 0.5)
        assert inside, f"{text.get_text()!r} is clipped: {box} outside the figure {fig_box}"
        for ax in fig.axes:
            if ax is owner:
                continue
            assert not box.overlaps(ax.get_window_extent()), (
                f"{text.get_text()!r} of another panel is drawn over the map {ax.get_title()!r}")


def test_boxplot_labels_and_note_inside_the_figure():
    values = {f"informed_social_rrt_star_{k}": [1e4 * k + 1.0, 2e4 * k + 3.0] for k in range(5)} | {"empty": []}
    fig = boxplot_figure(values, title="a long title: final cost F(q_end), all interest points, 20 runs of K = 2000",
                         ylabel="F(q_end)  (weights 1 on every point)", note="RRT* not shown: " + "x" * 60)
    FigureCanvasAgg(fig)
    for _, text, box in _text_boxes(fig):
        assert fig.bbox.x0 - 0.5 <= box.x0 and box.x1 <= fig.bbox.x1 + 0.5, f"{text.get_text()!r} is clipped"
        assert fig.bbox.y0 - 0.5 <= box.y0 and box.y1 <= fig.bbox.y1 + 0.5, f"{text.get_text()!r} is clipped"


def _assert_inside(fig) -> None:
    for _, text, box in _text_boxes(fig):
        assert fig.bbox.x0 - 0.5 <= box.x0 and box.x1 <= fig.bbox.x1 + 0.5, f"{text.get_text()!r} is clipped: {box}"
        assert fig.bbox.y0 - 0.5 <= box.y0 and box.y1 <= fig.bbox.y1 + 0.5, f"{text.get_text()!r} is clipped: {box}"


_LONG_GROUP = "office_bar-" + "very_long_variant_name_" * 4 + "x" * 8  # 111 characters, no space


@pytest.mark.parametrize("algorithms", [["social_rrt_star", "base_rrt_star"],
                                        ["social_rrt_star", "informed_social_rrt_star", "informed_base_rrt_star"]])
@pytest.mark.parametrize("group", ["office_bar, paper", _LONG_GROUP])
def test_boxplot_with_few_algorithms_fits_title_note_and_ticks(algorithms, group):
    costs = {a: [10.0 + k, 12.0 + k, 15.0 + k] for k, a in enumerate(algorithms)}
    costs["rrt_star"] = [1e5]
    values, note = boxplot_values(_records(group, costs), group, ["rrt_star"] + algorithms)
    assert note is not None and len(note) > 100
    title = f"{group}: final cost F(q_end), all interest points, 20 runs of K = 2000"
    fig = boxplot_figure(values, title=title, ylabel="F(q_end)  (weights 1 on every point)", note=note)
    FigureCanvasAgg(fig)
    _assert_inside(fig)
    ax = fig.axes[0]
    drawn = fig.texts[0].get_text()
    assert drawn.replace("\n", " ") == note  # wrapped, nothing left out
    assert ax.title.get_text().replace("\n", "") .replace(" ", "") == title.replace(" ", "")
    renderer = fig.canvas.get_renderer()  # the note and the title clear of the axes and the tick labels
    note_box, title_box = fig.texts[0].get_window_extent(renderer), ax.title.get_window_extent(renderer)
    assert title_box.y0 >= ax.get_window_extent().y1
    ticks = [t.label1.get_window_extent(renderer) for t in ax.xaxis.get_major_ticks()]
    assert all(note_box.y1 <= b.y0 for b in ticks)
    assert not any(a.overlaps(b) for i, a in enumerate(ticks) for b in ticks[i + 1:])


@pytest.mark.slow
def test_study_figure_titles_fit_their_figures(tiny_scenario):
    from drake_social.viz.path import cost_profile_figure

    wp = np.array([tiny_scenario.start, [3.0, 2.5, 0.5, 1.5], tiny_scenario.goal], float)
    long = f"{_LONG_GROUP}: social cost S(q) along the best run of each algorithm (all points)"
    for fig in (cost_profile_figure(tiny_scenario, {"rrt_star": wp, "social_rrt_star": wp}, title=long),
                paths_side_by_side(tiny_scenario, {f"{_LONG_GROUP}: F = 12.3": wp, "b: F = 1": wp},
                                   title=f"{_LONG_GROUP}: best paths " + "and more words " * 8)):
        FigureCanvasAgg(fig)
        _assert_inside(fig)
