"""The compiled closed loop of a plug-in controller on an N-joint arm.

A compiled plug-in (the protocol: ``docs/controllers.md``, "Compiled plug-ins") gives four
``numba.njit`` functions, ``reset``, ``command``, ``observe`` and optionally ``estimate``, and a
value of its parameters (anything numba compiles: a tuple of arrays and floats). The loop here is
:func:`adaptive_dd.closed_loop.glue.trial_samples` with the built-in law and estimator replaced by
those functions, handed to it as arguments: numba compiles one specialisation of the loop per
plug-in, with the plug-in's functions inlined or called directly, no Python between samples. The
per-sample glue (measurement and dropouts, divergence rule, actuator, plant step, failure freeze,
streamed sums, recordings, alarms, the estimate's record) is the built-ins' own
(:func:`~adaptive_dd.closed_loop.glue.measure_sample`,
:func:`~adaptive_dd.closed_loop.glue.apply_sample`,
:func:`~adaptive_dd.closed_loop.glue.accumulate_sample`,
:func:`~adaptive_dd.closed_loop.glue.record_estimate`), so results, failures and metrics follow
the same rules.

Before ``command`` the loop computes the model terms the plug-in declares (``needs``, bits
:data:`NEED_GRAVITY`, :data:`NEED_MASS_MATRIX`, :data:`NEED_BIAS`) at the measured state, of the
controllers' model or, for a plug-in that needs the true model, of the trial's plant in the current
segment (the model of the built-in oracles), and hands it the arm's kernels of that model
(:data:`NEED_REGRESSOR`: :mod:`adaptive_dd.controllers.kernels`, which the plug-in calls at the
reference velocity and acceleration of its law).

Each plug-in's loop is compiled once and cached like the built-ins' kernels (:func:`plugin_loop`):
numba keys a function-typed argument by the function object, so a loop taking the plug-in's
functions as arguments would never be found again in a new process. The loop of a plug-in is
instead a small module written into the cache folder, whose ``plugin_block`` calls the
plug-in's functions as globals; its name is a hash of this file and of the plug-in's functions
as numba compiles them, with the ``njit`` functions and the values they reach
(:func:`plugin_key`), so an edit of any of them gives a new module and one compilation, and the
cache folder is keyed by the package's kernels (:mod:`adaptive_dd._numba_cache`).
"""

from __future__ import annotations

import importlib.util
import itertools
import os
import sys
import threading
import types
from pathlib import Path

import numpy as np
from numba import njit

from adaptive_dd.closed_loop.borrow import borrowed, keep_alive
from adaptive_dd.closed_loop.chain_choices import _chain_plant_advance
from adaptive_dd.closed_loop.glue import (
    _bound,
    _segment,
    accumulate_sample,
    apply_sample,
    measure_sample,
    record_estimate,
)
from adaptive_dd.closed_loop.plugin_key import function_key
from adaptive_dd.closed_loop.tool_frame import accumulate_tool
from adaptive_dd.controllers.kernels import arm_kernels, with_model
from adaptive_dd.plant.chain_dynamics import mass_matrix_in, rnea_ref_in, workspace
from adaptive_dd.plant.integrator import plant_scratch

__all__ = [
    "NEEDS",
    "NEED_BIAS",
    "NEED_GRAVITY",
    "NEED_MASS_MATRIX",
    "NEED_REGRESSOR",
    "TRIALS",
    "no_estimate",
    "plugin_key",
    "plugin_loop",
]

NEED_GRAVITY, NEED_MASS_MATRIX, NEED_BIAS, NEED_REGRESSOR = 1, 2, 4, 8
NEEDS = {
    "gravity": NEED_GRAVITY,
    "mass_matrix": NEED_MASS_MATRIX,
    "bias": NEED_BIAS,
    "regressor": NEED_REGRESSOR,
}
"""What a compiled plug-in may declare (``needs``), name -> bit: ``gravity`` g(q) (n,),
``mass_matrix`` M(q) with the armature (n, n), ``bias`` the torque at zero acceleration
C(q, qd) qd + g(q) + fv qd + fc sgn(qd) (n,) [N m, kg m^2], each at the measured q, qd; ``regressor``
the arm's kernels (``terms[3]``) to call :func:`~adaptive_dd.controllers.kernels.reference_torque`
and :func:`~adaptive_dd.controllers.kernels.payload_regressor` with."""


def _model_terms(ch, pi, need, q, qd, zero, w, g, m, c):  # pragma: no cover - compiled
    """The declared terms of the model ``pi (13 n,)`` at ``q, qd (n,)`` into ``g, m, c``."""
    n = q.shape[0]
    links = pi[: 10 * n]
    if need & 1:
        rnea_ref_in(ch, links, q, zero, zero, zero, w, g)  # friction and armature: none at rest
    if need & 2:
        mass_matrix_in(ch, links, q, w, m)
        for j in range(n):
            m[j, j] += pi[12 * n + j]
    if need & 4:
        rnea_ref_in(ch, links, q, qd, qd, zero, w, c)
        for j in range(n):
            c[j] += pi[10 * n + j] * qd[j] + pi[11 * n + j] * np.sign(qd[j])


_model_terms_c = njit(inline="always")(_model_terms)
_apply_chain = njit(inline="always")(_bound(apply_sample.py_func, plant_advance=_chain_plant_advance))


def _no_estimate(p, x, out):  # pragma: no cover - compiled
    """The ``estimate`` of a plug-in that reports none (never called: ``estimates`` is false)."""
    return None


no_estimate = njit(_no_estimate)


def _plugin_trial(
    i, k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, ch, pis, pj, pmap, need, p, x,
    reset, command, observe, estimate, estimates,
):  # pragma: no cover - compiled  # fmt: skip
    """Samples ``k0`` to ``k1 - 1`` of trial i: :func:`~adaptive_dd.closed_loop.glue.trial_samples`
    with the plug-in's ``command``, ``observe`` and ``estimate`` in place of the built-in law and
    estimator; ``reset`` of trial i's state row ``x[i]`` at sample 0. ``pis (S or 1, G or 1,
    13 n)`` the model whose terms ``need`` asks for (``ch`` its kinematics, ``pj`` the payload's
    link, ``pmap (10, 10)`` its payload map), ``p`` the plug-in's parameters. The run's records
    and the loop's scratch are borrowed as the built-ins' are
    (:func:`~adaptive_dd.closed_loop.borrow.borrowed`); the plug-in's own ``p`` and ``x`` are not."""
    rc, io, pl, ts, acc, rec, alarms, noise, drop = borrowed((rc, io, pl, ts, acc, rec, alarms, noise, drop))
    T, max_error, max_speed, q_d, qd_d, qdd_d = rc.T, rc.max_error, rc.max_speed, rc.q_d, rc.qd_d, rc.qdd_d
    seg_start, seg_end, seg_settled = rc.seg_start, rc.seg_end, rc.seg_settled
    lim, lsb, saturate, quantize_dac = io.lim, io.lsb, io.saturate, io.quantize_dac
    res, std, quantize_encoder = io.res, io.std, io.quantize_encoder
    q, qd, stuck, failed, failed_at = ts.q, ts.qd, ts.stuck, ts.failed, ts.failed_at
    held_q, held_qd, n_dropped, failed_cmd = ts.held_q, ts.held_qd, ts.n_dropped, ts.failed_cmd
    sum_e2, sum_e2_joint, max_e, sum_tau2 = acc.sum_e2, acc.sum_e2_joint, acc.max_e, acc.sum_tau2
    n_saturated, sum_e2_settled, e_norm = acc.n_saturated, acc.sum_e2_settled, acc.e_norm
    first_saturated = acc.first_saturated
    ee_sum_p2, ee_max_p, ee_sum_th2 = acc.ee_sum_p2, acc.ee_max_p, acc.ee_sum_th2
    ee_index, ee_links, ee_ref = rc.ee_index, rc.ee_links, rc.ee_ref
    q_rec, qd_rec, tau_rec, sat_rec = rec.q, rec.qd, rec.tau, rec.saturated
    sigma_rec, sigma_end = rec.sigma, rec.sigma_end
    alarm_t, n_alarms = alarms.times, alarms.count
    n = q.shape[1]
    owned = (
        np.empty((8, n)), np.full(sigma_end.shape[2], np.nan), plant_scratch(n), workspace(n), np.zeros(n),
        np.zeros((max(ee_index.shape[0], 1), 12)), np.zeros(9),
        np.full(n, np.nan), np.full((n, n), np.nan), np.full(n, np.nan),  # g, m, c: NaN unless declared
    )  # fmt: skip
    rows, sig, pw, w, zero, tw, tr, g, m, c = borrowed(owned)
    qm, qdm, qm_obs, qdm_obs = rows[0], rows[1], rows[2], rows[3]
    cmd, tau, e, prev = rows[4], rows[5], rows[6], rows[7]
    xi = x[i]
    ip = i if pis.shape[0] > 1 else 0
    kin = arm_kernels(ch, pis[ip, 0], pj, pmap)  # its scratch: once per trial
    if k0 == 0:
        reset(p, xi)
    has_drop = drop.shape[1] > 0
    for k in range(k0, k1):
        s = _segment(seg_start, k)
        lost = has_drop and drop[i, k - k0]
        measure_sample(
            q, qd, held_q, held_qd, n_dropped, res, std, quantize_encoder, i, noise[i, k - k0], lost,
            qm, qdm, qm_obs, qdm_obs,
        )  # fmt: skip
        pi = pis[ip, s if pis.shape[1] > 1 else 0]
        if need & 7:
            _model_terms_c(ch, pi, need, qm, qdm, zero, w, g, m, c)
        command(p, xi, qm, qdm, q_d[k], qd_d[k], qdd_d[k], (g, m, c, with_model(kin, pi)), cmd)
        mask = _apply_chain(
            T, max_error, max_speed, q_d, lim, lsb, saturate, quantize_dac, pl, pw,
            q, qd, stuck, failed, failed_at, failed_cmd, q_rec, qd_rec, tau_rec, sat_rec, i, k, cmd, tau, e,
            prev, s,
        )  # fmt: skip
        accumulate_sample(
            sum_e2, sum_e2_joint, max_e, sum_tau2, n_saturated, first_saturated, sum_e2_settled, e_norm,
            seg_settled, i, s, k, e, tau, mask,
        )  # fmt: skip
        accumulate_tool(ee_index, ee_links, ee_ref, ee_sum_p2, ee_max_p, ee_sum_th2, i, s, k, prev, tw, tr)
        if observe(p, xi, qm_obs, qdm_obs, tau) == 1:
            if n_alarms[i] < alarm_t.shape[1]:
                alarm_t[i, n_alarms[i]] = k * T
            n_alarms[i] += 1
        if estimates and (k == seg_end[s] - 1 or i < sigma_rec.shape[0]):
            estimate(p, xi, sig)
            record_estimate(seg_end, sigma_end, sigma_rec, i, k, s, sig)
    keep_alive(owned)


_plugin_trial_c = njit(inline="always")(_plugin_trial)


def _two_link_terms(ch, pi, need, q, qd, zero, w, g, m, c):  # pragma: no cover - compiled
    """:func:`_model_terms` of the paper's arm's closed forms, base parameters ``pi (7,)`` =
    ``[J1 J2 r b1 b2 d1 d2]`` (eqs. 3-8): M(q), C(q, qd) qd + B qd + D sgn(qd), and no gravity
    (the arm moves in a horizontal plane)."""
    if need & 1:
        g[0] = 0.0
        g[1] = 0.0
    if need & 2:
        rc = pi[2] * np.cos(q[1])
        m[0, 0] = pi[0] + pi[1] + 2.0 * rc
        m[0, 1] = pi[1] + rc
        m[1, 0] = pi[1] + rc
        m[1, 1] = pi[1]
    if need & 4:
        rs = pi[2] * np.sin(q[1])
        c[0] = -rs * qd[1] * (2.0 * qd[0] + qd[1]) + pi[3] * qd[0] + pi[5] * np.sign(qd[0])
        c[1] = rs * qd[0] * qd[0] + pi[4] * qd[1] + pi[6] * np.sign(qd[1])


def _no_kernels(ch, pi, pj, pmap):  # pragma: no cover - compiled
    """The arm's kernels on the closed forms: none (a plug-in that needs them is refused)."""
    return None


def _no_model(kin, pi):  # pragma: no cover - compiled
    """:func:`~adaptive_dd.controllers.kernels.with_model` of no kernels: none."""
    return None


def _empty(n):  # pragma: no cover - compiled
    """The closed forms' plant step and model terms need no scratch."""
    return np.empty(0)


def _two_link_trial():
    """:func:`_plugin_trial` of the paper's arm on its closed forms (``plugin_loop(...,
    "two-link")``): its plant's step (:func:`~adaptive_dd.closed_loop.glue.apply_sample`, the
    plant's step chosen by type), the model terms of :func:`_two_link_terms` and no arm kernels;
    its records borrowed as on any arm (as they are, as the built-ins' two-link loop has them, it
    ran 1.4x slower per sample)."""
    import adaptive_dd.benchmark.compiled  # noqa: F401 - the two-link plant's step, by type
    from adaptive_dd.closed_loop.glue import _bound, apply_sample

    trial = _bound(
        _plugin_trial, _apply_chain=apply_sample,
        _model_terms_c=njit(inline="always")(_two_link_terms), arm_kernels=njit(inline="always")(_no_kernels),
        with_model=njit(inline="always")(_no_model), workspace=njit(inline="always")(_empty),
        plant_scratch=njit(inline="always")(_empty),
    )  # fmt: skip
    return njit(inline="always")(trial)


def __getattr__(name: str):
    """``_plugin_trial_two_link_c``, made when a two-link loop first asks for it."""
    if name == "_plugin_trial_two_link_c":
        globals()[name] = _two_link_trial()
        return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


_LOOP_SOURCE = '''"""The compiled closed loop of one compiled plug-in, written by
adaptive_dd.closed_loop.plugin_loop.plugin_loop (key {key}): its reset, command, observe and
estimate are this module's globals, set before the first call."""

from numba import njit

from adaptive_dd.closed_loop.plugin_loop import {trial} as _trial

reset = command = observe = estimate = None


def _plugin_block(
    i0, i1, k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, ch, pis, pj, pmap, need, p, x, estimates,
):  # fmt: skip
    for i in range(i0, i1):
        _trial(
            i, k0, k1, noise, drop, rc, io, pl, ts, acc, rec, alarms, ch, pis, pj, pmap, need, p, x,
            reset, command, observe, estimate, estimates,
        )  # fmt: skip


plugin_block = njit(nogil=True, cache={cache})(_plugin_block)
'''
"""The module of one plug-in's loop: :func:`_plugin_trial` over a range of trials, the plug-in's
functions read from the module's globals (numba compiles calls to them in, as to any global
``njit`` function)."""

_LOOPS: dict = {}
_UNKEYED = itertools.count()

KEEP_LOOPS = 16
"""How many plug-in loops the cache folder keeps: each edit of a plug-in numba would compile
is a new loop (about 0.3 MB compiled); beyond the :data:`KEEP_LOOPS` last used, a loop not used
for :data:`KEEP_AGE` seconds is removed with its compiled code when another loop is made."""

KEEP_AGE = 86400.0
"""[s] A loop used this recently is kept however many there are (another process may be running it)."""


def _mark_used(path: Path) -> None:
    """Stamp ``path``'s loop as used now (a ``.used`` file beside it: the module's own time stamp
    keys numba's cache and stays), then prune the folder (:data:`KEEP_LOOPS`)."""
    try:
        path.with_suffix(".used").touch()
        prune_loops(path.parent)
    except OSError:  # a cache folder that cannot be written is not this run's problem
        pass


def prune_loops(
    folder: Path, keep: int = KEEP_LOOPS, age: float = KEEP_AGE, now: float | None = None
) -> list[str]:
    """Remove the loops of ``folder`` beyond the ``keep`` last used that were not used for ``age``
    seconds: each one's module, its ``.used`` stamp and numba's files of it (in the cache's
    ``plugin_loops_*`` folders beside ``folder``). Returns the keys removed."""
    import time

    now = time.time() if now is None else now

    def used(p: Path) -> float:
        stamp = p.with_suffix(".used")
        return stamp.stat().st_mtime if stamp.exists() else p.stat().st_mtime

    loops = sorted(folder.glob("loop_*.py"), key=used, reverse=True)
    gone = []
    for p in loops[keep:]:
        if now - used(p) < age:
            continue
        stem = p.stem
        for q in (p, p.with_suffix(".used"), *(
            f for d in folder.parent.glob(f"{folder.name}_*") for f in d.glob(f"{stem}.*")
        )):  # fmt: skip
            q.unlink(missing_ok=True)
        gone.append(stem.removeprefix("loop_"))
    return gone


_LOCK = threading.Lock()

TRIALS = {"chain": "_plugin_trial_c", "two-link": "_plugin_trial_two_link_c"}
"""The trial a plug-in's loop runs, per runtime: an arm's general kernels (any arm from a URDF)
or the paper's arm on its closed forms."""


def plugin_key(functions, runtime: str = "chain") -> str | None:
    """The key of a plug-in's loop: :func:`~adaptive_dd.closed_loop.plugin_key.function_key` of its
    ``functions``, salted with this module's file (the loop's code) and the runtime's trial. The
    same functions give the same key in any process; an edit numba would compile gives another;
    None when a function reads what the key cannot follow."""
    return function_key(functions, Path(__file__).read_bytes() + TRIALS[runtime].encode())


def loop_cached(functions, runtime: str = "chain") -> bool:
    """Whether :func:`plugin_loop` of these ``functions`` would load its loop from numba's cache
    (numba's index of the loop's module, which numba keys by the module's text, is in the cache
    folder), not compile it: ``validate``'s estimate of a run's compilation."""
    import numba

    key = plugin_key(functions, runtime)
    if not key or not numba.config.CACHE_DIR:
        return False
    return any(Path(numba.config.CACHE_DIR).glob(f"plugin_loops*/loop_{key}._plugin_block-*.nbi"))


def plugin_loop(functions, runtime: str = "chain"):
    """The compiled loop (``plugin_block``) of a plug-in's ``functions`` (``reset, command,
    observe, estimate``): called as :func:`~adaptive_dd.closed_loop.glue.chain_loop_block` is
    (:func:`~adaptive_dd.closed_loop.glue.in_threads`), with the block's records, the model, the
    plug-in's ``need``, ``p``, ``x`` and ``estimates``; ``runtime`` a key of :data:`TRIALS` (the
    two-link records and plant, the closed forms' sigma as the model ``pis (S or 1, G or 1, 7)``,
    ``ch`` None). Its module (:data:`_LOOP_SOURCE`) is written into numba's cache folder under
    :func:`plugin_key` and cached: a later run, in any process, loads the loop instead of
    compiling it (a few seconds for a small law). A plug-in whose functions cannot be keyed, or a
    cache folder that cannot be written, gives a module of this process only, compiled again by
    every run; why is the loop's ``adaptive_dd_uncached`` (None when cached). One thread at a
    time: a module is in ``sys.modules`` before it has run."""
    with _LOCK:
        memo = (runtime, *(id(f) for f in functions))
        if memo not in _LOOPS:
            _LOOPS[memo] = (_make_loop(functions, runtime), functions)  # the functions kept: ids stay theirs
        return _LOOPS[memo][0]


def _make_loop(functions, runtime: str):
    """:func:`plugin_loop`'s module, made or found, its plug-in functions set."""
    import numba

    key = plugin_key(functions, runtime)
    why = None
    if not key:
        why = (
            "a function of it reads what the cache cannot key, such as a closure's value; pass such "
            "values through parameters() (docs/controllers.md)"
        )
    if key and not numba.config.CACHE_DIR:
        why = "numba's cache folder is not set"
    folder = Path(numba.config.CACHE_DIR) / "plugin_loops" if why is None else None
    unkeyed = f"adaptive_dd_plugin_loop_p{os.getpid()}_{next(_UNKEYED)}"
    name = f"adaptive_dd_plugin_loop_{key}" if folder else unkeyed
    path = None
    if folder is not None:
        path = folder / f"loop_{key}.py"
        try:
            if not path.exists():  # written once: numba's cache is keyed by the file's time stamp
                folder.mkdir(parents=True, exist_ok=True)
                tmp = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
                tmp.write_text(_LOOP_SOURCE.format(key=key, cache=True, trial=TRIALS[runtime]))
                try:  # the first of processes writing at once wins; the others keep its file
                    os.link(tmp, path)
                except FileExistsError:
                    pass
                finally:
                    tmp.unlink()
        except OSError as exc:
            path, name, why = None, unkeyed, f"its module could not be written in {folder} ({exc.strerror})"
    if path is not None:
        _mark_used(path)
    if name in sys.modules:
        module = sys.modules[name]
    elif path is not None:
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # numba finds a cached loop's globals by the module's name
        spec.loader.exec_module(module)
    else:
        module = types.ModuleType(name)
        sys.modules[name] = module
        source = _LOOP_SOURCE.format(key=key, cache=False, trial=TRIALS[runtime])
        exec(compile(source, f"<{name}>", "exec"), module.__dict__)
    module.reset, module.command, module.observe, module.estimate = functions
    module.plugin_block.adaptive_dd_uncached = why
    return module.plugin_block
