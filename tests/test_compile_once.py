"""Each shared kernel is compiled once, whatever calls it (a fresh clone's first run compiles less).

numba compiles a function once per tuple of argument types, and ``True``, ``0`` or a read-only
array are types of their own: a kernel reached with ``0`` from one call site and an ``int64`` from
another is compiled twice (``benchmarks/compile_profile.py --why`` lists such kernels). These
tests count the specialisations of the kernels that were compiled twice or three times before
(in this process and in numba's cache for this source: the count does not depend on the cache).
"""

from __future__ import annotations

import dataclasses
import tomllib
from importlib import resources

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import load_scenario, parse_scenario
from adaptive_dd.plant import chain as C
from adaptive_dd.plant import chain_dynamics as CD
from adaptive_dd.plant import chain_regressor as CR
from adaptive_dd.plant import chain_rk4 as RK
from adaptive_dd.plant import integrator as S


def _specialisations(kernel) -> set[str]:
    """Argument types ``kernel`` is compiled for: in this process, or in numba's cache for this
    state of its source (a callee loaded from the cache with its caller has no signature in memory)."""
    index = kernel._cache._cache_file._load_index()

    def text(types):
        return ", ".join(str(t) for t in types)

    return {text(s) for s in kernel.signatures} | {text(key[0]) for key in index}


def _ur5(duration: float | None = None):
    """The shipped UR5 scenario (cut to ``duration`` with no payload change, 1 seed, if given)."""
    path = str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml"))
    if duration is None:
        return load_scenario(path)
    data = tomllib.loads(open(path, encoding="utf-8").read())
    data["run"] = {**data["run"], "duration": duration, "seeds": 1, "controllers": ["pd", "adaptive_ct"]}
    data["payload"], data["reference"]["ramp"] = [], 0.2
    data["controllers"] = {k: v for k, v in data.get("controllers", {}).items() if k in ("pd", "adaptive_ct")}
    return parse_scenario(data, "test.toml", name="ur5_tool_swap")


@pytest.mark.slow  # compiles the smooth friction family's step: 26 s in a cold run
def test_the_integrator_step_compiles_once_per_friction_law_family():
    """``_rk4`` (the integrator's largest kernel): one copy for the stick-slip law (its law a
    compile-time constant: faster), one for the smooth laws; not one more per call site."""
    sc = _ur5()
    ch, n = sc.arm.chain, sc.n_joints
    for law in ("stick-slip", "tanh"):
        pp = S.plant_params(ch, sc.arm.pi[: 10 * n], np.full(n, 0.1), np.full(n, 0.5), law=law)
        q, qd, stuck = np.full(n, 0.3), np.zeros(n), np.zeros(n, dtype=bool)
        for _ in range(3):  # from rest: the stick-slip law decides modes and steps to crossings
            assert S.plant_step(ch, pp, q, qd, np.ones(n), 1e-3, 2, stuck)
    assert len(_specialisations(RK._rk4)) == 2, _specialisations(RK._rk4)


def test_the_chain_kernels_compile_once_for_every_caller(rng):
    """Batch wrappers (read-only inputs allowed) and in-place kernels share one compiled form."""
    sc = _ur5()
    ch, pi, n = sc.arm.chain, sc.arm.pi[: 10 * sc.n_joints], sc.n_joints
    q = np.broadcast_to(rng.normal(size=n), (3, n))  # a read-only view
    qd, qdd = rng.normal(size=(3, n)), rng.normal(size=(3, n))
    C.regressor_batch(ch, q, qd, qdd)
    C.slotine_li_regressor_batch(ch, q, qd, qd, qdd)
    C.rnea_batch(ch, pi, q, qd, qdd)
    C.rnea_ref_batch(ch, pi, q, qd, qd, qdd)
    C.mass_matrix_batch(ch, pi, q)
    w, a, out = C.workspace(n), np.empty((6, 10)), np.empty((n, 10))
    C.body_regressor_in(ch, 2, q[0].copy(), qd[0], qdd[0], w, a, out)
    C.body_slotine_li_regressor_in(ch, 2, q[0].copy(), qd[0], qd[0], qdd[0], w, a, out)
    C.rnea_body_regressor_in(ch, pi, 2, q[0].copy(), qd[0], qdd[0], w, a, np.empty(n), out)
    C.mass_matrix_in(ch, pi, q[0].copy(), w, np.empty((n, n)))
    C.rnea_in(ch, pi, q[0].copy(), qd[0], qdd[0], w, np.empty(n))
    C.rnea_ref_in(ch, pi, q[0].copy(), qd[0], qd[0], qdd[0], w, np.empty(n))
    C.regressor(ch, q[0].copy(), qd[0], qdd[0], np.empty((n, 10 * n)))
    C.body_regressor(ch, 2, q[0].copy(), qd[0], qdd[0], out)
    p, wv, py, wy = np.empty(n), np.empty(n), np.empty((n, 10)), np.empty((n, 10))
    C.momentum_form_in(ch, pi, 2, q[0].copy(), qd[0], w, np.empty((2, 6, 10)), p, wv, py, wy)
    C.momentum_in(ch, pi, q[0].copy(), qd[0], w, p, wv)
    for kernel in (
        CD.rnea_in, CD.rnea_ref_in, CD.mass_matrix_in, CR._local_regressor, CR._columns_from_motion,
        CR._regressor_blocks, CR._regressor_blocks_in, CR.momentum_in,
    ):  # fmt: skip
        assert len(_specialisations(kernel)) == 1, (kernel.__name__, _specialisations(kernel))


def _of_arm(specialisations: set[str], two_link: bool) -> set[str]:
    """The specialisations of the closed loop's one kernel for one kind of arm (the two-link arm's
    name its ``TwoLinkPlant``)."""
    return {s for s in specialisations if ("TwoLinkPlant" in s) == two_link}


def test_the_two_link_sample_loop_compiles_once_for_every_law():
    """The two-link laws are one record type (the law a runtime branch) and carry the estimator's
    configuration whether they run it or not: ``pd`` and ``adaptive_ct`` share one sample loop."""
    from adaptive_dd.benchmark import run_benchmark
    from adaptive_dd.closed_loop import glue

    sc = dataclasses.replace(load_scenario(), seeds=2, duration=0.02, swap_times=(), swap_masses=())
    run_benchmark(
        dataclasses.replace(sc, controllers=("pd", "adaptive_ct")), progress=False, engine="compiled"
    )
    loops = _of_arm(_specialisations(glue.trial_samples), two_link=True)
    assert len(loops) == 1, loops


def test_a_short_run_compiles_the_n_joint_loop_once_for_every_law():
    """A short UR5 run of ``pd`` and ``adaptive_ct``: one loop for both (``pd`` carries an inactive
    estimator, :class:`~adaptive_dd.closed_loop.chain_choices.ChainEstimator`), the stick-slip ``_rk4``
    once (on a constant law: with the law a runtime value ct_oracle ran at 78 simulated s per CPU s
    against 98). The second process of a cold-cache run compiles the plant's integrator alone
    (``precompile.plant_kernels``, run here first): the loop calls it with the same argument
    types (one ``_stick_slip``), or it would compile it again (about 20 CPU s) and the second
    process's work would be lost."""
    from adaptive_dd.closed_loop import glue
    from adaptive_dd.closed_loop.precompile import plant_kernels
    from adaptive_dd.closed_loop.runner import run_closed_loop

    sc = _ur5(duration=0.01)
    plant_kernels(sc)
    res = run_closed_loop(sc)
    assert list(res.runs) == ["pd", "adaptive_ct"]
    # on the stick-slip plant (a run on another friction law in this state of the source is another
    # specialisation, in the cache: not this test's business)
    chain = _of_arm(_specialisations(glue.chain_loop_block), two_link=False)
    loops = {s for s in chain if "StickSlipLaw" in s}
    assert len(loops) == 1, loops
    assert len([s for s in _specialisations(RK._rk4) if "Literal[int](0)" in s]) == 1
    assert len(_specialisations(RK._stick_slip)) == 1, _specialisations(RK._stick_slip)


def test_the_estimator_step_compiles_once_for_the_loop_and_the_estimator_alone():
    """The estimator's step (its largest kernel) is one compiled function, ``est_step_model``,
    called by the closed loop (its model written) and by the estimator run alone (``run_online``,
    ``est_step``: no model): one specialisation for both, not a second inlined copy (about 25 CPU s
    of a cold test run). The argument types a cold benchmark compiles it for
    (``compile_estimator``) are those of both callers. The estimator alone reaches it through one
    compiled driver, ``est_run``, with one specialisation whoever calls it."""
    from numba.core.registry import CPUDispatcher

    from adaptive_dd.closed_loop import chain_choices, glue
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.identification import online
    from adaptive_dd.identification import online_kernel as K

    sc = _ur5(duration=0.01)
    chain_choices.compile_estimator(sc.arm)
    run_closed_loop(dataclasses.replace(sc, controllers=("adaptive_ct",)))
    z = np.zeros((4, sc.n_joints))
    cfg = online.OnlineConfig(sample_period=sc.sample_period)
    online.run_online(sc.arm, cfg, z, z, z)
    c, s = online.est_init(cfg, sc.arm, 2)
    online.est_step(c, s, z[:2], z[:2], z[:2])
    steps = _specialisations(K.est_step_model)
    assert len(steps) == 1, steps
    # the estimator alone has one compiled driver (each compiled caller links and optimises the
    # step again): run_online, est_step and est_run_trial call est_run with the same argument types
    N = 3
    rec = (np.empty((N, s.theta.shape[1])), np.empty((N, 10)), np.empty((N, sc.n_joints)))
    K.est_run_trial(c, s, 1, z[:N], z[:N], z[:N], *rec, np.zeros(N, np.int64), np.empty(N))
    runs = _specialisations(K.est_run)
    assert len(runs) == 1, runs
    drivers = {
        name for name, f in vars(K).items()
        if isinstance(f, CPUDispatcher) and "est_step_trial_w" in f.py_func.__code__.co_names
    }  # fmt: skip
    assert drivers == {"est_run", "est_step_trial"}, drivers  # est_step_trial: timed by benchmarks
    # the step is inlined nowhere: every caller reaches it through est_step_model
    for mod in (K, chain_choices, glue):
        for name, f in vars(mod).items():
            if isinstance(f, CPUDispatcher) and name != "est_step_model":
                assert "est_step_trial_in" not in f.py_func.__code__.co_names, (mod.__name__, name)


def test_the_n_joint_law_compiles_once_for_the_batch_and_the_second_process():
    """``law_trial`` (one trial, as a cold benchmark's second process and the tests call it) and
    ``law_batch``'s loop (the Python path's controllers) share one compiled law: the loop calls
    ``law_trial``, it does not inline the law a second time."""
    from adaptive_dd.closed_loop import laws as L
    from adaptive_dd.closed_loop.controllers import SlotineLi

    sc = _ur5()
    T, n, arm = sc.sample_period, sc.n_joints, sc.arm
    cfg = SlotineLi(arm).law_config(T)
    q, qd, ref, out = np.full(n, 0.1), np.zeros(n), np.zeros((3, n)), np.empty(n)
    one = L.LawState.start(cfg, 1)  # as the second process calls it (precompile.second_process)
    pi_true = np.zeros(13 * n)
    L.law_trial(arm.chain, cfg, pi_true, one.pi_model[0], one.theta[0], 0, one.obs[0], q, qd, *ref, out)
    tau = L.law_batch(arm.chain, cfg, L.LawState.start(cfg, 2), np.stack([q, q]), np.stack([qd, qd]), *ref)
    assert np.all(np.isfinite(out)) and np.any(out != 0.0)
    np.testing.assert_array_equal(tau, np.stack([out, out]))  # the batch is the one-trial law
    assert len(_specialisations(L.law_trial)) == 1, _specialisations(L.law_trial)
    assert "law_trial_in" not in L._law_loop.py_func.__code__.co_names


def test_the_friction_law_as_a_record_compiles_its_family_alone():
    """The closed loop's plant holds the law as a record (:func:`friction_law`): the step it
    compiles calls one family's integrator (a stick-slip arm does not compile ``_smooth`` and its
    ``_rk4``, nor LuGre's micro-steps); an integer code still compiles stick-slip and the smooth laws
    and chooses at run time."""
    from numba import typeof, types

    from adaptive_dd.closed_loop.types import plant_of
    from adaptive_dd.errors import ParameterError

    assert isinstance(plant_of(_ur5(duration=0.01)).friction_law, S.StickSlipLaw)
    a = (types.none,) * 5
    b = (types.none,) * 8
    for code, family in ((0, "_stick_slip"), (1, "_smooth"), (2, "_smooth"), (3, "_lugre")):
        law = S.friction_law(code, np.zeros(2))
        assert law.code == code
        called = S._by_law_typed(*a, typeof(law), *b).__code__.co_names
        assert set(called) & {"_stick_slip", "_smooth", "_lugre"} == {family}, (code, called)
    both = S._by_law_typed(*a, types.int64, *b).__code__.co_names
    assert {"_stick_slip", "_smooth"} <= set(both) and "_lugre" not in both  # LuGre only as its record
    with pytest.raises(ParameterError, match="friction law code"):
        S.friction_law(4)
    with pytest.raises(ParameterError, match="bristle state"):
        S.friction_law(3)


@pytest.mark.parametrize(
    ("root", "chosen"),
    [
        ("_chain_trial_samples", ("_chain_plant_advance", "_chain_law_command", "_chain_estimator_sample")),
        ("_chain_apply_loop", ("_chain_plant_advance", "_chain_plant_work")),
        ("_chain_estimator_loop", ("_chain_estimator_sample", "_chain_estimator_work")),
    ],
)
def test_the_n_joint_loop_calls_its_choices_by_name_not_through_overloads(root, chosen):
    """numba compiles an ``@overload``'s implementation in full to type it, even one inlined where
    it is called (then throws it away): on the UR5 about 15 CPU s of the closed loop's
    compilation. The N-joint loop (``glue._chain_trial_samples``, inlined into
    ``chain_loop_block``) and the Python path's N-joint loops (the applied sample and the
    estimator: the overloads cost them about 11 CPU s) call every choice (the plant's step, the
    law, the estimator, their scratch) by name: each global they call, in their code and in the
    per-sample pieces they inline, is a compiled function (inlined before typing, or compiled and
    cached once), not one of the stubs the overloads choose for."""
    import inspect

    from numba.core.registry import CPUDispatcher

    from adaptive_dd.closed_loop import batches, glue

    stubs = {
        name for name, f in vars(glue).items()
        if inspect.isfunction(f) and "compiled only" in inspect.getsource(f)
    }  # fmt: skip
    assert {"plant_advance", "law_command", "estimator_sample", "law_estimate", "plant_work"} <= stubs
    home = glue if root == "_chain_trial_samples" else batches
    seen, todo = set(), [getattr(home, root)]
    while todo:
        d = todo.pop()
        f = d.py_func
        for name in f.__code__.co_names:
            g = f.__globals__.get(name)
            if isinstance(g, CPUDispatcher) and g not in seen and g.targetoptions.get("inline") == "always":
                seen.add(g)
                todo.append(g)
            assert not (inspect.isfunction(g) and name in stubs), (f.__qualname__, name)
    assert {getattr(glue, c) for c in chosen} <= seen  # the choices: glue's names
