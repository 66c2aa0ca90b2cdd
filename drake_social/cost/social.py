"""The multi-interest-point social cost S(q) and its integral along motions."""

from __future__ import annotations

import numpy as np

from drake_social.cost import kernel, timed_kernel
from drake_social.cost.agf import (PersonalSpace, agf_xy, gaussian, inverse_variances, person_reaches,
                                   speed_scaled_sigmas)
from drake_social.kinematics import ArmGeometry, config_distance, displacement_bound
from drake_social.limits import MAX_MOTION_STEPS
from drake_social.people import PeopleModel, PeopleState, Prediction, people_model
from drake_social.scenario.geometry import arm_geometry

__all__ = ["FIELD_CHUNK_ELEMENTS", "SocialCost", "interpolation_segments"]

#: Largest number of (point, person) values :meth:`SocialCost.field` holds at
#: once (about 2 MB per temporary array); larger grids are evaluated in chunks.
FIELD_CHUNK_ELEMENTS = 1 << 18


def interpolation_segments(max_displacement: np.ndarray, resolution: float) -> np.ndarray:
    """Number of equal steps (>= 1) so that no tracked point moves more than
    ``resolution`` metres per step, given a bound on its total displacement.

    Raises:
        ValueError: a bound is NaN or infinite (a non-finite configuration,
            or ends so far apart that their difference overflows), or a
            motion would need more than ``MAX_MOTION_STEPS`` steps
            (its samples are held in memory).
    """
    bound = np.asarray(max_displacement, dtype=float)
    if not np.all(np.isfinite(bound)):
        raise ValueError(f"motions need finite configurations (and ends whose difference does not overflow); "
                         f"displacement bounds: {bound[~np.isfinite(bound)]}")
    too_long = bound > MAX_MOTION_STEPS * resolution
    if np.any(too_long):
        index = np.flatnonzero(too_long.ravel())
        raise ValueError(
            f"motion {int(index[0])} ({len(index)} in all) is too long to sample: its displacement bound "
            f"{bound.ravel()[index[0]]:.6g} m needs more than {MAX_MOTION_STEPS:,} steps of {resolution} m; "
            "split it into shorter motions"
        )
    return np.maximum(1, np.ceil(bound / resolution - 1e-9)).astype(np.int64)


class SocialCost:
    """``S(q) = sum_i sum_j w_j AGF_i(p_j(q))`` and its motion integral (Msc).

    Args:
        geometry: the robot and its object (gives the interest points p_j).
        people: (H, 3) rows [x, y, theta]; may be empty (the cost is then 0).
        space: AGF variances and threshold.
        weights: (3 + P,) weights w_j >= 0, base first (see
            :attr:`ArmGeometry.interest_names`); None = all ones.
        resolution: largest displacement of any weighted interest point
            between two samples of the trapezoid rule, metres.
        distance_weights: per-coordinate scale of the configuration norm used
            as ``ds`` in the integral (None = the plain norm of the paper).
        sigmas: (H, 3) per-person variances [sigma_h, sigma_s, sigma_r],
            metres (Kirby's speed scaling: :func:`~drake_social.cost.agf.speed_scaled_sigmas`),
            in place of ``space``'s; None = ``space``'s for everyone (the
            threshold is always ``space``'s).
    """

    def __init__(
        self,
        geometry: ArmGeometry,
        people: np.ndarray,
        space: PersonalSpace = PersonalSpace(),
        weights: np.ndarray | None = None,
        resolution: float = 0.1,
        distance_weights: np.ndarray | None = None,
        sigmas: np.ndarray | None = None,
    ):
        n = geometry.num_interest_points
        w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
        if w.shape != (n,):
            raise ValueError(f"weights must have {n} values ({geometry.interest_names}), got {w.shape}")
        if np.any(~np.isfinite(w)) or np.any(w < 0):
            raise ValueError(f"weights must be finite and >= 0, got {w}")
        if not resolution > 0:
            raise ValueError(f"resolution must be > 0, got {resolution}")
        self.geometry = geometry
        self.people = np.asarray(people, dtype=float).reshape(-1, 3)
        if sigmas is not None:
            sigmas = np.asarray(sigmas, dtype=float)
            if sigmas.shape != (len(self.people), 3) or not (np.all(np.isfinite(sigmas)) and np.all(sigmas > 0)):
                raise ValueError(f"sigmas must be ({len(self.people)}, 3) finite values > 0 (metres: sigma_h, "
                                 f"sigma_s, sigma_r per person), got shape {sigmas.shape}")
        #: (H, 3) per-person [sigma_h, sigma_s, sigma_r], or None (``space``'s for everyone).
        self.sigmas = sigmas
        self.space = space
        self.weights = w
        self.resolution = float(resolution)
        self.distance_weights = None if distance_weights is None else np.asarray(distance_weights, float)
        # Only points with a non-zero weight are evaluated (base-only: one point).
        self._active = np.flatnonzero(w > 0)
        self._active_weights = w[self._active]
        # Lever arms of the weighted points: their displacement bound per motion.
        self._lever = geometry.lever(active=self._active)
        self._inverse_variances = tuple(1.0 / (2.0 * v**2) for v in (space.sigma_h, space.sigma_r, space.sigma_s))
        #: "numba": motion costs by the compiled kernel (drake_social.cost.kernel);
        #: "numpy": by the batched numpy code, the reference the kernel is tested against.
        self.backend = "numba" if kernel.AVAILABLE else "numpy"

    @classmethod
    def from_scenario(cls, scenario, weights: np.ndarray | None = None,
                      people: PeopleState | None = None) -> "SocialCost":
        """The scenario's cost; ``weights`` overrides ``scenario.social.weights``.

        Only the people present in ``people`` count (:meth:`PeopleState.visible`);
        with ``social.speed_scaling`` each one's variances follow their speed
        (:func:`~drake_social.cost.agf.speed_scaled_sigmas`: a standing
        person gets sigma_h = 0.5 m), otherwise everyone has ``social.sigma_h``.

        Args:
            people: the people the cost is about; None = the scenario's
                people model at t = 0 (:func:`drake_social.people.people_model`).
        """
        from drake_social.arguments import require_scenario

        require_scenario(scenario, "SocialCost.from_scenario")
        s = scenario.social
        if people is None:
            people = people_model(scenario).state_at(0.0)
        people = people.visible()
        sigmas = speed_scaled_sigmas(people.speeds(), s.side_ratio, s.rear_ratio) if s.speed_scaling else None
        return cls(
            arm_geometry(scenario),
            people.poses(),
            PersonalSpace.from_options(s),
            weights=s.weights if weights is None else weights,
            resolution=s.resolution,
            distance_weights=scenario.planner.distance_weights,
            sigmas=sigmas,
        )

    @classmethod
    def at_time(cls, scenario, t: float, model: PeopleModel | None = None,
                weights: np.ndarray | None = None) -> "SocialCost":
        """The scenario's cost with the people where they are at time ``t``.

        Args:
            t: seconds since the start of the run.
            model: anything with ``state_at(t) -> PeopleState`` (a
                :class:`~drake_social.people.PeopleModel`, a
                :class:`~drake_social.people.PeopleLog` of a run); None = the
                scenario's people model (its crowd open loop, without the robot).
            weights: as in :meth:`from_scenario`.
        """
        model = people_model(scenario) if model is None else model
        return cls.from_scenario(scenario, weights, people=model.state_at(t))

    @classmethod
    def for_prediction(cls, scenario, prediction: Prediction, weights: np.ndarray | None = None) -> "SocialCost":
        """The scenario's cost about the people of ``prediction``, for
        :meth:`timed_motion_cost` (and the tree's compiled loop, through
        :meth:`timed_kernel_args`).

        Its ``people`` are every predicted person at the first sample (t0), in
        the prediction's order, absent ones included, so that the per-person
        parameters (:meth:`person_parameters`) line up with the prediction's
        people: the time-indexed cost reads presence from the prediction at
        each sample, whereas :meth:`motion_cost` (static) would count them all.
        With ``social.speed_scaling`` each one's variances follow their speed
        (``prediction.speeds``, Kirby's scaling by
        :func:`~drake_social.cost.agf.speed_scaled_sigmas`), otherwise
        everyone has ``social.sigma_h``.

        Args:
            weights: as in :meth:`from_scenario`.

        Raises:
            TypeError: ``scenario`` is not a Scenario or ``prediction`` not a Prediction.
        """
        from drake_social.arguments import require_scenario

        require_scenario(scenario, "SocialCost.for_prediction")
        _require_prediction(prediction, "SocialCost.for_prediction")
        s = scenario.social
        sigmas = speed_scaled_sigmas(prediction.speeds, s.side_ratio, s.rear_ratio) if s.speed_scaling else None
        return cls(
            arm_geometry(scenario),
            np.column_stack([prediction.positions[0], prediction.headings[0]]),
            PersonalSpace.from_options(s),
            weights=s.weights if weights is None else weights,
            resolution=s.resolution,
            distance_weights=scenario.planner.distance_weights,
            sigmas=sigmas,
        )

    def with_weights(self, weights: np.ndarray) -> "SocialCost":
        """The same cost with other interest-point weights."""
        return SocialCost(self.geometry, self.people, self.space, weights, self.resolution, self.distance_weights,
                          self.sigmas)

    def person_parameters(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per person (H,) each: the AGF's largest reach (metres) and the
        front, rear and side ``1 / (2 sigma^2)`` (1 / m^2), as the compiled
        kernel takes them (equal rows without per-person variances)."""
        h = len(self.people)
        key = (h, None if self.sigmas is None else self.sigmas.tobytes())
        if getattr(self, "_person_key", None) != key:
            if self.sigmas is None:
                params = (np.full(h, self.space.max_reach), *(np.full(h, v) for v in self._inverse_variances))
            else:
                params = (person_reaches(self.sigmas, self.space.threshold), *inverse_variances(self.sigmas))
            self._person_params, self._person_key = params, key
        return self._person_params

    def _reaches(self):
        """The AGF's reach: a scalar (everyone's) or (H,) per person, metres."""
        return self.space.max_reach if self.sigmas is None else self.person_parameters()[0]

    def _max_reach(self) -> float:
        """The largest reach of anyone's AGF, metres."""
        reach = self._reaches()
        return float(np.max(reach)) if np.ndim(reach) and len(reach) else float(self.space.max_reach)

    def agf_values(self, x: np.ndarray, y: np.ndarray, thresholded: bool = True) -> np.ndarray:
        """Every person's AGF (with their own variances) at world points x, y (...,) -> (..., H)."""
        return agf_xy(x, y, self.people, self.space, thresholded, sigmas=self.sigmas)

    # ---- per configuration ----------------------------------------------------

    def point_costs(self, q: np.ndarray) -> np.ndarray:
        """Unweighted ``sum_i AGF_i(p_j(q))`` for every interest point, (..., 3 + P)."""
        points = self.geometry.interest_points(q)
        return self._people_sum(points[..., 0], points[..., 1])

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """S(q) for q of shape (..., 4); returns shape (...).

        The people's sums are taken as in :meth:`field` (in chunks of
        bounded memory), so a long path's profile in a crowd costs megabytes."""
        q = np.asarray(q, dtype=float)
        if len(self.people) == 0 or len(self._active) == 0:
            return np.zeros(q.shape[:-1])
        x, y = self.geometry.interest_xy(q, self._active)
        # In the memory layout of x, as the sums of one (..., K, H) array
        # would be: the weighted sum over K then runs the same BLAS path.
        sums = np.empty_like(x)
        sums[...] = self._people_sum(x, y)
        return sums @ self._active_weights

    # ---- along motions --------------------------------------------------------

    def segments(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Trapezoid steps per motion: no weighted point moves > resolution per step."""
        dq = np.asarray(q_b, float) - np.asarray(q_a, float)
        return interpolation_segments(displacement_bound(dq, self._lever), self.resolution)

    def relevant_people(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """(E, H) bool: False where person i contributes exactly 0 to motion e.

        A weighted point moves at most D (:func:`displacement_bound`) along
        the motion, so at parameter t it is at least ``A - D t`` and
        ``B - D (1 - t)`` from a person it starts A and ends B away. Beyond the
        AGF's reach R (where it is <= threshold in every direction) its term
        is 0, so a person matters only where both bounds are <= R.
        """
        q_a, q_b = np.atleast_2d(q_a), np.atleast_2d(q_b)
        relevant, _, _ = self._window(q_a, q_b, displacement_bound(q_b - q_a, self._lever))
        return relevant

    def _people_grid(self) -> tuple:
        """(point reach, cell side, *kernel.people_grid) for the compiled
        kernel's culling; rebuilt when ``people`` changes."""
        key = self.people.tobytes() + (b"" if self.sigmas is None else self.sigmas.tobytes())
        if getattr(self, "_grid_key", None) != key:
            point_reach = float(self.geometry.reach(active=self._active)[2]) if len(self._active) else 0.0
            reach = self._max_reach()
            cell = reach + point_reach if np.isfinite(reach) and reach + point_reach > 0 else 1.0
            people = np.ascontiguousarray(self.people)
            self._grid = (point_reach, cell, *kernel.people_grid(people, cell))
            self._grid_key = key
        return self._grid

    def _window(self, q_a: np.ndarray, q_b: np.ndarray, span: np.ndarray):
        """For every (motion, person): whether the person may matter, and the
        parameter interval [t0, t1] outside which every term is 0."""
        e, h = len(q_a), len(self.people)
        reach = self._reaches()  # scalar, or per person (H,)
        if not np.all(np.isfinite(reach)):
            return np.ones((e, h), dtype=bool), np.zeros((e, h)), np.ones((e, h))
        x, y = self.geometry.interest_xy(np.concatenate([q_a, q_b]), self._active)  # (2E, K)
        dist = np.hypot(x[..., None] - self.people[:, 0], y[..., None] - self.people[:, 1]) - reach
        near_a, near_b = dist[:e], dist[e:]  # (E, K, H): distance beyond the reach at each end
        relevant = np.any(near_a + near_b <= span[:, None, None], axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            t0 = np.where(span[:, None] > 0, near_a.min(axis=1) / span[:, None], 0.0)
            t1 = np.where(span[:, None] > 0, 1.0 - near_b.min(axis=1) / span[:, None], 1.0)
        return relevant, np.clip(t0, 0.0, 1.0), np.clip(t1, 0.0, 1.0)

    def motion_cost(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Msc: the integral of S along straight motions, by the trapezoid rule.

        Each motion is cut into N equal steps of configuration length h
        (N from :meth:`segments`). The trapezoid rule is applied to every
        (point, person) term ``w_j AGF_i`` on its own, and where a term crosses
        the threshold inside a step (it jumps between 0 and > threshold there)
        the crossing is located by linear interpolation of the raw Gaussian
        and only the part above the threshold is integrated. Without crossings
        this is exactly the paper's ``h/2 sum [S(q_k) + S(q_k+1)]``; with them
        the error stays second order instead of a first-order jump error.
        A person is evaluated only on the samples of a motion where a
        distance bound (:meth:`relevant_people`) says their terms can be
        non-zero; elsewhere they are exactly 0.

        Args:
            q_a, q_b: motion ends (E, 4) or (4,), broadcastable.

        Returns:
            (E,) costs (a 0-d value for a single motion).

        Raises:
            ValueError: a configuration is not finite, or (where anyone's
                terms are weighted) a motion is too long to sample (see
                :func:`interpolation_segments`; a validated scenario's
                motions never are).
        """
        q_a = np.asarray(q_a, dtype=float)
        q_b = np.asarray(q_b, dtype=float)
        single = q_a.ndim == 1 and q_b.ndim == 1
        q_a, q_b = np.broadcast_arrays(np.atleast_2d(q_a), np.atleast_2d(q_b))
        if not (np.all(np.isfinite(q_a)) and np.all(np.isfinite(q_b))):
            raise ValueError("motion_cost needs finite configurations")
        out = np.zeros(len(q_a))
        if len(self.people) == 0 or len(self._active) == 0 or len(q_a) == 0:
            return out[0] if single else out
        length = config_distance(q_a, q_b, self.distance_weights)
        if self.backend == "numba":
            try:
                sums, n = self._msc_sums(q_a, q_b)
            except ValueError as kernel_error:
                try:
                    self.segments(q_a, q_b)  # raises, naming the motion and its bound
                except ValueError as named:
                    raise named from None
                raise kernel_error
            out += sums * (length / n)
            return out[0] if single else out
        dq = q_b - q_a
        span = displacement_bound(dq, self._lever)
        n = interpolation_segments(span, self.resolution)  # raises for a motion that cannot be sampled
        relevant, t0, t1 = self._window(q_a, q_b, span)
        relevant &= (length > 0)[:, None]
        if relevant.any():
            out += self._integrate(q_a, dq, n, relevant, t0, t1) * (length / n)
        return out[0] if single else out

    def _msc_sums(self, q_a: np.ndarray, q_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The compiled kernel's per-motion sums and step counts."""
        return kernel.msc_sums(
            np.ascontiguousarray(q_a), np.ascontiguousarray(q_b), self.people,
            *self.geometry.link_lengths, self.geometry.object_interest, self._active, self._active_weights,
            self._lever, self.resolution, *self.person_parameters(), self.space.threshold,
            *self._people_grid(),
        )  # fmt: skip

    # ---- along motions, against predicted people -----------------------------

    def timed_motion_cost(self, q_a: np.ndarray, q_b: np.ndarray, t_a, t_b, prediction: Prediction) -> np.ndarray:
        """Msc of straight motions against the people predicted at the time
        the robot is there (the replanner's objective).

        Along motion e, ``q(u) = q_a + u (q_b - q_a)`` is reached at
        ``t(u) = t_a + u (t_b - t_a)``; each trapezoid sample (u = k / n, the
        steps of :meth:`segments`, as :meth:`motion_cost`) is evaluated
        against the prediction's people at t(u): positions interpolated
        between its samples, heading and presence of the sample at or before
        t(u); before ``prediction.t0`` and beyond ``prediction.horizon`` the
        first and last samples hold. An absent person adds nothing at a sample
        (their raw Gaussian counts as 0 there, so a step where they appear or
        leave is a threshold crossing). Each person has this cost's
        per-person variances (:meth:`for_prediction` gives them from the
        prediction's speeds). Otherwise the rule is :meth:`motion_cost`'s: a
        static prediction gives its value (to about 1e-13 relative).

        The compiled kernel (:func:`drake_social.cost.timed_kernel.msc_sums_timed`)
        computes it with backend "numba"; backend "numpy" is the independent
        reference (every sample of every motion against every person, no
        culling), which the kernel is tested against.

        Args:
            q_a, q_b: motion ends (E, 4) or (4,), broadcastable.
            t_a, t_b: the times at the ends (E,) or scalars, seconds
                (finite, t_b >= t_a).
            prediction: the people, a :class:`~drake_social.people.Prediction`
                with as many people as this cost's per-person variances (any
                number without them).

        Returns:
            (E,) costs (a 0-d value for a single motion).

        Raises:
            TypeError: ``prediction`` is not a Prediction.
            ValueError: naming the argument: configurations not (E, 4) or not
                finite, times not finite or of another length, t_b < t_a, a
                prediction whose people do not match the per-person
                variances or whose ``max_speeds`` understate its motion, or a
                motion too long to sample.
        """
        q_a = np.asarray(q_a, dtype=float)
        q_b = np.asarray(q_b, dtype=float)
        single = q_a.ndim == 1 and q_b.ndim == 1 and np.ndim(t_a) == 0 and np.ndim(t_b) == 0
        try:
            q_a, q_b = np.broadcast_arrays(np.atleast_2d(q_a), np.atleast_2d(q_b))
        except ValueError:
            raise ValueError(f"timed_motion_cost: q_a {q_a.shape} and q_b {q_b.shape} do not broadcast") from None
        if q_a.ndim != 2 or q_a.shape[1] != 4:
            raise ValueError(f"timed_motion_cost: q_a and q_b must be (E, 4) or (4,) configurations, got {q_a.shape}")
        if not (np.all(np.isfinite(q_a)) and np.all(np.isfinite(q_b))):
            raise ValueError("timed_motion_cost needs finite configurations (q_a, q_b)")
        e = len(q_a)
        times = []
        for name, value in (("t_a", t_a), ("t_b", t_b)):
            value = np.asarray(value, dtype=float)
            if value.ndim > 1 or (value.ndim == 1 and len(value) not in (1, e)):
                raise ValueError(f"timed_motion_cost: {name} must be a scalar or ({e},) times, got shape {value.shape}")
            value = np.ascontiguousarray(np.broadcast_to(value.reshape(-1), (e,)))
            if not np.all(np.isfinite(value)):
                raise ValueError(f"timed_motion_cost: {name} must be finite times (seconds), got {value}")
            times.append(value)
        t_a, t_b = times
        if np.any(t_b < t_a):
            bad = int(np.flatnonzero(t_b < t_a)[0])
            raise ValueError(f"timed_motion_cost: t_b must be >= t_a; motion {bad} has t_a = {float(t_a[bad])!r}, "
                             f"t_b = {float(t_b[bad])!r}")
        _require_prediction(prediction, "SocialCost.timed_motion_cost")
        args = self.timed_kernel_args(prediction)  # checks the people and max_speeds
        out = np.zeros(e)
        if prediction.count == 0 or len(self._active) == 0 or e == 0:
            return out[0] if single else out
        length = config_distance(q_a, q_b, self.distance_weights)
        if self.backend == "numba":
            try:
                sums, n = timed_kernel.msc_sums_timed(np.ascontiguousarray(q_a), np.ascontiguousarray(q_b), t_a, t_b,
                                                      *args)
            except ValueError as kernel_error:
                try:
                    self.segments(q_a, q_b)  # raises, naming the motion and its bound
                except ValueError as named:
                    raise named from None
                raise kernel_error
        else:
            n = self.segments(q_a, q_b)  # raises for a motion that cannot be sampled
            sums = self._timed_sums(q_a, q_b, t_a, t_b, prediction, n)
        out += sums * (length / n)
        return out[0] if single else out

    def timed_kernel_args(self, prediction: Prediction) -> tuple:
        """The arguments of :func:`drake_social.cost.timed_kernel.msc_sums_timed`
        after ``q_a, q_b, t_a, t_b``, for ``prediction``'s people:
        ``(xy, theta, present, t0, dt, max_speeds, l1, l2, obj, active,
        weights, lever, resolution, reaches, inv_front, inv_rear, inv_side,
        tau, point_reach)`` (C-contiguous float arrays, ``present`` bool,
        ``active`` int64, the scalars floats), so that ``sums, n =
        msc_sums_timed(q_a, q_b, t_a, t_b, *cost.timed_kernel_args(p))`` and
        ``Msc = sums * length / n``.

        Raises:
            TypeError: ``prediction`` is not a Prediction.
            ValueError: the prediction's people do not match this cost's
                per-person variances, or its ``max_speeds`` understate the
                speed of its interpolated motion (the kernel's culling relies
                on them).
        """
        _require_prediction(prediction, "SocialCost.timed_kernel_args")
        f = np.ascontiguousarray
        key = id(prediction)
        cached = getattr(self, "_timed_args", None)
        if cached is not None and cached[0] == key and cached[1] is prediction:
            return cached[2]
        speeds = _interpolated_speeds(prediction)
        if not np.all(speeds <= prediction.max_speeds * (1.0 + 1e-9) + 1e-12):
            bad = int(np.flatnonzero(~(speeds <= prediction.max_speeds * (1.0 + 1e-9) + 1e-12))[0])
            raise ValueError(f"prediction.max_speeds[{bad}] = {float(prediction.max_speeds[bad])!r} m/s is below the "
                             f"speed of that person's predicted motion, {float(speeds[bad])!r} m/s")
        args = (
            f(prediction.positions, float), f(prediction.headings, float), f(prediction.present, bool),
            float(prediction.t0), float(prediction.dt), f(prediction.max_speeds, float),
            *map(float, self.geometry.link_lengths), f(self.geometry.object_interest, float),
            f(self._active, np.int64), f(self._active_weights, float), f(self._lever, float), float(self.resolution),
            *(f(v, float) for v in self._timed_person_parameters(prediction.count)), float(self.space.threshold),
            self._point_reach(),
        )  # fmt: skip
        self._timed_args = (key, prediction, args)
        return args

    def _timed_person_parameters(self, count: int) -> tuple:
        """:meth:`person_parameters` for a prediction of ``count`` people."""
        if self.sigmas is None:
            return tuple(np.full(count, v) for v in (self.space.max_reach, *self._inverse_variances))
        if count != len(self.people):
            raise ValueError(f"the prediction has {count} people but this cost's per-person variances (sigmas) are "
                             f"for {len(self.people)}: make the cost with SocialCost.for_prediction")
        return self.person_parameters()

    def _point_reach(self) -> float:
        """The largest distance of a weighted interest point from the base centre, metres."""
        return float(self.geometry.reach(active=self._active)[2]) if len(self._active) else 0.0

    def _timed_sums(self, q_a, q_b, t_a, t_b, prediction, n) -> np.ndarray:
        """The numpy reference of the time-indexed sums (E,): every sample of
        every motion against every predicted person (no culling), in chunks
        of about :data:`FIELD_CHUNK_ELEMENTS` (sample, point, person) values;
        times h = length / n gives Msc."""
        _, inv_front, inv_rear, inv_side = self._timed_person_parameters(prediction.count)
        per_sample = len(self._active) * prediction.count
        budget = max(1, FIELD_CHUNK_ELEMENTS // max(per_sample, 1))
        dq, duration, tau = q_b - q_a, t_b - t_a, self.space.threshold
        sums = np.zeros(len(q_a))
        start = 0
        while start < len(q_a):
            stop, total = start + 1, n[start] + 1
            while stop < len(q_a) and total + n[stop] + 1 <= budget:
                total += n[stop] + 1
                stop += 1
            count = n[start:stop] + 1
            edge = np.repeat(np.arange(start, stop), count)
            k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
            u = k / n[edge]
            x, y = self.geometry.interest_xy(q_a[edge] + u[:, None] * dq[edge], self._active)  # (S, K)
            pos, heading, here = _predicted_people(prediction, t_a[edge] + u * duration[edge])
            g = gaussian(x[:, :, None] - pos[:, None, :, 0], y[:, :, None] - pos[:, None, :, 1],
                         np.cos(heading)[:, None, :], np.sin(heading)[:, None, :], self.space,
                         (inv_front, inv_rear, inv_side))  # (S, K, P)
            g = np.where(here[:, None, :], g, 0.0)
            step = np.flatnonzero(k[:-1] < n[edge[:-1]])  # consecutive samples of one motion
            g0, g1 = g[step], g[step + 1]
            hi, lo = np.maximum(g0, g1), np.minimum(g0, g1)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                crossing = 0.5 * (hi + tau) * (hi - tau) / (hi - lo)
            up0, up1 = g0 > tau, g1 > tau
            area = np.where(up0 & up1, 0.5 * (g0 + g1), np.where(up0 ^ up1, crossing, 0.0))
            per_step = np.einsum("skp,k->s", area, self._active_weights)
            sums[start:stop] = np.bincount(edge[step] - start, weights=per_step, minlength=stop - start)
            start = stop
        return sums

    def _integrate(self, q_a, dq, n, relevant, t0, t1) -> np.ndarray:
        """Sums over steps of the threshold-aware trapezoid areas (E,), in one
        batch over the (motion, relevant person) pairs; times h gives Msc.

        Pair (e, i) walks the samples k0 .. k1 of motion e that bracket its
        window [t0, t1]; the steps outside have both ends beyond the reach.
        """
        pair_edge, pair_person = np.nonzero(relevant)
        n_pair = n[pair_edge]
        k0 = np.floor(t0[pair_edge, pair_person] * n_pair).astype(np.int64)
        k1 = np.minimum(np.ceil(t1[pair_edge, pair_person] * n_pair).astype(np.int64), n_pair)
        # At least one step, within the motion: with t0 = 1 (k0 = n) the step is
        # the last one, n - 1 .. n, never a sample beyond q_b.
        k1 = np.minimum(np.maximum(k1, k0 + 1), n_pair)
        k0 = np.minimum(k0, k1 - 1)
        count = k1 - k0 + 1
        pair = np.repeat(np.arange(len(pair_edge)), count)
        local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        edge = pair_edge[pair]
        t = (k0[pair] + local) / n[edge]
        x, y = self.geometry.interest_xy(q_a[edge] + t[:, None] * dq[edge], self._active)
        person = self.people[pair_person[pair]]
        inverse = None
        if self.sigmas is not None:
            inverse = tuple(v[pair_person[pair]][:, None] for v in inverse_variances(self.sigmas))
        g = gaussian(
            x - person[:, 0:1], y - person[:, 1:2], np.cos(person[:, 2:3]), np.sin(person[:, 2:3]), self.space,
            inverse,
        )  # (samples of all pairs, K)
        step = np.flatnonzero(local[:-1] < count[pair[:-1]] - 1)  # consecutive samples of one pair
        g0, g1 = g[step], g[step + 1]
        tau = self.space.threshold
        up0, up1 = g0 > tau, g1 > tau
        hi, lo = np.maximum(g0, g1), np.minimum(g0, g1)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            crossing = 0.5 * (hi + tau) * (hi - tau) / (hi - lo)
        area = np.where(up0 & up1, 0.5 * (g0 + g1), np.where(up0 ^ up1, crossing, 0.0))
        return np.bincount(edge[step], weights=area @ self._active_weights, minlength=len(q_a))

    # ---- for figures ----------------------------------------------------------

    def field(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``G(x, y) = sum_i AGF_i(x, y)`` (thresholded), broadcast over x and y.

        Evaluated in chunks of consecutive points, each against only the
        people within the AGF's reach of the chunk's bounding box (the others
        add exactly 0), so the temporary (points, people) arrays hold at most
        about :data:`FIELD_CHUNK_ELEMENTS` values whatever the number of
        points and people: a 512 x 512 heat map of a crowd costs megabytes,
        not gigabytes. Each point's sum is that of ``agf(...).sum(-1)`` of all
        points at once, bit for bit.
        """
        return self._people_sum(x, y)

    def _people_sum(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """:meth:`field`, also the people's sums of :meth:`__call__` and
        :meth:`point_costs` (apart from :meth:`field`, which figures call and
        tests count)."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        shape = x.shape
        x, y = x.ravel(), y.ravel()
        out = np.zeros(x.size)
        h = len(self.people)
        if h == 0 or x.size == 0:
            return out.reshape(shape)
        # Beyond the reach every AGF is <= threshold, hence 0; the relative
        # margin keeps a person whose value rounds just above the threshold.
        reach = np.asarray(self._reaches()) * (1.0 + 1e-9) + 1e-9  # scalar, or per person
        chunk = max(1, FIELD_CHUNK_ELEMENTS // h)
        px, py = self.people[:, 0], self.people[:, 1]
        for start in range(0, x.size, chunk):
            cx, cy = x[start : start + chunk], y[start : start + chunk]
            near = np.ones(h, dtype=bool)
            if np.all(np.isfinite(reach)):
                # Distance from each person to the chunk's bounding box (NaN keeps the person).
                gap_x = np.maximum(np.maximum(cx.min() - px, px - cx.max()), 0.0)
                gap_y = np.maximum(np.maximum(cy.min() - py, py - cy.max()), 0.0)
                near = ~(np.hypot(gap_x, gap_y) > reach)  # reach (H,) or scalar
            if near.any():
                # The far people's exact zeros stay in their columns, so each
                # point's sum runs over the same H values in the same order as
                # one unchunked evaluation would: the same bits.
                values = np.zeros((len(cx), h))
                sigmas = None if self.sigmas is None else self.sigmas[near]
                values[:, near] = agf_xy(cx, cy, self.people[near], self.space, sigmas=sigmas)
                out[start : start + chunk] = values.sum(-1)
        return out.reshape(shape)


def _require_prediction(prediction, who: str) -> None:
    """Refuses anything but a :class:`~drake_social.people.Prediction`."""
    if not isinstance(prediction, Prediction):
        raise TypeError(f"{who}: prediction must be a drake_social.people.Prediction (people.predict, "
                        f"constant_velocity, perfect_prediction), got {type(prediction).__name__}")


def _predicted_people(prediction: Prediction, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The predicted people at each of ``times`` (T,): positions (T, P, 2)
    interpolated between samples, headings (T, P) and presence (T, P) of the
    sample at or before each time, clamped to the first and the last sample
    (:meth:`Prediction.state_at`'s rule, batched)."""
    s = (np.asarray(times, dtype=float) - prediction.t0) / prediction.dt
    last = prediction.samples - 1
    slot = np.zeros(len(s), dtype=np.int64)
    frac = np.zeros(len(s))
    slot[(s > 0) & (s >= last)] = last
    mid = (s > 0) & (s < last)
    slot[mid] = np.floor(s[mid]).astype(np.int64)
    frac[mid] = s[mid] - slot[mid]
    here = prediction.positions[slot]
    nxt = prediction.positions[np.minimum(slot + 1, last)]
    positions = here + frac[:, None, None] * (nxt - here)
    return positions, prediction.headings[slot], prediction.present[slot]


def _interpolated_speeds(prediction: Prediction) -> np.ndarray:
    """(P,) each person's largest speed along the interpolated prediction, m/s."""
    if prediction.samples < 2 or prediction.count == 0:
        return np.zeros(prediction.count)
    step = np.diff(prediction.positions, axis=0)
    return np.hypot(step[..., 0], step[..., 1]).max(axis=0) / prediction.dt
