"""One trial in one's own loop, and results as data."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.controllers import ComputedTorque, computed_torque_law
from adaptive_dd.errors import SignalError
from adaptive_dd.simulation import Simulation, run_trial


@pytest.fixture(scope="module")
def short():
    return dataclasses.replace(
        load_scenario(),
        seeds=2,
        duration=1.0,
        swap_times=(0.6,),
        swap_masses=(3.0,),
        controllers=("ct_oracle",),
    )


def test_stepping_one_arm_by_hand_equals_the_benchmark_trial(short):
    sim = Simulation(short, seed_index=1)
    meas = sim.reset()
    g = ComputedTorque(oracle=True).gains
    while not sim.done:
        tau = computed_torque_law(
            meas.q[None],
            meas.qd[None],
            meas.q_d,
            meas.qd_d,
            meas.qdd_d,
            sim.sigma_true[None],
            g.kp,
            g.kd,
            g.lam,
        )[0]
        before = meas.q_d - sim.q_true
        meas = sim.step(tau)
    assert sim.payload_mass == 3.0 and not sim.failed
    res = run_trial(ComputedTorque(oracle=True), short, seed_index=1, name="ct_oracle")
    run = res.runs["ct_oracle"]
    np.testing.assert_allclose(run.e_norm[0, -1], np.linalg.norm(before), rtol=1e-6)
    with pytest.raises(SignalError, match="done"):
        sim.step(np.zeros(2))
    with pytest.raises(SignalError, match="shape"):
        sim.reset() and sim.step(np.zeros(3))


def test_results_as_a_long_table_and_a_summary(short):
    sc = dataclasses.replace(short, controllers=("ct_oracle", "adaptive_ct"))
    from adaptive_dd.benchmark.runner import run_benchmark

    res = run_benchmark(sc, progress=False)
    df = res.to_frame()
    assert len(df) == 2 * sc.seeds * len(sc.segments())  # controller x seed x segment
    a = df[(df.controller == "adaptive_ct") & (df.segment == 1)]
    # independent of the streamed sums: the RMS of the recorded error norm over the segment
    k = int(np.ceil(0.6 / sc.sample_period - 1e-9))

    def rms(name):
        return np.sqrt(np.mean(res.runs[name].e_norm[:, k:].astype(float) ** 2, axis=1))

    direct = rms("adaptive_ct") / rms("ct_oracle")
    np.testing.assert_allclose(a.ratio_to_floor.to_numpy(), direct, rtol=1e-5)
    s = res.summary()
    row = s[(s.controller == "adaptive_ct") & (s.segment == 1)].iloc[0]
    assert row.ratio_max == pytest.approx(direct.max(), rel=1e-5) and row.n == sc.seeds
    assert row.worst_seed == int(np.argmax(direct))
    m = res.metrics()
    st = m["controllers"]["adaptive_ct"]["segments"][1]["ratio_to_floor"]
    assert st["max"] == pytest.approx(direct.max(), rel=1e-5) and st["mean"] == pytest.approx(
        direct.mean(), rel=1e-5
    )
    prov = m["provenance"]
    assert prov["version"] and prov["seed_indices"] == [0, 1] and prov["scenario"]["swap_masses"] == [3.0]


def test_no_two_built_in_controllers_are_drawn_alike():
    """Each built-in has its own line (pd_gravity and its oracle shared a colour and a width: a
    figure could not tell them apart); a plug-in's ``*_oracle`` takes its law's colour, wide."""
    from adaptive_dd.controllers.registry import CONTROLLERS
    from adaptive_dd.plotting import controller_style

    looks = {n: tuple(controller_style(n)[k] for k in ("color", "ls", "lw")) for n in CONTROLLERS}
    assert len(set(looks.values())) == len(looks)
    mine, floor = controller_style("mine"), controller_style("mine_oracle")
    assert floor["color"] == mine["color"] and floor["lw"] > mine["lw"] and floor["zorder"] < mine["zorder"]


def test_figures_are_returned_with_one_style_per_controller(short, tmp_path, assert_on_the_page):
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.plotting import controller_style, plot_benchmark_estimates, plot_tracking_errors

    sc = dataclasses.replace(short, controllers=("ct_oracle", "adaptive_ct"))
    res = run_benchmark(sc, progress=False)
    fig = plot_tracking_errors(res)
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    for name in ("ct_oracle", "adaptive_ct"):
        st = controller_style(name)
        assert lines[name].get_color() == st["color"] and lines[name].get_zorder() == st["zorder"]
    assert lines["ct_oracle"].get_zorder() < lines["adaptive_ct"].get_zorder()  # oracle underneath
    assert controller_style("my_pkg.mod:Mine") == controller_style("my_pkg.mod:Mine")
    fig2 = plot_benchmark_estimates(res, tmp_path / "est.png", formats=("png", "svg"))
    assert (tmp_path / "est.png").is_file() and (tmp_path / "est.svg").is_file()
    assert fig2.axes[0].get_lines()[1].get_color() == controller_style("adaptive_ct")["color"]
    for f in (fig, fig2):
        assert_on_the_page(f)


def test_no_module_constant_outside_the_default_factory():
    """Everything physical comes from a ClosedFormTwoLink; only parameters.py defines and two_link.py's
    ClosedFormTwoLink.sice() reads the SICE constants (plant/__init__ re-exports them)."""
    import re
    from pathlib import Path

    import adaptive_dd

    root = Path(adaptive_dd.__file__).parent
    allowed = {root / "plant" / name for name in ("parameters.py", "two_link.py", "__init__.py")}
    pat = re.compile(r"\b(TABLE1_SIGMA|TABLE1_PHYSICAL|TORQUE_LIMITS|L1|L2)\b")
    offenders = [
        f"{p.relative_to(root)}:{i}"
        for p in root.rglob("*.py")
        if p not in allowed
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if pat.search(line.split("#")[0])
    ]
    assert offenders == []


def test_one_trial_of_another_arm_uses_that_arm(tmp_path):
    from adaptive_dd.benchmark.scenario import load_scenario

    sc = load_scenario(Path(__file__).resolve().parent.parent / "benchmarks" / "scenarios" / "other_arm.toml")
    sim = Simulation(dataclasses.replace(sc, duration=0.2, swap_times=(0.1,), swap_masses=(2.0,)))
    sim.reset()
    np.testing.assert_allclose(sim.sigma_true, sc.closed_forms.sigma)  # the paper's sigma of its arm
    while not sim.done:
        sim.step(np.zeros(2))
    np.testing.assert_allclose(sim.sigma_true, sc.closed_forms.sigma_with_payload(2.0, sc.payload_radius))


class _PD:
    """A plain Python PD law (a plug-in's interface) for any number of joints."""

    def __init__(self, kp: float, kd: float) -> None:
        self.kp, self.kd = kp, kd

    def reset(self, n_trials, T):
        pass

    def command(self, q, qd, q_d, qd_d, qdd_d):
        return self.kp * (q_d - q) + self.kd * (qd_d - qd)

    def observe(self, q, qd, tau):
        pass


@pytest.fixture(scope="module")
def ur5_short():
    from importlib import resources

    sc = load_scenario(str(resources.files("adaptive_dd.scenarios").joinpath("ur5_tool_swap.toml")))
    return dataclasses.replace(
        sc, duration=0.3, swap_times=(0.1,), swap_masses=(2.0,), swap_com=(), swap_inertia=(), seeds=2
    )


def test_stepping_a_urdf_arm_by_hand_equals_its_benchmark_trial(ur5_short):
    """Issue 27: Simulation(...).reset() raised 'arm must be a ClosedFormTwoLink, got Arm' on a URDF arm."""
    sc = ur5_short
    n = sc.n_joints
    sim = Simulation(sc, seed_index=1)
    meas = sim.reset()
    assert meas.q.shape == (n,) and meas.q_d.shape == (n,)
    ctrl = _PD(400.0, 40.0)
    e_norm = []
    while not sim.done:
        e_norm.append(np.linalg.norm(meas.q_d - sim.q_true))
        meas = sim.step(ctrl.command(meas.q, meas.qd, meas.q_d, meas.qd_d, meas.qdd_d))
    assert not sim.failed and sim.payload_mass == 2.0
    from adaptive_dd.closed_loop.types import plant_of, true_models

    # this trial's plant (the scenario's [plant] draw for seed index 1), payload segment 1
    truth = true_models(plant_of(sc, [1]))[0, 1] @ sc.arm.base.B.T
    np.testing.assert_allclose(sim.sigma_true, truth)
    run = run_trial(_PD(400.0, 40.0), sc, seed_index=1, name="pd").runs["pd"]
    assert not run.failed[0]
    np.testing.assert_allclose(run.e_norm[0], e_norm, rtol=1e-6, atol=1e-12)
    # the final measurement is of the final state, not NaN
    assert np.all(np.isfinite(meas.q)) and np.all(np.isfinite(meas.q_d)) and meas.k == sc.n_samples
    np.testing.assert_allclose(meas.q, sim.q_true, atol=1e-3)
    with pytest.raises(SignalError, match=rf"\({n},\)"):
        sim.reset() and sim.step(np.zeros(2))


def test_the_two_link_final_measurement_is_not_nan(short):
    """Issue 27: the two-link arm's last measurement had q and q_d NaN."""
    sim = Simulation(short)
    meas = sim.reset()
    while not sim.done:
        meas = sim.step(np.zeros(2))
    assert meas.k == short.n_samples
    assert np.all(np.isfinite([*meas.q, *meas.qd, *meas.q_d, *meas.qd_d, *meas.qdd_d]))
    np.testing.assert_allclose(meas.q, sim.q_true, atol=2e-3)  # sensor noise std 3e-4 rad
    q_end = short.reference.sample(np.array([short.duration]))[0][0]
    np.testing.assert_allclose(meas.q_d, q_end)


def test_importing_the_figures_keeps_the_users_matplotlib_backend():
    """A notebook's backend stays its own: the library draws on whatever backend is chosen (the
    command line chooses Agg for itself)."""
    import subprocess
    import sys

    code = (
        "import matplotlib; matplotlib.use('svg'); "
        "import adaptive_dd.plotting, adaptive_dd.identification_plots; print(matplotlib.get_backend())"
    )
    env = {k: v for k, v in __import__("os").environ.items() if k != "MPLBACKEND"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == "svg", out.stdout + out.stderr


def test_the_library_names_a_misused_argument_and_what_to_pass():
    """A file path, a list of controllers, a negative number of kept trajectories, a negative or
    NaN payload mass, a window that is no time: each refused naming the argument and the fix."""
    import dataclasses

    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.errors import ParameterError
    from adaptive_dd.plant import Arm

    sc = dataclasses.replace(load_scenario(), seeds=1, duration=0.2, swap_times=(0.1,), swap_masses=(1.0,))
    with pytest.raises(ParameterError, match=r"scenario must be a Scenario.*load_scenario"):
        run_benchmark("payload_swap.toml", progress=False)
    with pytest.raises(ParameterError, match=r"controllers must be a dict.*with_controllers"):
        run_benchmark(sc, progress=False, controllers=["ct_oracle"])
    with pytest.raises(ParameterError, match="keep_trajectories must be an integer >= 0"):
        run_benchmark(sc, progress=False, keep_trajectories=-1)
    arm = Arm.sice()
    for bad in (-1.0, float("nan")):
        with pytest.raises(ParameterError, match="mass must be finite and >= 0 kg"):
            arm.sigma_with_payload(bad)
    from adaptive_dd.plotting import plot_tracking_errors

    res = run_benchmark(sc, progress=False)
    with pytest.raises(ParameterError, match=r"window must be a time in \(0, 0.2\] s"):
        plot_tracking_errors(res, window=-1)


def test_a_controllers_dict_holds_controller_objects():
    """run_benchmark(controllers=) checks what it is given before any trial runs: a name, a class, an
    object without the protocol's methods (each failed every trial in silence, the reason only in
    to_frame's failure column)."""
    from adaptive_dd import make_controller
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.errors import ParameterError

    sc = dataclasses.replace(load_scenario(), seeds=1, duration=0.2, swap_times=(0.1,), swap_masses=(1.0,))
    oracle = make_controller("ct_oracle")

    class NoObserve:
        def reset(self, n, T):
            pass

        def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
            return 0 * q

    with pytest.raises(ParameterError, match=r"^run_trial: controller is the name 'adaptive_ct'"):
        run_trial("adaptive_ct", sc)
    for bad, what in [
        ("adaptive_ct", r"controllers\['a'\] is the name 'adaptive_ct'.*make_controller\('adaptive_ct'\)"),
        (NoObserve, r"controllers\['a'\] is the class NoObserve.*an instance"),
        (NoObserve(), r"controllers\['a'\] \(NoObserve\) is not a controller.*missing \['observe'\]"),
    ]:
        with pytest.raises(ParameterError, match=what):
            run_benchmark(sc, progress=False, controllers={"ct_oracle": oracle, "a": bad})


def test_the_summary_counts_a_failed_trial_before_its_failure(short):
    """summary() keeps a failed trial's segments that ended before it failed (as metrics() and the
    report do), and a controller whose every trial failed at once keeps its rows with n 0."""
    from adaptive_dd import make_controller
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.controllers import Controller

    class NanLate(Controller):  # seed 1 fails at 0.7 s, in the second segment (the swap at 0.6 s)
        name = "nan_late"

        def reset(self, n, T):
            super().reset(n, T)
            self.k, self.n = 0, n

        def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
            self.k += 1
            tau = 100 * (q_d - q) + 20 * (qd_d - qd)
            if self.k > 700:
                tau[1, 1] = np.nan  # trial 1's joint 2
            return tau

    class NanNow(Controller):
        name = "nan_now"

        def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
            return np.full_like(q, np.nan)

    res = run_benchmark(
        short, progress=False,
        controllers={"ct_oracle": make_controller("ct_oracle"), "late": NanLate(), "now": NanNow()},
    )  # fmt: skip
    frame = res.to_frame().set_index(["controller", "seed", "segment"])
    assert frame.loc[("late", 1, 0), "failed"] and np.isfinite(frame.loc[("late", 1, 0), "rms_error_rad"])
    assert np.isnan(frame.loc[("late", 1, 1), "rms_error_rad"])
    summary = res.summary().set_index(["controller", "segment"])
    assert list(summary.loc["late", "n"]) == [2, 1]
    m = res.metrics()["controllers"]["late"]["segments"]
    assert summary.loc[("late", 0), "ratio_mean"] == pytest.approx(m[0]["ratio_to_floor"]["mean"])
    assert list(summary.loc["late", "ratio_n"]) == [s["ratio_to_floor"]["n"] for s in m]  # the JSON's n
    assert list(summary.loc["now", "n"]) == [0, 0]


def test_a_bad_seed_index_is_named_where_it_is_given():
    from adaptive_dd.errors import ParameterError

    for bad in (-1, 1.5, True):
        with pytest.raises(ParameterError, match=r"Simulation: seed_index must be an integer >= 0"):
            Simulation(seed_index=bad)


def test_run_trial_says_how_to_run_the_floor_beside_it(short):
    """run_trial runs one controller: a floor it lacks is said in run_trial's terms (it has no
    controllers= to put the floor in), pointing at the caller's line."""
    from adaptive_dd import make_controller

    with pytest.warns(UserWarning, match=r"run_trial: adaptive_ct's floor ct_oracle.*run_benchmark\(") as w:
        run_trial(make_controller("adaptive_ct"), short, seed_index=0)
    assert all(Path(x.filename).name == "test_simulation_api.py" for x in w)


def test_the_ratio_figures_interval_is_the_reports():
    """plot_ratios drew mean +- 1.96 sd / sqrt(n), not the report's ci95 of the same seeds; now it
    draws the report's (the bootstrap of ``intervals.mean_interval``, the seeds in the report's order)."""
    import pandas as pd

    from adaptive_dd.benchmark.metrics import ratio_statistics
    from adaptive_dd.plotting import plot_ratios

    r = np.random.default_rng(0).lognormal(0.0, 0.2, 3)
    rows = [
        {
            "controller": "a",
            "seed": k,
            "segment": 0,
            "start_s": 0.0,
            "end_s": 1.0,
            "mass_kg": 0.0,
            "ratio_to_floor": x,
        }
        for k, x in enumerate(r)
    ]
    bar = plot_ratios(pd.DataFrame(rows[::-1])).axes[0].collections[0].get_segments()[0][:, 1]
    np.testing.assert_allclose(bar, ratio_statistics(r, [0, 1, 2])["ci95"], rtol=1e-12)


def test_a_path_a_string_or_a_number_where_a_list_or_a_scenario_goes_is_named():
    """A user's API slips (a walk-through's): each says what to pass instead, not an AttributeError
    deep inside or a controller named 'a'."""
    from adaptive_dd.arena.leaderboard import leaderboard
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.errors import ParameterError

    with pytest.raises(
        ParameterError, match=r"Simulation: scenario must be a Scenario, got str .*load_scenario"
    ):
        Simulation("adaptive_dd/scenarios/ur5_tool_swap.toml")
    with pytest.raises(ParameterError, match=r"run_trial: scenario must be a Scenario"):
        run_trial(ComputedTorque(), "payload_swap")
    with pytest.raises(ParameterError, match=r"seed_indices is a list of seed indices, got 3: pass \[3\]"):
        run_benchmark(load_scenario(), seed_indices=3)
    with pytest.raises(ParameterError, match=r"controllers is a list, got the one 'adaptive_ct'"):
        leaderboard([], controllers="adaptive_ct", arms=1)


@pytest.mark.slow  # a cold compile of its own path; the rest of the file covers the check
def test_run_trial_raises_what_the_controller_raised():
    """A two-link class on an N-joint arm failed at t = 0 and run_trial handed back a result of NaN
    without a word (the library page's own example on a user's arm)."""
    import dataclasses

    from adaptive_dd import load_scenario, make_controller, run_trial
    from adaptive_dd.controllers import ComputedTorque
    from adaptive_dd.errors import SignalError

    sc = load_scenario("vertical3_payload_exact")
    sc = dataclasses.replace(
        sc, duration=0.5, swap_times=(0.25,), swap_masses=(1.0,), swap_com=(), swap_inertia=()
    )
    with pytest.raises(
        SignalError, match=r"run_trial: ct_oracle on trial 1: ValueError in command at t = 0.000 s"
    ):
        run_trial(ComputedTorque(oracle=True), sc, seed_index=1)
    res = run_trial(make_controller("ct_oracle", arm=sc.arm), sc, seed_index=1)  # the page's way
    assert not res.runs["ct_oracle"].failed.any()


@pytest.mark.parametrize("arm", ["two_link", "ur5"])
def test_a_failed_trial_says_when_and_why(arm, short, ur5_short):
    """A NaN command failed the trial and set ``failed``; the loop went on with no word of when or why."""
    from adaptive_dd import Simulation

    sc = short if arm == "two_link" else ur5_short
    n = sc.n_joints
    sim = Simulation(sc, 0)
    sim.reset()
    assert sim.failed_at is None and sim.failure is None
    for k in range(5):
        tau = np.zeros(n)
        if k == 3:
            tau[n - 1] = np.nan
        sim.step(tau)
    assert sim.failed and sim.failed_at == pytest.approx(3 * sc.sample_period)
    assert sim.failure == f"non-finite torque command (joint {n})"
    sim.reset()  # and a new trial starts clean
    assert sim.failed_at is None and sim.failure is None


def test_the_ratio_figure_labels_a_populations_segments_by_their_range():
    """A population's per_seed.csv: each arm carries its own payload; the tick read the first row's
    (2-4 s / 0.848 kg on arms of 0.848, 2.056 and 3.024 kg)."""
    import pandas as pd

    from adaptive_dd.plotting import plot_ratios

    rows = [
        {"controller": "adaptive_ct", "arm_seed": a, "seed": 0, "segment": s, "start_s": 2.0 * s,
         "end_s": 2.0 * s + 2, "mass_kg": m * s, "ratio_to_floor": 1.0}
        for a, m in enumerate((0.848, 2.056, 3.024)) for s in (0, 1)
    ]  # fmt: skip
    fig = plot_ratios(pd.DataFrame(rows))
    labels = [t.get_text() for t in fig.axes[0].get_xticklabels()]
    assert labels == ["0-2 s\n0 kg", "2-4 s\n0.848-3.02 kg"]
