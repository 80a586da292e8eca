"""Derivative filter banks of Section 4, discretized by the bilinear transform (eq. 21).

M1 (eq. 18): ``G0 = 1/(1 + tau_f s)^3``, ``G1 = s G0``, ``G2 = s^2 G0``.
M2 (eq. 20): ``G0 = 1/(1 + tau_f s)^2``, ``G1 = s G0``.

A bank is one single-input, multi-output system: the chain ``w = G0 u`` in
controllable canonical form, whose state holds ``w, w', w''`` = ``G0 u, G1 u, G2 u``.
python-control discretizes it (Tustin); each design is kept in the user's cache folder, so a
later process reads it instead of importing python-control again (about 1.3 s of a warm run).
The bank runs two ways:

* streaming, one sample at a time, carrying its state (:func:`filter_step`,
  :class:`StreamingFilter`): the online path;
* over a whole record with ``scipy.signal.lfilter`` on each output's discrete
  transfer function (:func:`filter_record`), designed separately by
  ``control.c2d`` on the transfer function: the offline path.

The tests check that both give the same output.
"""

from __future__ import annotations

import os
import tempfile
import zipfile
from dataclasses import dataclass
from importlib import metadata
from math import comb
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError, SignalError

__all__ = [
    "FilterBank",
    "StreamingFilter",
    "design_filter_bank",
    "filter_record",
    "filter_step",
    "summing_realisation",
]

Array = NDArray[np.float64]

ORDERS = {"M1": 3, "M2": 2}
"""Order of G0 for each method (eqs. 18, 20)."""


@dataclass(frozen=True)
class FilterBank:
    """A discretized SIMO filter bank: outputs ``[G0, G1, (G2)]`` of one input.

    Attributes
    ----------
    method : {"M1", "M2"}
    tau_f : float
        Filter time constant [s].
    sample_period : float
        T [s].
    A, B, C, D : ndarray
        Discrete state space (n x n, n x 1, n_out x n, n_out x 1), from
        ``control.c2d(..., method="tustin")``.
    num, den : tuple of ndarray
        Discrete transfer function of each output (for ``lfilter``), from
        ``control.c2d`` of ``G_k`` as a transfer function.
    """

    method: str
    tau_f: float
    sample_period: float
    A: Array
    B: Array
    C: Array
    D: Array
    num: tuple
    den: tuple

    @property
    def order(self) -> int:
        return self.A.shape[0]

    @property
    def n_outputs(self) -> int:
        return self.C.shape[0]

    def steady_state(self, u0: ArrayLike) -> Array:
        """State for a constant input ``u0 (...)``: shape ``(..., order)``."""
        xs = np.linalg.solve(np.eye(self.order) - self.A, self.B[:, 0])
        return np.asarray(u0, dtype=float)[..., None] * xs


def design_filter_bank(method: str, tau_f: float, sample_period: float = 1e-3) -> FilterBank:
    """Design the bank of method M1 or M2 (eqs. 18, 20) and discretize it (eq. 21).


    Parameters
    ----------
    method : {"M1", "M2"}
        The paper's method: M1 differentiates the position (eq. 18), M2 filters the measured
        velocity (eq. 20).
    tau_f : float
        The filters' time constant [s], > 0.
    sample_period : float
        T [s], > 0 (Tustin discretisation).

    Returns
    -------
    FilterBank
        The continuous and discrete state-space forms of ``G0`` and ``G1``.


    Examples
    --------
    >>> from adaptive_dd.identification.filters import design_filter_bank
    >>> bank = design_filter_bank("M2", tau_f=0.01, sample_period=1e-3)
    >>> bank.method, bank.A.shape  # G0 = 1 / (1 + tau_f s)^2 and G1 = s G0, as one state-space
    ('M2', (2, 2))

    Raises
    ------
    ParameterError
        Unknown method, ``tau_f <= 0`` or ``sample_period <= 0``.
    """
    if method not in ORDERS:
        raise ParameterError(f"method must be 'M1' or 'M2', got {method!r}")
    if not np.isfinite(tau_f) or tau_f <= 0:
        raise ParameterError(f"filter time constant tau_f must be > 0, got {tau_f}")
    if not np.isfinite(sample_period) or sample_period <= 0:
        raise ParameterError(f"sample_period T must be > 0, got {sample_period}")
    cached = _read_cached_bank(method, float(tau_f), float(sample_period))
    if cached is not None:
        return cached
    bank = _design(method, float(tau_f), float(sample_period))
    _write_cached_bank(bank)
    return bank


def _design(method: str, tau_f: float, sample_period: float) -> FilterBank:
    """:func:`design_filter_bank`'s design by python-control (arguments checked)."""
    import control  # here: it imports matplotlib and SciPy's signal and statistics (1-2 CPU s)

    n = ORDERS[method]
    # (1 + tau s)^n = sum_k comb(n, k) tau^k s^k; chain state z = [w, w', ..., w^(n-1)]
    coeff = np.array([comb(n, k) * tau_f**k for k in range(n + 1)])
    a = np.zeros((n, n))
    a[:-1, 1:] = np.eye(n - 1)
    a[-1, :] = -coeff[:n] / coeff[n]
    b = np.zeros((n, 1))
    b[-1, 0] = 1.0 / coeff[n]
    c = np.eye(n)  # outputs G0, G1, ..., G_{n-1}
    n_out = n  # M1: G0, G1, G2; M2: G0, G1
    sysd = control.c2d(control.ss(a, b, c, np.zeros((n_out, 1))), sample_period, method="tustin")
    den_c = coeff[::-1]  # highest power first
    nums, dens = [], []
    for k in range(n_out):
        num_c = np.zeros(k + 1)
        num_c[0] = 1.0  # s^k
        tfd = control.c2d(control.tf(num_c, den_c), sample_period, method="tustin")
        nd, dd = control.tfdata(tfd)
        nums.append(np.asarray(nd[0][0], dtype=float))
        dens.append(np.asarray(dd[0][0], dtype=float))
    return FilterBank(
        method=method,
        tau_f=float(tau_f),
        sample_period=float(sample_period),
        A=np.asarray(sysd.A),
        B=np.asarray(sysd.B),
        C=np.asarray(sysd.C),
        D=np.asarray(sysd.D),
        num=tuple(nums),
        den=tuple(dens),
    )


_BANK_FIELDS = ("A", "B", "C", "D")


def _bank_cache_path(method: str, tau_f: float, sample_period: float) -> Path:
    """The design's file in ``$XDG_CACHE_HOME/adaptive_dd/filters`` (default ``~/.cache``), named by
    the method, ``tau_f`` and ``T`` to the last bit and python-control's version."""
    try:
        version = metadata.version("control")
    except metadata.PackageNotFoundError:
        version = "none"
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "adaptive_dd" / "filters"
    return base / f"{method}-{tau_f.hex()}-{sample_period.hex()}-control{version}.npz"


def _read_cached_bank(method: str, tau_f: float, sample_period: float) -> FilterBank | None:
    """The bank designed before with these arguments, from its file; None when there is none or it
    cannot be read whole (it is then designed again and the file written again)."""
    path = _bank_cache_path(method, tau_f, sample_period)
    try:
        with np.load(path) as z:
            n_out = int(z["n_out"])
            arrays = {k: np.array(z[k], dtype=float) for k in _BANK_FIELDS}
            num = tuple(np.array(z[f"num{k}"], dtype=float) for k in range(n_out))
            den = tuple(np.array(z[f"den{k}"], dtype=float) for k in range(n_out))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile, EOFError):
        return None
    n = ORDERS[method]
    shapes_ok = arrays["A"].shape == (n, n) and arrays["B"].shape == (n, 1) and n_out == n
    if not shapes_ok or not all(np.all(np.isfinite(a)) for a in (*arrays.values(), *num, *den)):
        return None
    return FilterBank(method=method, tau_f=tau_f, sample_period=sample_period, num=num, den=den, **arrays)


def _write_cached_bank(bank: FilterBank) -> None:
    """Write ``bank``'s design to its file (atomically: a reader sees the whole file or none); a
    folder that cannot be written leaves the design uncached (designed again next process)."""
    path = _bank_cache_path(bank.method, bank.tau_f, bank.sample_period)
    arrays = {k: getattr(bank, k) for k in _BANK_FIELDS}
    arrays.update({f"num{k}": v for k, v in enumerate(bank.num)})
    arrays.update({f"den{k}": v for k, v in enumerate(bank.den)})
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "wb") as f:
            np.savez(f, n_out=len(bank.num), **arrays)
        os.replace(tmp, path)
    except OSError:
        return


def summing_realisation(bank: FilterBank) -> tuple[Array, Array, Array, Array]:
    """The bank as one state driven by one input per output, with the sum of the outputs as its output.

    The bank's outputs share their poles (one ``A``), so the transposed (dual, observable-form)
    realisation ``x+ = A^T x + sum_k C_k^T u_k``, ``y = B^T x + sum_k D_k u_k`` has from input
    ``k`` the transfer function ``B^T (zI - A^T)^-1 C_k^T + D_k = C_k (zI - A)^-1 B + D_k = G_k``:
    ``y = sum_k G_k u_k`` costs one state of order ``bank.order`` instead of one per input.
    The state that continues constant inputs ``u_k`` (steady state) is
    ``(I - A^T)^-1 sum_k C_k^T u_k``.

    Returns
    -------
    A : ndarray, shape (order, order)
        ``bank.A^T``.
    B : ndarray, shape (order, n_outputs)
        Column k: the input vector of ``u_k`` (``bank.C[k]``).
    C : ndarray, shape (order,)
        The output vector (``bank.B[:, 0]``).
    D : ndarray, shape (n_outputs,)
        Feedthrough of each input (``bank.D[:, 0]``).
    """
    return (
        np.ascontiguousarray(bank.A.T),
        np.ascontiguousarray(bank.C.T),
        np.ascontiguousarray(bank.B[:, 0]),
        np.ascontiguousarray(bank.D[:, 0]),
    )


def filter_step(bank: FilterBank, x: Array, u: Array) -> tuple[Array, Array]:
    """One sample of the bank on many channels (pure function).

    Parameters
    ----------
    x : ndarray, shape (..., order)
        State of each channel.
    u : ndarray, shape (...)
        Input sample of each channel.

    Returns
    -------
    x_next : ndarray, shape (..., order)
    y : ndarray, shape (..., n_outputs)
        ``[G0 u, G1 u, (G2 u)]`` at this sample.
    """
    y = x @ bank.C.T + u[..., None] * bank.D[:, 0]
    x_next = x @ bank.A.T + u[..., None] * bank.B[:, 0]
    return x_next, y


def filter_record(
    bank: FilterBank, u: ArrayLike, axis: int = -1, initial: ArrayLike | None = None, outputs=None
) -> Array:
    """Filter a whole record with ``scipy.signal.lfilter``.

    Parameters
    ----------
    u : array_like
        Signal(s); time runs along ``axis``.
    axis : int
        Time axis of ``u``.
    initial : array_like, optional
        Start from the steady state of this constant input (shape of ``u``
        without the time axis); default: zero state.
    outputs : sequence of int, optional
        The outputs to compute, in this order (default all): a caller that needs one of them does
        not filter the record through the others.

    Returns
    -------
    ndarray, shape ``u.shape + (n_outputs,)``
        The outputs ``G0 u, G1 u, (G2 u)`` (or those of ``outputs``) on a new last axis.
    """
    from scipy import signal  # here: SciPy's signal imports its statistics (2 CPU s per process)

    u = np.asarray(u, dtype=float)
    if u.ndim == 0:
        raise SignalError("filter_record needs at least one time axis")
    u_t = np.moveaxis(u, axis, -1)
    outs = []
    chosen = range(len(bank.num)) if outputs is None else outputs
    for num, den in ((bank.num[k], bank.den[k]) for k in chosen):
        if initial is None:
            y = signal.lfilter(num, den, u_t, axis=-1)
        else:
            zi = signal.lfilter_zi(num, den) * np.asarray(initial, dtype=float)[..., None]
            y, _ = signal.lfilter(num, den, u_t, axis=-1, zi=zi)
        outs.append(np.moveaxis(y, -1, axis if axis >= 0 else u.ndim + axis))
    return np.stack(outs, axis=-1)


class StreamingFilter:
    """The bank run sample by sample on ``n`` channels (stateful wrapper of :func:`filter_step`).

    Parameters
    ----------
    bank : FilterBank
    shape : tuple
        Shape of one input sample (batch and channel axes).
    initial : array_like, optional
        Start in the steady state of this constant input (default zero state).
    """

    def __init__(self, bank: FilterBank, shape: tuple, initial: ArrayLike | None = None) -> None:
        self.bank = bank
        self.shape = tuple(shape)
        self.x = (
            np.zeros((*self.shape, bank.order))
            if initial is None
            else np.broadcast_to(bank.steady_state(initial), (*self.shape, bank.order)).copy()
        )

    def __call__(self, u: ArrayLike) -> Array:
        """Feed one sample ``u (shape)``; return ``(shape..., n_outputs)``."""
        u = np.asarray(u, dtype=float)
        if u.shape != self.shape:
            raise SignalError(f"StreamingFilter expects samples of shape {self.shape}, got {u.shape}")
        self.x, y = filter_step(self.bank, self.x, u)
        return y
