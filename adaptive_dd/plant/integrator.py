"""The compiled sampled-data plant for any serial chain: one sample under a held torque.

The N-joint generalisation of :mod:`adaptive_dd.plant.two_link_integrator` (two links): the
torque is held over one sample ``T`` (zero-order hold) and the state is advanced by
``substeps`` classical RK4 steps; the rigid-body terms come from
:func:`adaptive_dd.plant.chain_dynamics.bias_and_mass`. Joint friction is viscous ``fv_i qd_i``
plus a Coulomb term of level ``fc_i`` under one of four laws
(:data:`adaptive_dd.plant.two_link_integrator.FRICTION_CODES`): stick-slip, tanh, Stribeck, or
LuGre, whose bristle state the law's record carries (:class:`LugreLaw`).

The modes of resting joints under the stick-slip law (an active set), the crossings of zero
velocity within a substep and the step splitting of the smooth laws are described, and
implemented, in :mod:`adaptive_dd.plant.chain_rk4`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numba.extending import overload
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.chain import Chain
from adaptive_dd.plant.chain_rk4 import _lugre, _scratch, _smooth, _stick_slip
from adaptive_dd.plant.two_link_integrator import FRICTION_CODES

__all__ = [
    "LugreLaw",
    "PlantParams",
    "SmoothLaw",
    "StickSlipLaw",
    "friction_law",
    "plant_params",
    "plant_run",
    "plant_step",
    "trial_law",
]


class PlantParams(NamedTuple):
    """The physical plant of one serial arm, as the compiled step takes it.

    Attributes
    ----------
    pi : ndarray, shape (10 n,)
        Standard link parameters (payload already folded in by the caller),
        :func:`adaptive_dd.plant.chain.standard_parameters`.
    fv : ndarray, shape (n,)
        Viscous friction [N m s] (N s/m for prismatic joints).
    fc : ndarray, shape (n,)
        Coulomb friction level [N m] (N).
    armature : ndarray, shape (n,)
        Rotor inertia added to M's diagonal [kg m^2] (kg).
    law : int or StickSlipLaw or SmoothLaw or LugreLaw
        0 stick-slip, 1 tanh, 2 stribeck (:data:`adaptive_dd.plant.two_link_integrator.FRICTION_CODES`);
        as a code, the step compiles the integrators of both families and chooses at run time; as a
        :func:`friction_law` record, only its family's. LuGre (3) only as its record, which carries
        the bristle state.
    fparams : ndarray, shape (3,) or (3 + 2 n,)
        ``friction_velocity, stribeck_ratio, stribeck_velocity`` of the smooth laws; LuGre's
        bristle stiffness ``sigma0`` [N m/rad] and damping ``sigma1`` [N m s/rad] per joint after them.
    """

    pi: NDArray[np.float64]
    fv: NDArray[np.float64]
    fc: NDArray[np.float64]
    armature: NDArray[np.float64]
    law: int | StickSlipLaw | SmoothLaw | LugreLaw
    fparams: NDArray[np.float64]


class StickSlipLaw(NamedTuple):
    """The stick-slip law (``code`` 0) as a type of its own (:func:`friction_law`)."""

    code: int


class SmoothLaw(NamedTuple):
    """A smooth law (``code`` 1 tanh, 2 Stribeck) as a type of its own (:func:`friction_law`)."""

    code: int


class LugreLaw(NamedTuple):
    """The LuGre law (``code`` 3) and its bristle deflections ``z`` [rad], updated in place by each
    step: ``(n,)`` for one arm, or ``(S, n)`` for a run's trials (the closed loop steps trial i
    with row ``z[i]``)."""

    code: int
    z: NDArray[np.float64]


def friction_law(code: int, z: NDArray | None = None) -> StickSlipLaw | SmoothLaw | LugreLaw:
    """Friction law ``code`` with its family (stick-slip, smooth or LuGre) a compile-time choice.

    numba compiles a kernel per argument type: a plant step given this record instead of the
    integer code compiles only its family's integrator (a closed loop on a stick-slip arm does not
    compile the smooth laws' RK4 and step splitting, about a fifth of its compilation). LuGre
    (code 3) needs the bristle state ``z`` (zeros: the bristles at rest), which it keeps.
    """
    code = int(code)
    if code not in (0, 1, 2, 3):
        raise ParameterError(f"friction law code of a serial arm must be 0, 1, 2 or 3, got {code!r}")
    if code == 3:
        if z is None:
            raise ParameterError("friction_law(3): LuGre needs its bristle state z, e.g. np.zeros(n)")
        return LugreLaw(3, np.ascontiguousarray(z, dtype=np.float64))
    return StickSlipLaw(code) if code == 0 else SmoothLaw(code)


def plant_params(
    ch: Chain,
    pi: NDArray,
    fv: NDArray,
    fc: NDArray,
    armature: NDArray | None = None,
    law: str | int = "stick-slip",
    friction_velocity: float = 0.02,
    stribeck_ratio: float = 1.5,
    stribeck_velocity: float = 0.1,
    lugre_stiffness=None,
    lugre_damping=None,
) -> PlantParams:
    """Checked :class:`PlantParams` of chain ``ch`` (shapes, finite, friction >= 0, law known).

    ``law`` is a name or code of :data:`adaptive_dd.plant.two_link_integrator.FRICTION_CODES`;
    ``armature`` defaults to zeros. LuGre takes ``lugre_stiffness`` and ``lugre_damping`` (n
    values each, > 0 and >= 0) and starts its bristles at rest (:class:`LugreLaw`).

    Raises
    ------
    ParameterError
        Naming the field and the offending value.
    """
    n = ch.jtype.shape[0]
    code = FRICTION_CODES.get(law, law) if isinstance(law, str) else law
    if code not in FRICTION_CODES.values():
        raise ParameterError(f"friction law must be one of {FRICTION_CODES}, got {law!r}")
    arrays = {"pi": (pi, 10 * n), "fv": (fv, n), "fc": (fc, n), "armature": (armature, n)}
    out = {}
    for name, (value, size) in arrays.items():
        a = np.zeros(size) if value is None else np.array(value, dtype=np.float64).reshape(-1)
        if a.shape != (size,) or not np.all(np.isfinite(a)):
            raise ParameterError(f"plant {name} must be {size} finite numbers, got {value!r}")
        if name != "pi" and np.any(a < 0.0):
            raise ParameterError(f"plant {name} must be >= 0, got {a}")
        out[name] = a
    fparams = np.array([friction_velocity, stribeck_ratio, stribeck_velocity], dtype=np.float64)
    if not (np.all(np.isfinite(fparams)) and fparams[0] > 0 and fparams[2] > 0 and fparams[1] >= 1):
        raise ParameterError(
            "friction_velocity and stribeck_velocity must be > 0 and stribeck_ratio >= 1, got "
            f"{friction_velocity!r}, {stribeck_velocity!r}, {stribeck_ratio!r}"
        )
    if code != 3:
        return PlantParams(out["pi"], out["fv"], out["fc"], out["armature"], int(code), fparams)
    bristles = []
    bounds = (("lugre_stiffness", lugre_stiffness, 0.0), ("lugre_damping", lugre_damping, -1.0))
    for name, value, low in bounds:
        a = np.array([np.nan] if value is None else value, dtype=np.float64).reshape(-1)
        if a.shape != (n,) or not (np.all(np.isfinite(a)) and np.all(a > low)):
            bound = "> 0" if low == 0.0 else ">= 0"
            raise ParameterError(f"LuGre plant: {name} must be {n} finite values {bound}, got {value!r}")
        bristles.append(a)
    fp = np.concatenate((fparams, *bristles))
    law_rec = friction_law(3, np.zeros(n))
    return PlantParams(out["pi"], out["fv"], out["fc"], out["armature"], law_rec, fp)


def _by_law(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover
    """One sample under ``law``: an integer code chooses at run time between :func:`_stick_slip`
    and :func:`_smooth` (both compiled), a :func:`friction_law` record at compile time."""
    raise NotImplementedError("compiled only")


@overload(_by_law)
def _by_law_typed(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
    family = getattr(law, "instance_class", None)
    if family is StickSlipLaw:

        def stick_slip(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
            return _stick_slip(ch, pi, fv, fc, arm, fp, q, qd, tau, T, substeps, stuck, sc)

        return stick_slip
    if family is LugreLaw:

        def lugre(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
            return _lugre(ch, pi, fv, fc, arm, fp, q, qd, tau, T, substeps, law.z, stuck, sc)

        return lugre
    if family is SmoothLaw:

        def smooth(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
            return _smooth(ch, pi, fv, fc, arm, law.code, fp, q, qd, tau, T, substeps, stuck, sc)

        return smooth

    def either(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):
        if law == 0:
            return _stick_slip(ch, pi, fv, fc, arm, fp, q, qd, tau, T, substeps, stuck, sc)
        return _smooth(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc)

    return either


def compile_family(ch, pp: PlantParams, q, qd, tau, T: float, substeps: int, stuck, sc) -> None:
    """Compile (or load from numba's cache) the integrator that a compiled step on ``pp`` calls
    (:func:`_stick_slip` or :func:`_smooth`, as :func:`_by_law` chooses), alone, by one step of
    it with these arguments (updated in place), of the types the compiled step passes it: the
    second process of a cold-cache benchmark (:func:`adaptive_dd.closed_loop.precompile.second_process`)
    fills the cache with it without compiling a step around it (the closed loop's own
    compilation inlines the step; numba does not cache :func:`_by_law`'s choice)."""
    law = pp.law
    args = (ch, pp.pi, pp.fv, pp.fc, pp.armature)
    if isinstance(law, LugreLaw):  # a run's record: trial 0's row, as the closed loop passes it
        z = law.z[0] if law.z.ndim == 2 else law.z
        _lugre(*args, pp.fparams, q, qd, tau, T, substeps, z, stuck, sc)
        return
    if not isinstance(law, SmoothLaw):  # the stick-slip record, or a code: both compiled then
        _stick_slip(*args, pp.fparams, q, qd, tau, T, substeps, stuck, sc)
    if not isinstance(law, StickSlipLaw):
        _smooth(*args, int(getattr(law, "code", law)), pp.fparams, q, qd, tau, T, substeps, stuck, sc)


def trial_law(law, i):  # pragma: no cover - compiled
    """The law of trial ``i`` of a run's record: the record itself, or LuGre's with row ``z[i]``."""
    raise NotImplementedError("compiled only")


@overload(trial_law)
def _trial_law_typed(law, i):
    if getattr(law, "instance_class", None) is LugreLaw:

        def row(law, i):
            return LugreLaw(law.code, law.z[i])

        return row

    def same(law, i):
        return law

    return same


@njit(cache=True, inline="always")
def _step(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover
    ok = _by_law(ch, pi, fv, fc, arm, law, fp, q, qd, tau, T, substeps, stuck, sc)
    for i in range(q.shape[0]):
        ok &= np.isfinite(q[i]) and np.isfinite(qd[i])
    return ok


@njit(cache=True)
def plant_step(ch, pp, q, qd, tau, T, substeps, stuck):  # pragma: no cover - compiled
    """Advance one arm by one sample in place under the held torque ``tau``.

    Parameters
    ----------
    ch : Chain
    pp : PlantParams
    q, qd : ndarray, shape (n,)
        Joint positions [rad or m] and velocities, updated in place.
    tau : ndarray, shape (n,)
        Applied joint torque [N m or N], held over the sample.
    T : float
        Sample period [s].
    substeps : int
        RK4 steps per sample (further split where needed: :mod:`adaptive_dd.plant.chain_rk4`).
    stuck : ndarray of bool, shape (n,)
        Output: joints held at rest by Coulomb friction at the end of the sample
        (stick-slip law; False under the smooth laws). Modes are decided anew from
        the velocities at every substep, so its input value is not used.

    Returns
    -------
    bool
        False if a mass matrix was not positive definite or the state is not finite.
    """
    return plant_step_in(ch, pp, q, qd, tau, T, substeps, stuck, _scratch(q.shape[0]))


@njit(cache=True)
def plant_scratch(n):  # pragma: no cover - compiled
    """The scratch arrays of one arm's step (:func:`plant_step_in`), allocated once."""
    return _scratch(n)


@njit(cache=True, inline="always")
def plant_step_in(ch, pp, q, qd, tau, T, substeps, stuck, sc):  # pragma: no cover - compiled
    """:func:`plant_step` with its scratch ``sc`` (:func:`plant_scratch`) given: no
    allocation per sample (a closed loop allocates it once per trial)."""
    return _step(ch, pp.pi, pp.fv, pp.fc, pp.armature, pp.law, pp.fparams, q, qd, tau, T, substeps, stuck, sc)


@njit(cache=True)
def plant_run(ch, pp, q, qd, tau, T, substeps, q_out, qd_out):  # pragma: no cover - compiled
    """Open loop over a torque sequence: ``tau`` (n_samples, n) held one sample each.

    ``q, qd`` (n,) are the initial state (updated in place to the final one);
    ``q_out, qd_out`` (n_samples, n) receive the state after each sample. Returns
    the number of samples completed (< n_samples: the step failed, see
    :func:`plant_step`).
    """
    n = q.shape[0]
    sc = _scratch(n)
    stuck = np.zeros(n, dtype=np.bool_)
    for k in range(tau.shape[0]):
        if not _step(
            ch, pp.pi, pp.fv, pp.fc, pp.armature, pp.law, pp.fparams, q, qd, tau[k], T, substeps, stuck, sc
        ):
            return k
        for i in range(n):
            q_out[k, i] = q[i]
            qd_out[k, i] = qd[i]
    return tau.shape[0]
