"""Drawing the mobile manipulator: base disc, both links, the object and its
interest points, for one configuration ``q = [x, y, psi1, psi2]``."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Polygon

from drake_social.kinematics import ArmGeometry

__all__ = ["RobotStyle", "capsule_outline", "draw_robot"]


@dc.dataclass(frozen=True)
class RobotStyle:
    """Colours of the robot's parts (the paper's figures: dark blue base,
    yellow link 1, orange link 2, light-blue object)."""

    base: str = "#1f3b73"
    link1: str = "#f5c518"
    link2: str = "#f28c28"
    object: str = "#6ec6f2"
    edge: str = "#101010"
    interest: str = "white"


def capsule_outline(a: np.ndarray, b: np.ndarray, radius: float, arc_points: int = 11) -> np.ndarray:
    """The outline (2 * arc_points, 2) of the capsule of axis a-b and given
    radius, metres: two half circles joined by straight sides (an odd
    ``arc_points`` puts a vertex exactly on each tip)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    heading = np.arctan2(d[1], d[0]) if np.hypot(d[0], d[1]) > 0 else 0.0
    arc = np.linspace(-np.pi / 2, np.pi / 2, arc_points)
    around_b = b + radius * np.stack([np.cos(heading + arc), np.sin(heading + arc)], -1)
    around_a = a + radius * np.stack([np.cos(heading + np.pi + arc), np.sin(heading + np.pi + arc)], -1)
    return np.concatenate([around_b, around_a])


def draw_robot(
    ax: Axes,
    geometry: ArmGeometry,
    q: np.ndarray,
    *,
    style: RobotStyle = RobotStyle(),
    alpha: float = 1.0,
    interest_points: bool = True,
    labels: bool = False,
    zorder: float = 5.0,
) -> dict[str, list]:
    """Draws the robot and its object at one configuration.

    Capsules are drawn at their true size (link width, object thickness) with
    a thin outline so that thin parts stay visible on large maps.

    Args:
        ax: the axes to draw on (world metres).
        geometry: the robot and object dimensions.
        q: the configuration (4,): base x, y (metres), psi1, psi2 (radians).
        style: colours of the parts.
        alpha: opacity of every part, e.g. < 1 for intermediate poses.
        interest_points: mark the social-cost interest points.
        labels: give the parts legend labels ("robot base", "link 1", ...).
        zorder: drawing order of the base; the arm and object go above it.

    Returns:
        Artists by part: "base", "link1", "link2", "object", "interest".
    """
    q = np.asarray(q, dtype=float)
    if q.shape != (4,):
        raise ValueError(f"q must be one configuration [x, y, psi1, psi2], got shape {q.shape}")
    out: dict[str, list] = {"base": [], "link1": [], "link2": [], "object": [], "interest": []}

    def label(text: str) -> str | None:
        return text if labels else None

    # Patches go in with add_artist and the data limits get the outlines' points
    # once: add_patch would walk every patch's Bezier curves (a third of a map's cost).
    r = geometry.base_radius
    base = Circle((q[0], q[1]), r, facecolor=style.base, edgecolor=style.edge,
                  linewidth=0.8, alpha=alpha, zorder=zorder, label=label("robot base"))
    out["base"].append(ax.add_artist(base))
    extent = [q[:2] - r, q[:2] + r]
    segments = geometry.segments(q)
    radii = geometry.segment_radii
    parts = [("link1", style.link1, "link 1"), ("link2", style.link2, "link 2")]
    parts += [("object", style.object, "object")] * (len(segments) - 2)
    for s, (part, color, text) in enumerate(parts):
        outline = capsule_outline(segments[s, 0], segments[s, 1], radii[s])
        extent += [outline.min(0), outline.max(0)]
        # The object is drawn above the links, as it is held above them.
        patch = Polygon(outline, closed=True, facecolor=color, edgecolor=style.edge, linewidth=0.5, alpha=alpha,
                        zorder=zorder + (1.0 if part == "link1" else 1.1 if part == "link2" else 1.2),
                        label=label(text) if s < 3 else None)
        out[part].append(ax.add_artist(patch))
    ax.update_datalim(np.array(extent))
    if interest_points:
        pts = geometry.interest_points(q)
        (line,) = ax.plot(pts[:, 0], pts[:, 1], linestyle="none", marker="o", markersize=3.5,
                          markerfacecolor=style.interest, markeredgecolor=style.edge, markeredgewidth=0.7,
                          alpha=alpha, zorder=zorder + 1.5, label=label("interest points"))
        out["interest"].append(line)
    return out
