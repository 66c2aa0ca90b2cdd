"""The holonomic base: a proportional controller and the mecanum wheel kinematics.

The paper (Section IV-C) drives the base with ``v = Kp (x_next - x_current)``
and four mecanum wheels, ``v_wheels = (1/r) M^T [vx, vy]`` with::

    M = [[ 1, 1, -1, -1],
         [-1, 1,  1, -1]]          (2 x 4)

Since ``M M^T = 4 I``, ``(r/4) M w`` maps wheel speeds back to the base
velocity and is the exact inverse of ``(1/r) M^T`` on its range. The base
rotation is not controlled (the robot keeps its heading), so only ``[vx,
vy]`` appear.

* :func:`mecanum_matrix`, :func:`wheel_speeds`, :func:`base_velocity`,
  :func:`saturate_norm`, :func:`wheel_limited_speed`: pure numpy, vectorised
  over leading axes.
* :class:`HolonomicPController`: target and position in, limited wheel
  speeds and the base velocity they produce out.
* :class:`MecanumDrive`: wheel speeds in, base velocity out (the base that
  moves is driven by the wheels, so a wheel limit really slows it).

Example::

    from drake_social.control import HolonomicPController, MecanumDrive

    dut = HolonomicPController(kp=1.5, max_base_speed=0.5, wheel_radius=0.05, max_wheel_speed=20.0)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("base_target").FixValue(context, [1.0, 0.0])
    dut.GetInputPort("base_position").FixValue(context, [0.9, 0.0])
    print(dut.GetOutputPort("base_velocity").Eval(context))  # [0.15 0.  ]
    print(dut.GetOutputPort("wheel_speeds").Eval(context))   # [ 3.  3. -3. -3.]
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.systems.framework import BasicVector, Context, Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import MatrixGain

from drake_social.arguments import require_execution_options
from drake_social.scenario import ExecutionOptions

__all__ = [
    "HolonomicPController",
    "MecanumDrive",
    "base_velocity",
    "mecanum_matrix",
    "saturate_norm",
    "wheel_limited_speed",
    "wheel_speeds",
]

# M of the paper (2 x 4); rows map the four wheel speeds to vx and vy.
_M = np.array([[1.0, 1.0, -1.0, -1.0], [-1.0, 1.0, 1.0, -1.0]])


def mecanum_matrix() -> np.ndarray:
    """The (4, 2) matrix ``M^T`` of the paper (a fresh copy)."""
    return _M.T.copy()


def wheel_speeds(v_xy, wheel_radius: float) -> np.ndarray:
    """Wheel speeds ``(1/r) M^T v`` (rad/s), shape (..., 4).

    Args:
        v_xy: base velocity ``[vx, vy]`` (m/s), shape (..., 2).
        wheel_radius: r, metres (> 0).
    """
    return np.asarray(v_xy, float) @ _M / wheel_radius


def base_velocity(wheels, wheel_radius: float) -> np.ndarray:
    """Base velocity ``(r/4) M w`` (m/s), shape (..., 2), of wheel speeds ``w``.

    The exact inverse of :func:`wheel_speeds` on its range (``M M^T = 4 I``);
    for other wheel speeds, the least-squares base velocity.

    Args:
        wheels: wheel speeds (rad/s), shape (..., 4).
        wheel_radius: r, metres (> 0).
    """
    return np.asarray(wheels, float) @ _M.T * (wheel_radius / 4.0)


def saturate_norm(v, max_norm: float) -> np.ndarray:
    """``v`` scaled down so that its norm (over the last axis) is at most ``max_norm``.

    The whole vector is scaled, so the direction is kept (clipping each axis
    would bend the path). Vectors already within the bound are returned unchanged.
    """
    v = np.asarray(v, float)
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    scale = np.minimum(1.0, max_norm / np.maximum(norm, np.finfo(float).tiny))
    return v * scale


def wheel_limited_speed(direction, wheel_radius: float, max_wheel_speed: float) -> np.ndarray:
    """The largest base speed (m/s) in ``direction`` that the wheels allow.

    With ``w = (1/r) M^T v`` the largest wheel speed is ``(|vx| + |vy|) / r``,
    so a base moving at speed s along the unit vector u needs ``s (|u_x| +
    |u_y|) / r <= max_wheel_speed``: ``s <= max_wheel_speed r / (|u_x| +
    |u_y|)``, from ``max_wheel_speed r`` along x or y down to ``max_wheel_speed
    r / sqrt(2)`` on a diagonal.

    Args:
        direction: [dx, dy] (any non-zero length), shape (..., 2).
        wheel_radius: r, metres (> 0).
        max_wheel_speed: rad/s (> 0).

    Returns:
        Shape (...); ``inf`` for a zero direction (the base does not move).
    """
    d = np.asarray(direction, float)
    norm = np.linalg.norm(d, axis=-1)
    l1 = np.abs(d).sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(l1 > 0, max_wheel_speed * wheel_radius * norm / np.where(l1 > 0, l1, 1.0), np.inf)


def _positive(name: str, value: float, who: str) -> float:
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{who}: {name} must be a finite number > 0, got {value!r}")
    return float(value)


class HolonomicPController(LeafSystem):
    """Proportional base controller with norm and wheel-speed limits.

    The law, in order:

    1. ``v = v_ff + Kp (target - position)``; the paper writes
       ``Kp (current - next)``, but only ``next - current`` converges (with
       ``x' = v`` the error then decays as ``exp(-Kp t)``). ``v_ff = 0``
       without feed-forward.
    2. ``v`` saturated by its norm to ``max_base_speed`` (direction kept).
    3. ``w = (1/r) M^T v``; if ``max |w_i| > max_wheel_speed``, ``w`` is
       scaled uniformly by ``max_wheel_speed / max |w_i|`` (direction kept).

    While the optional input ``hold`` (1; unconnected = never held) is above
    0.5, the output is zero wheel speeds (the safety monitor's stop).

    Stateless, with direct feedthrough. Input ports ``base_target`` (2, m),
    ``base_position`` (2, m), ``base_velocity_ff`` (2, m/s; only with
    ``feedforward=True``), ``hold`` (1). Output ports ``wheel_speeds`` (4, rad/s) and
    ``base_velocity`` (2, m/s) = ``(r/4) M w``, the velocity the limited
    wheel speeds produce.

    Args:
        kp: proportional gain Kp, 1/s (> 0).
        max_base_speed: largest norm of [vx, vy], m/s (> 0).
        wheel_radius: mecanum wheel radius r, metres (> 0).
        max_wheel_speed: largest wheel speed, rad/s (> 0).
        feedforward: declare ``base_velocity_ff`` and add it to the law.
    """

    def __init__(
        self, *, kp: float, max_base_speed: float, wheel_radius: float, max_wheel_speed: float,
        feedforward: bool = False,
    ):
        super().__init__()
        who = "HolonomicPController"
        self._kp = _positive("kp", kp, who)
        self._max_base_speed = _positive("max_base_speed", max_base_speed, who)
        self._wheel_radius = _positive("wheel_radius", wheel_radius, who)
        self._max_wheel_speed = _positive("max_wheel_speed", max_wheel_speed, who)

        self._target_port = self.DeclareVectorInputPort("base_target", 2)
        self._position_port = self.DeclareVectorInputPort("base_position", 2)
        self._ff_port = self.DeclareVectorInputPort("base_velocity_ff", 2) if feedforward else None
        self._hold_port = self.DeclareVectorInputPort("hold", 1)
        # Outputs depend on the inputs only (not on time): Drake's cache then
        # keeps them across integrator stages while the inputs hold.
        inputs = {self.input_port_ticket(port.get_index())
                  for port in (self._target_port, self._position_port, self._ff_port, self._hold_port)
                  if port is not None}
        self.DeclareVectorOutputPort("wheel_speeds", 4, self._CalcWheelSpeeds, prerequisites_of_calc=inputs)
        self.DeclareVectorOutputPort("base_velocity", 2, self._CalcBaseVelocity, prerequisites_of_calc=inputs)

    @classmethod
    def from_options(cls, execution_options: ExecutionOptions, feedforward: bool = False) -> "HolonomicPController":
        """A controller with the gain and limits of a scenario's ``execution`` section."""
        require_execution_options(execution_options, "HolonomicPController.from_options")
        return cls(
            kp=execution_options.kp,
            max_base_speed=execution_options.max_base_speed,
            wheel_radius=execution_options.wheel_radius,
            max_wheel_speed=execution_options.max_wheel_speed,
            feedforward=feedforward,
        )

    def _LimitedWheelSpeeds(self, context: Context) -> list[float]:
        # The same law as saturate_norm / wheel_speeds, in plain floats: this runs
        # once per control period of every simulation (numpy's per-call cost
        # on 2-vectors was most of it); tests compare the two.
        if self._hold_port.HasValue(context) and self._hold_port.Eval(context)[0] > 0.5:
            return [0.0, 0.0, 0.0, 0.0]
        target = self._target_port.Eval(context)
        position = self._position_port.Eval(context)
        vx = self._kp * (float(target[0]) - float(position[0]))
        vy = self._kp * (float(target[1]) - float(position[1]))
        if self._ff_port is not None:
            ff = self._ff_port.Eval(context)
            vx += float(ff[0])
            vy += float(ff[1])
        norm = math.hypot(vx, vy)
        if norm > self._max_base_speed:
            scale = self._max_base_speed / norm
            vx, vy = vx * scale, vy * scale
        r = self._wheel_radius
        w = [(vx - vy) / r, (vx + vy) / r, (vy - vx) / r, (-vx - vy) / r]  # (1/r) M^T v
        largest = max(abs(w[0]), abs(w[1]))  # |w3| = |w1| and |w4| = |w2|
        if largest > self._max_wheel_speed:
            scale = self._max_wheel_speed / largest
            w = [wi * scale for wi in w]
        return w

    def _CalcWheelSpeeds(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._LimitedWheelSpeeds(context))

    def _CalcBaseVelocity(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(base_velocity(self._LimitedWheelSpeeds(context), self._wheel_radius))


class MecanumDrive(Diagram):
    """Mecanum base kinematics: ``base_velocity = (r/4) M wheel_speeds``.

    Input port ``wheel_speeds`` (4, rad/s), output port ``base_velocity``
    (2, m/s). Stateless, direct feedthrough; integrate the output for the
    base position. A diagram around one ``MatrixGain`` (the map is linear),
    so that it costs nothing in Python at every step of a simulation; the
    same map as :func:`base_velocity`.

    Args:
        wheel_radius: r, metres (> 0).
    """

    def __init__(self, wheel_radius: float):
        super().__init__()
        r = _positive("wheel_radius", wheel_radius, "MecanumDrive")
        builder = DiagramBuilder()
        gain = builder.AddNamedSystem("forward_kinematics", MatrixGain(_M * (r / 4.0)))
        builder.ExportInput(gain.get_input_port(), "wheel_speeds")
        builder.ExportOutput(gain.get_output_port(), "base_velocity")
        builder.BuildInto(self)
        self._wheel_radius = r
