"""The second process of a cold-cache benchmark (:class:`adaptive_dd._numba_cache.Compiling`): it
compiles into numba's cache kernels the closed loop and the report call while the first process
compiles the rest: on an N-joint arm the plant's step, the law's pieces and the report's kernels
while the first compiles the estimator's step; on the paper's arm (its closed forms) the
estimator's step and the report's regressor while the first compiles the closed loop. Apart
from :mod:`adaptive_dd._numba_cache` so that the cache module does not import the scenario loader
(which imports it: no import circle)."""

from __future__ import annotations

from adaptive_dd._numba_cache import READY

__all__ = ["plant_kernels", "second_process", "second_process_two_link"]


def second_process(source: str) -> None:
    """The second process of a cold-cache benchmark on the N-joint arm of scenario file
    ``source`` (:class:`~adaptive_dd._numba_cache.Compiling`). It compiles into the cache the
    plant's integrator and the law's pieces that the closed loop calls, then prints ``READY``;
    then the kernels that ``adaptive_ct``'s set-up and the report call (its initial model, the
    information times, the detection limit). With records built as the run builds them, so with
    the same argument types; on a few samples of the reference. The plant's integrator alone
    (:func:`~adaptive_dd.plant.integrator.compile_family`): a step compiled around it would be
    compiled again, inlined, in the closed loop (4 CPU s of the critical path)."""
    from types import SimpleNamespace

    import numpy as np

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.closed_loop.controllers import SlotineLi
    from adaptive_dd.closed_loop.information import _chain
    from adaptive_dd.closed_loop.laws import OBS_ROWS, law_trial
    from adaptive_dd.identification import online

    sc = load_scenario(source)
    T, n, arm = sc.sample_period, sc.n_joints, sc.arm
    z = np.zeros((8, n))
    plant_kernels(sc)
    pi, theta, out = np.zeros((2, 13 * n)), np.zeros(10), np.empty(n)
    obs = np.zeros((OBS_ROWS, n))
    law_trial(arm.chain, SlotineLi(arm).law_config(T), pi[0], pi[1], theta, 0, obs, *z[3:], out)
    print(READY, flush=True)
    ec, es = online.est_init(online.OnlineConfig(sample_period=T), arm, 1)
    online.est_model_trial(ec, es, 0, np.empty((1, 13 * n))[0])
    if not sc.swap_masses:
        return
    q, qd, _ = sc.reference.sample(np.arange(8) * T)
    ref = SimpleNamespace(q=q[None], qd=qd[None], tau=np.zeros((1, 8, n)), failed=np.zeros(1, bool), name="-")
    _chain.information(sc, ref, 1, 1, 6)
    _chain.detection_limit(sc, ref, 1, 1, 6)


def plant_kernels(sc) -> None:
    """Compile into the cache the plant's integrator that the closed loop of scenario ``sc`` calls
    (:func:`~adaptive_dd.plant.integrator.compile_family`), with its arguments built as the loop
    builds them: trial 0's :class:`~adaptive_dd.closed_loop.types.Plant` in its first segment."""
    import numpy as np

    from adaptive_dd.closed_loop.plant import plant_scratch
    from adaptive_dd.closed_loop.types import plant_of
    from adaptive_dd.plant.integrator import PlantParams, compile_family

    n, pl = sc.n_joints, plant_of(sc, (0,))
    pp = PlantParams(pl.pi_seg[0, 0], pl.fv[0], pl.fc[0], pl.armature[0], pl.friction_law, pl.fparams)
    q, qd, tau, stuck = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n, bool)
    compile_family(pl.chain, pp, q, qd, tau, sc.sample_period, pl.substeps, stuck, plant_scratch(n))


def second_process_two_link(source: str) -> None:
    """The second process of a cold-cache benchmark on the paper's arm (its closed forms) of
    scenario file ``source``: it compiles into the cache the estimator's step that the closed loop
    calls (:func:`~adaptive_dd.identification.two_link_online_kernel.online_step_trial`, reached
    through :func:`~adaptive_dd.identification.two_link_online.online_step` with the state and
    settings ``adaptive_ct``'s run builds, so with the loop's argument types), prints ``READY``,
    then the arm's regressor that the report's base parameters call
    (:meth:`~adaptive_dd.plant.arm.Arm.standard_regressor`). The first process compiles the
    closed loop meanwhile and, reaching the estimator's step, loads it from the cache (or waits
    for it: :func:`adaptive_dd._numba_cache._lock_compilations`)."""
    import numpy as np

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.controllers.compiled_form import compiled_spec
    from adaptive_dd.controllers.registry import scenario_controller
    from adaptive_dd.identification.two_link_online import online_init, online_step

    sc = load_scenario(source)
    spec = compiled_spec(scenario_controller(sc, "adaptive_ct")[1], sc.sample_period)
    z = np.zeros((1, 2))
    online_step(online_init(spec.online, 1, spec.sigma), z, z, z, spec.online)
    print(READY, flush=True)
    if sc.arm is not None:
        sc.arm.standard_regressor(z[0], z[0], z[0])
