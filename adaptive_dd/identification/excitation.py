"""Exciting trajectories for any serial arm: finite Fourier series designed within the arm's limits.

Trajectory
----------
Per joint ``q_j(t) = q0_j + sum_{k=1..K} a_jk sin(2 pi k f0 t) + b_jk cos(2 pi k f0 t)``,
periodic with period ``1/f0``; written as a scenario ``[reference]``
(``offset = q0``, ``amplitude = hypot(a, b)``, ``frequency = k f0``, ``phase = atan2(b, a)``).

Design
------
Maximise ``log det`` of the information of the base parameters in the inverse-dynamics
regression along one period (D-optimal), ``sum_i Y_i^T diag(1/tau_max^2) Y_i`` over a grid
of ``m`` points (rows weighted by each joint's torque limit), subject to, at every grid
point, positions within the limits less a margin, ``|qd| <= velocity limit``,
``|qdd| <= acceleration limit`` and ``|tau| <= torque limit`` (the URDF's model, less a
margin), by ``scipy.optimize.minimize(method="SLSQP")`` with the objective's gradient and the
limits' Jacobian by the chain rule (:mod:`~adaptive_dd.identification.excitation_gradient`).

The comparison
--------------
A plain multi-sine of the same harmonics (amplitudes ``1/k``, Schroeder phases, the same
pattern on every joint, the offset mid-range), scaled per joint to the largest amplitude
that meets the same limits. Each trajectory's bound is the Cramér-Rao bound of the
segmented output error (:func:`~adaptive_dd.identification.output_error.cramer_rao_bound`)
on a simulated record tracking it; the worst parameter is the largest std relative to the
parameter's magnitude, floored at 1 % of the largest of its kind (mass, first moment,
inertia, viscous, Coulomb) so that parameters near zero are compared on their kind's scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq, minimize

from adaptive_dd.benchmark.scenario import Reference
from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.excitation_gradient import DesignProblem, limit_slack
from adaptive_dd.identification.model import Model, arm_model, base_regressor

__all__ = [
    "TASK_MARGIN",
    "Coverage",
    "ExcitationLimits",
    "FourierTrajectory",
    "coverage",
    "design_excitation",
    "moving_joints",
    "multisine",
    "reference_toml",
    "relative_bounds",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ExcitationLimits:
    """Limits a designed trajectory keeps within (``(n,)`` arrays).

    ``lower, upper`` [rad] positions (already less the margin), ``velocity`` [rad/s],
    ``acceleration`` [rad/s^2], ``torque`` [N m].
    """

    lower: Array
    upper: Array
    velocity: Array
    acceleration: Array
    torque: Array

    @classmethod
    def of_arm(
        cls, arm, acceleration: float = 5.0, margin: float = 0.1, fraction: float = 0.8, span: float = np.pi
    ) -> ExcitationLimits:
        """The arm's limits: positions less ``margin`` [rad] (and within ``+-span`` of the middle for
        unbounded joints), velocities and torques times ``fraction``, one acceleration limit."""
        lim = np.asarray(arm.position_limits, float)
        bounded = np.isfinite(lim).all(axis=1)  # a continuous joint's [-inf, inf]: centred on 0
        mid = np.zeros(lim.shape[0])
        mid[bounded] = lim[bounded].mean(axis=1)
        lo = np.maximum(lim[:, 0] + margin, mid - span)
        hi = np.minimum(lim[:, 1] - margin, mid + span)
        if np.any(hi <= lo):
            raise ParameterError(
                f"position limits leave no room after a margin of {margin} rad: {lim.tolist()}"
            )
        n = arm.n_joints
        return cls(
            lo,
            hi,
            fraction * np.asarray(arm.velocity_limits, float),
            np.full(n, float(acceleration)),
            fraction * np.asarray(arm.actuator.torque_limit, float),
        )


@dataclass(frozen=True)
class FourierTrajectory:
    """``q0 (n,)``, ``a, b (n, K)`` [rad], base frequency ``f0`` [Hz]."""

    q0: Array
    a: Array
    b: Array
    f0: float

    def sample(self, t: Array) -> tuple[Array, Array, Array]:
        """``q, qd, qdd`` at times ``t (m,)``, each ``(m, n)``."""
        K = self.a.shape[1]
        w = 2 * np.pi * self.f0 * np.arange(1, K + 1)
        s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
        q = self.q0 + s @ self.a.T + c @ self.b.T
        qd = (c * w) @ self.a.T - (s * w) @ self.b.T
        qdd = -(s * w**2) @ self.a.T - (c * w**2) @ self.b.T
        return q, qd, qdd

    def reference(self, ramp: float = 0.0) -> Reference:
        """The scenario :class:`~adaptive_dd.benchmark.scenario.Reference` of this trajectory."""
        K = self.a.shape[1]
        freqs = tuple(float(self.f0 * k) for k in range(1, K + 1))
        amp = np.hypot(self.a, self.b)
        ph = np.arctan2(self.b, self.a)
        return Reference(
            offset=tuple(float(x) for x in self.q0),
            amplitude=tuple(tuple(float(x) for x in row) for row in amp),
            frequency=tuple(freqs for _ in range(len(self.q0))),
            phase=tuple(tuple(float(x) for x in row) for row in ph),
            ramp=float(ramp),
        )


def _pack(tr: FourierTrajectory) -> Array:
    return np.concatenate([tr.q0, tr.a.ravel(), tr.b.ravel()])


def _unpack(x: Array, n: int, K: int, f0: float) -> FourierTrajectory:
    return FourierTrajectory(x[:n], x[n : n + n * K].reshape(n, K), x[n + n * K :].reshape(n, K), f0)


def _constraints(model: Model, tr: FourierTrajectory, t: Array, lim: ExcitationLimits) -> Array:
    """Slack of every limit at every grid point (>= 0 when met), normalised by the limit."""
    q, qd, qdd = tr.sample(t)
    return limit_slack(q, qd, qdd, base_regressor(model, q, qd, qdd) @ model.sigma_ref, lim)


def multisine(
    arm, lim: ExcitationLimits, harmonics: int = 5, f0: float = 0.1, grid: int = 200
) -> FourierTrajectory:
    """The plain multi-sine of the same harmonics, scaled per joint to the largest amplitude in ``lim``."""
    model = arm_model(arm)
    n, K = arm.n_joints, harmonics
    k = np.arange(1, K + 1)
    phase = -np.pi * k * (k - 1) / K  # Schroeder
    a0, b0 = np.cos(phase) / k, np.sin(phase) / k
    t = np.linspace(0, 1 / f0, grid, endpoint=False)
    q0 = 0.5 * (lim.lower + lim.upper)
    scale = np.zeros(n)

    def traj(s):
        return FourierTrajectory(q0, np.outer(s, a0), np.outer(s, b0), f0)

    for j in range(n):  # joint by joint, the others at the scale found so far (0 at first)

        def slack(alpha, j=j):
            s = scale.copy()
            s[j] = alpha
            return float(np.min(_constraints(model, traj(s), t, lim)))

        hi = 1.0
        while slack(hi) > 0 and hi < 100:
            hi *= 2
        scale[j] = brentq(slack, 0.0, hi, xtol=1e-6) * 0.999 if slack(hi) < 0 else hi
    # joints scaled one by one: the torque of later joints' motion may load earlier ones, shrink together
    while np.min(_constraints(model, traj(scale), t, lim)) < 0:
        scale *= 0.95
    return traj(scale)


def _random_start(model, lim, n, K, f0, t, rng) -> FourierTrajectory:
    """Random coefficients (decaying as 1/k) scaled by one factor to the edge of the limits."""
    k = np.arange(1, K + 1)
    a = rng.uniform(-1, 1, (n, K)) / k
    b = rng.uniform(-1, 1, (n, K)) / k
    q0 = 0.5 * (lim.lower + lim.upper)

    def slack(alpha):
        return float(np.min(_constraints(model, FourierTrajectory(q0, alpha * a, alpha * b, f0), t, lim)))

    hi = 1.0
    while slack(hi) > 0 and hi < 100:
        hi *= 2
    alpha = brentq(slack, 1e-9, hi, xtol=1e-6) * 0.9 if slack(hi) < 0 else hi
    return FourierTrajectory(q0, alpha * a, alpha * b, f0)


def design_excitation(
    arm,
    lim: ExcitationLimits | None = None,
    *,
    harmonics: int = 5,
    f0: float = 0.1,
    grid: int = 100,
    maxiter: int = 100,
    start: FourierTrajectory | None = None,
    rng: np.random.Generator | None = None,
    progress: bool = False,
) -> tuple[FourierTrajectory, object]:
    """D-optimal Fourier trajectory within ``lim`` (module docstring); returns it and scipy's result.
    ``progress``: a bar of SLSQP's iterations on stderr (minutes on a 7-joint arm).

    Starts from ``start`` or from random coefficients (``rng``, default seed 0) scaled into the
    limits; the result is checked on a grid :data:`FINE` times finer, and its oscillation about
    ``q0`` shrunk by the smallest factor that keeps it within the limits there (an optimum sits on
    a limit at the optimiser's grid points and may cross it between them).


    Parameters
    ----------
    arm : Arm
        The arm to excite.
    lim : ExcitationLimits, optional
        Position, velocity, acceleration and torque limits (default: the arm's, with margins).
    harmonics : int
        Harmonics of the Fourier series per joint.
    f0 : float
        The fundamental frequency [Hz]: the trajectory repeats every ``1 / f0`` s.
    grid : int
        Samples per period at which the limits and the information are evaluated.
    maxiter : int
        SLSQP's iterations at most.
    start : FourierTrajectory, optional
        A start for the optimiser.
    rng : numpy.random.Generator, optional
        For the random start (default seed 0).
    progress : bool
        A bar of SLSQP's iterations on stderr (minutes on a 7-joint arm).

    Returns
    -------
    trajectory : FourierTrajectory
        The designed excitation, within the limits.
    result : scipy.optimize.OptimizeResult
        The optimiser's result.

    Raises
    ------
    ParameterError
        If the optimum crosses a limit on a grid :data:`FINE` times finer and shrinking its
        oscillation to :data:`MIN_SHRINK` does not bring it within (:func:`_within_limits`).

    Examples
    --------
    A short optimisation (one harmonic, three iterations) on the three-joint arm:

    >>> from adaptive_dd.benchmark.scenario import parse_scenario
    >>> from adaptive_dd.identification.excitation import design_excitation
    >>> ref = {"joint1": {"offset": 0.3, "amplitude": [0.4], "frequency": [0.3]},
    ...        "joint2": {"offset": -0.6, "amplitude": [0.5], "frequency": [0.4]},
    ...        "joint3": {"offset": 0.4, "amplitude": [0.6], "frequency": [0.5]}}
    >>> arm = parse_scenario({"arm": {"robot": "vertical3"}, "reference": ref}).arm
    >>> traj, opt = design_excitation(arm, harmonics=1, grid=20, maxiter=3)
    >>> traj.a.shape, traj.f0  # sine coefficients per joint and harmonic; [Hz]
    ((3, 1), 0.1)
    """
    lim = lim or ExcitationLimits.of_arm(arm)
    model = arm_model(arm)
    n, K = arm.n_joints, harmonics
    t = np.linspace(0, 1 / f0, grid, endpoint=False)
    x0 = _pack(start or _random_start(model, lim, n, K, f0, t, rng or np.random.default_rng(0)))
    problem = DesignProblem(model, lim, n, K, f0, t)
    problem.set_scaling(x0)
    # a box every coefficient must lie in for the limits to hold on its own
    w = 2 * np.pi * f0 * np.arange(1, K + 1)
    amax = np.minimum.reduce(
        [
            np.broadcast_to(0.5 * (lim.upper - lim.lower)[:, None], (n, K)),
            lim.velocity[:, None] / w,
            lim.acceleration[:, None] / w**2,
        ]
    ).ravel()
    bounds = list(zip(lim.lower, lim.upper, strict=True)) + [(-a, a) for a in np.concatenate([amax, amax])]
    bar = _design_bar(progress, maxiter, len(x0))
    res = _optimise(problem, x0, bounds, maxiter, None if bar is None else (lambda _x: bar.update(1)))
    if bar is not None:
        bar.close()
    fine = np.linspace(0, 1 / f0, FINE * grid, endpoint=False)
    return _within_limits(model, _unpack(res.x, n, K, f0), fine, lim), res


def _optimise(
    problem: DesignProblem, x0: Array, bounds: list, maxiter: int, callback=None, exact: bool = True
):
    """SLSQP on ``problem`` from ``x0`` (clipped into ``bounds``) with the exact derivatives
    (:mod:`~adaptive_dd.identification.excitation_gradient`); ``exact=False``: scipy's forward
    differences instead (the design before, kept to compare against)."""
    lo, hi = (np.array([b[i] for b in bounds]) for i in (0, 1))
    cons = {"type": "ineq", "fun": problem.constraints}
    if exact:
        cons["jac"] = problem.constraints_jacobian
    return minimize(
        problem.cost,
        np.clip(x0, lo, hi),
        jac=problem.cost_gradient if exact else None,
        method="SLSQP",
        bounds=bounds,
        constraints=[cons],
        options={"maxiter": maxiter, "ftol": 1e-6},
        callback=callback,
    )


def _design_bar(show: bool, maxiter: int, size: int):
    """A progress bar of the design's SLSQP iterations on stderr, or None."""
    if not show:
        return None
    from tqdm.auto import tqdm

    return tqdm(
        total=maxiter, desc=f"designing the excitation (SLSQP, {size} coefficients)", unit="iteration",
        mininterval=0.5, leave=False,
    )  # fmt: skip


FINE = 8
"""The design's check: a grid this many times finer than the one the optimiser saw."""
MIN_SHRINK = 0.8
"""The smallest factor :func:`design_excitation` shrinks an optimum's oscillation by to bring it
within the limits between grid points (below it the design is refused)."""


def _within_limits(
    model: Model, tr: FourierTrajectory, fine: Array, lim: ExcitationLimits
) -> FourierTrajectory:
    """``tr`` if it keeps within ``lim`` on the ``fine`` grid, else its oscillation about ``q0``
    shrunk by the largest factor that does (an optimum sits on the limits at the optimiser's grid
    points and may cross them between); refused below :data:`MIN_SHRINK`."""

    def slack(alpha):
        shrunk = FourierTrajectory(tr.q0, alpha * tr.a, alpha * tr.b, tr.f0)
        return float(np.min(_constraints(model, shrunk, fine, lim)))

    worst = slack(1.0)
    if worst >= 0:
        return tr
    if slack(MIN_SHRINK) < 0:
        raise ParameterError(
            f"the designed trajectory exceeds a limit by {-worst:.1%} between grid points, and still "
            f"does with its oscillation shrunk to {MIN_SHRINK:g}: try more grid points (grid) or "
            "fewer harmonics"
        )
    alpha = brentq(slack, MIN_SHRINK, 1.0, xtol=1e-6) * (1 - 1e-4)  # the feasible side of the root
    if slack(alpha) < 0:  # the slack need not be monotone in alpha (torques): the checked factor
        alpha = MIN_SHRINK
    return FourierTrajectory(tr.q0, alpha * tr.a, alpha * tr.b, tr.f0)


TASK_MARGIN = 0.2
"""[rad] How far beyond the task's range of positions (per joint) the task's region reaches
(:class:`Coverage`)."""


@dataclass(frozen=True)
class Coverage:
    """How an excitation's record covers a task's region (:func:`coverage`).

    The task's region: per joint the range of positions the task visits widened by ``radius`` [rad]
    (:data:`TASK_MARGIN`). ``moves (n,)``: the joints whose position enters the dynamics (a base
    joint about the vertical does not: its position is not judged). ``span (n,)``: per joint the
    fraction of the task's range the excitation visits; ``speed (n,)``: the excitation's largest
    ``|qd|`` over the task's; ``inside``: the share of the excitation's poses within the task's
    region (every judged joint); ``distance (3,)`` [rad]: median, p90 and max over the task's poses
    of the distance (largest judged joint difference) to the excitation's nearest pose.
    """

    moves: NDArray[np.bool_]
    span: Array
    speed: Array
    inside: float
    distance: Array
    radius: float

    @property
    def ok(self) -> bool:
        """Covered: every judged joint's range visited to :data:`MIN_SPAN`, and either at least
        :data:`MIN_INSIDE` of the excitation within the task's region or the median task pose within
        ``radius`` of an excitation pose (an excitation wider than the region that still passes
        near the task's poses, as on a two-joint arm)."""
        near = self.inside >= MIN_INSIDE or self.distance[0] <= self.radius
        return bool(np.all(self.span[self.moves] >= MIN_SPAN) and near)

    def line(self) -> str:
        """One printed line: the figures and the verdict."""
        verdict = "covered" if self.ok else "NOT covered: the excitation lies mostly off the task's region"
        if self.ok and self.inside < MIN_INSIDE:
            verdict = "covered: the task's poses lie near the excitation's"
        judged = self.span[self.moves] if self.moves.any() else self.span
        return (
            f"coverage of the task's region (its positions +- {self.radius:g} rad) by the excitation: "
            f"{self.inside:.0%} of the excitation inside it, the task's range visited per joint min "
            f"{judged.min():.0%}, speed reached min {self.speed.min():.2f}x the task's; distance from a "
            f"task pose to the nearest excitation pose median {self.distance[0]:.3f} / p90 "
            f"{self.distance[1]:.3f} / max {self.distance[2]:.3f} rad ({verdict})"
        )


MIN_SPAN = 0.9
"""The share of the task's range of each judged joint an excitation must visit (:class:`Coverage`)."""
MIN_INSIDE = 0.5
"""The share of an excitation's poses that must lie within the task's region (:class:`Coverage`)."""


def moving_joints(model: Model, q: Array, rng: np.random.Generator) -> NDArray[np.bool_]:
    """``(n,)`` the joints whose position enters the base regressor at the poses ``q (m, n)`` (a
    shift of 0.5 rad, random velocities and accelerations, relative change above 1e-9)."""
    q = np.asarray(q, float)
    qd, qdd = rng.standard_normal(q.shape), rng.standard_normal(q.shape)
    Y = base_regressor(model, q, qd, qdd)
    scale = np.abs(Y).max()
    out = np.zeros(model.n, bool)
    for j in range(model.n):
        qs = q.copy()
        qs[:, j] += 0.5
        out[j] = np.abs(base_regressor(model, qs, qd, qdd) - Y).max() > 1e-9 * scale
    return out


def coverage(
    task: tuple[Array, Array],
    excitation: tuple[Array, Array],
    moves: NDArray[np.bool_] | None = None,
    radius: float = TASK_MARGIN,
) -> Coverage:
    """How the excitation's poses and speeds ``excitation = (q, qd)`` (each ``(m, n)``) cover the
    task's ``task = (q, qd)`` (``(k, n)``): :class:`Coverage`; ``moves`` the judged joints (default
    all, :func:`moving_joints`). Sample both at tens of milliseconds (the distances hold blocks of
    ``256 m n`` numbers)."""
    tq, tqd = (np.asarray(x, float) for x in task)
    eq, eqd = (np.asarray(x, float) for x in excitation)
    moves = np.ones(tq.shape[1], bool) if moves is None else np.asarray(moves, bool)
    lo, hi = tq.min(axis=0), tq.max(axis=0)
    seen = np.clip(np.minimum(hi, eq.max(axis=0)) - np.maximum(lo, eq.min(axis=0)), 0.0, None)
    span = np.where(hi > lo, seen / np.maximum(hi - lo, 1e-300), 1.0)
    speed = np.abs(eqd).max(axis=0) / np.maximum(np.abs(tqd).max(axis=0), 1e-300)
    within = (eq >= lo - radius - 1e-9) & (eq <= hi + radius + 1e-9)
    inside = float(np.mean(within[:, moves].all(axis=1)))
    d = np.empty(len(tq))
    for s in range(0, len(tq), 256):
        d[s : s + 256] = np.abs(tq[s : s + 256, None, moves] - eq[None, :, moves]).max(axis=2).min(axis=1)
    dist = np.array([np.median(d), np.quantile(d, 0.9), d.max()])
    return Coverage(moves, span, speed, inside, dist, float(radius))


def relative_bounds(crb: Array, sigma: Array, names: tuple[str, ...]) -> Array:
    """``crb_i / max(|sigma_i|, 1 % of the largest |sigma| of its kind)`` (module docstring); NaN
    for a kind whose every parameter is 0 (an arm without friction: no magnitude to compare with)."""
    kinds = []
    for nm in names:
        lead = nm.split(" ")[0].split("*")[-1]
        if lead.startswith(("fv", "fc")):
            kinds.append(lead[:2])
        elif lead.startswith("I"):
            kinds.append("I")
        elif lead.startswith("m") and len(lead) > 1 and lead[1] in "xyz":
            kinds.append("mx")
        else:
            kinds.append("m")
    kinds = np.array(kinds)
    scale = np.abs(np.asarray(sigma, float)).copy()
    for kd in set(kinds):
        sel = kinds == kd
        scale[sel] = np.maximum(scale[sel], 0.01 * scale[sel].max()) if scale[sel].max() > 0 else np.nan
    return np.asarray(crb, float) / scale


def reference_toml(ref: Reference, comment: str = "") -> str:
    """The ``[reference]`` table of a scenario for ``ref``."""
    lines = ["[reference]"]
    if comment:
        lines.insert(0, "# " + comment)
    lines.append(f"ramp = {ref.ramp!r}")
    for j in range(ref.n_joints):
        amp = ", ".join(f"{x:.6g}" for x in ref.amplitude[j])
        fr = ", ".join(f"{x:.6g}" for x in ref.frequency[j])
        ph = ", ".join(f"{x:.6g}" for x in ref.phase[j])
        lines.append(
            f"joint{j + 1} = {{ offset = {ref.offset[j]:.6g}, amplitude = [{amp}], frequency = [{fr}], "
            f"phase = [{ph}] }}"
        )
    return "\n".join(lines) + "\n"
