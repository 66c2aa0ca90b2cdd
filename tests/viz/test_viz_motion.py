"""drake_social.viz.motion: the speed, acceleration and jerk of motion.png."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import to_rgba

from drake_social.evaluation.time_series import motion_profile
from drake_social.viz.motion import motion_figure


def _drive():
    """The base along x: 0.5 t^2 for 1 s, then 0.5 + (t - 1) (1 m/s): |a| 1 then 0, a jerk step at 1 s."""
    t = np.linspace(0.0, 3.0, 301)
    x = np.where(t < 1.0, 0.5 * t**2, 0.5 + (t - 1.0))
    return t, np.c_[x, np.zeros_like(x)]


def test_three_panels_of_the_tracks_with_the_limit_and_the_stops():
    t, xy = _drive()
    limit = np.where((t >= 1.5) & (t < 2.5), 0.4, np.inf)
    dut = motion_figure(t, {"base": motion_profile(t, xy)}, speed_limit=limit,
                        stops=[{"start": 2.0, "end": 2.2}], slow_stops=[{"start": 2.4, "end": None}],
                        limits=(0.5, 1.0, 5.0), title="drive")
    speed, accel, jerk = dut.axes
    assert [ax.get_ylabel() for ax in dut.axes] == ["speed (m/s)", "acceleration (m/s^2)", "jerk (m/s^3)"]
    assert jerk.get_yscale() == "log"
    (base, *_), = [[line for line in speed.lines if line.get_label() == "base"]]
    np.testing.assert_allclose(base.get_ydata()[-1], 1.0, rtol=1e-9)  # the speed at the end
    # The limit is drawn where it is in force only.
    (drawn,) = [line for line in speed.lines if line.get_label().startswith("speed limit")]
    y = np.asarray(drawn.get_ydata(), float)
    assert np.all(np.isnan(y[~np.isfinite(limit)])) and np.all(y[np.isfinite(limit)] == 0.4)
    # Shaded in every panel: the limited time (1.5 to 2.5 s), the safety stop and the slow-down stop up to the end.
    for ax in dut.axes:
        spans = [(p.get_x(), p.get_x() + p.get_width(), p.get_facecolor()) for p in ax.patches]
        assert [(a, b) for a, b, _ in spans] == [(1.5, 2.5), (2.4, 3.0), (2.0, 2.2)]
        assert to_rgba(spans[1][2])[:3] != to_rgba(spans[2][2])[:3]
    # The base's limits, dashed.
    assert [line.get_ydata()[0] for ax in dut.axes for line in ax.lines if line.get_label() == "base limit"] == \
        [0.5, 1.0, 5.0]


def test_a_run_without_samples_says_so():
    dut = motion_figure(np.zeros(1), {}, title="none")
    assert "nothing was executed" in [text.get_text() for text in dut.axes[0].texts]
