"""The validity-checker protocol the planners use (implemented in numpy and in Drake),
and the :class:`Contact` a checker reports."""

from __future__ import annotations

import dataclasses as dc
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np

__all__ = ["CompiledSceneChecker", "Contact", "Grid", "PlanarScene", "ValidityChecker"]


@runtime_checkable
class ValidityChecker(Protocol):
    """Answers whether configurations and straight motions are collision-free.

    Configurations are ``q = [x, y, psi1, psi2]`` (metres, radians); a motion
    is the straight line ``(1 - t) q_a + t q_b``, t in [0, 1]. A valid
    configuration keeps the base, the links and the object clear of obstacles,
    people and walls, inside the joint limits.
    """

    def is_valid(self, q: np.ndarray) -> bool:
        """One configuration (4,)."""

    def are_valid(self, qs: np.ndarray) -> np.ndarray:
        """Many configurations (N, 4) -> (N,) bool."""

    def is_motion_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """The straight motion from q_a to q_b, ends included."""

    def are_motions_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Many motions (E, 4), (E, 4) -> (E,) bool."""

    def clearance(self, q: np.ndarray) -> float:
        """Signed distance (metres) from the robot and object to the nearest
        obstacle, person or wall; negative when penetrating."""


@dc.dataclass(frozen=True)
class Contact:
    """A robot body touching or penetrating an environment shape.

    Attributes:
        robot_body: ``base``, ``link1``, ``link2`` or ``object``.
        other: the environment shape (``obstacle[i]``, ``person[i] 'name'``,
            ``wall_<side>``, or ``map[j], the box of world.map ... over image
            rows ..., columns ... (x .. m, y .. m)``).
        distance: their signed distance, metres (<= 0).
    """

    robot_body: str
    other: str
    distance: float

    def __str__(self) -> str:
        return f"{self.robot_body} with {self.other} ({self.distance:+.3f} m)"


class Grid(NamedTuple):
    """A uniform grid over the environment's shapes (built by
    :func:`drake_social.collision.broadphase.build_grid`, which describes it):
    cell ``c = i + j nx`` lists the shapes ``items[start[c] : start[c + 1]]``."""

    header: np.ndarray  #: (4,) float ``[x0, y0, cell, pad]``: the lower corner, the cell side and the padding, metres
    dims: np.ndarray  #: (2,) int64 ``[nx, ny]`` cells
    start: np.ndarray  #: (nx ny + 1,) int64 each cell's first entry in items
    items: np.ndarray  #: (M,) int64 environment row indices, ascending within each cell


class PlanarScene(NamedTuple):
    """A checker's geometry as the arrays of :mod:`drake_social.collision.planar_kernel`
    (formats there), which compiled planners call directly."""

    lower: np.ndarray  #: (4,) float configuration limits (metres, radians)
    upper: np.ndarray
    bodies: np.ndarray  #: (B, 6) float the planar chain
    robot: np.ndarray  #: (S, 6) float the robot's capsules in their body frames
    env: np.ndarray  #: (K, 8) float the environment's boxes and discs
    levers: np.ndarray  #: (S, 2) float each capsule's lever arms, metres
    grid: Grid  #: the broadphase over env


@runtime_checkable
class CompiledSceneChecker(ValidityChecker, Protocol):
    """The capability of a checker whose answers are exactly those of the
    planar kernel on its :meth:`compiled_scene`: a compiled planner may then
    check configurations and motions itself, without calling the checker."""

    def compiled_scene(self) -> PlanarScene:
        """The scene, C-contiguous float64 arrays."""
