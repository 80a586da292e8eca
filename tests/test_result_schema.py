"""One result schema and one failure rule on every arm (issue 27: "a failed trial blanks
different segments on the two paths; `information_time` has different keys").

The same short scenario runs on the paper's two-link arm (the closed forms) and on a URDF arm
(the N-joint loop); their metrics, CSV and long table must have the same keys (but the number of
joints), and a trial that diverges at the same time must be failed, blanked and explained the
same way on both.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.metrics import CONTROLLER_KEYS, SEGMENT_KEYS, TOP_KEYS
from adaptive_dd.benchmark.results import frame_columns
from adaptive_dd.benchmark.runner import run_benchmark, scenario_controller
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.closed_loop.information import INFORMATION_KEYS

ROOT = Path(__file__).resolve().parent.parent
ARMS = {"two_link": None, "urdf": ROOT / "examples" / "plugin_urdf.toml"}
T_FAIL = 1.3  # [s] the planted divergence, in the second segment (0.5 - 1.5 s)


class NanAt:
    """A PD plug-in whose command on trial 1 turns NaN from ``T_FAIL`` on."""

    def reset(self, n_trials, sample_period):
        self.k, self.T = 0, sample_period

    def command(self, q, qd, q_d, qd_d, qdd_d):
        tau = 400.0 * (q_d - q) + 40.0 * (qd_d - qd)
        if self.k * self.T >= T_FAIL - 1e-12:
            tau[1, 0] = np.nan
        self.k += 1
        return tau

    def observe(self, q, qd, tau):
        pass


class Unstable(NanAt):
    """Positive feedback on trial 1's velocity from ``T_FAIL`` on: the arm runs away."""

    def command(self, q, qd, q_d, qd_d, qdd_d):
        tau = 400.0 * (q_d - q) + 40.0 * (qd_d - qd)
        if self.k * self.T >= T_FAIL - 1e-12:
            tau[1] = 2e4 * qd[1] + 2e3 * np.sign(qd[1] + 1e-9)
        self.k += 1
        return tau


def _short(arm: str, seeds: int = 2, duration: float = 2.0):
    sc = load_scenario(ARMS[arm])
    return dataclasses.replace(
        sc, seeds=seeds, duration=duration, swap_times=(0.5, 1.5), swap_masses=(1.0, 0.0),
        swap_com=(), swap_inertia=(), controllers=("ct_oracle", "adaptive_ct"), controller_options=(),
    )  # fmt: skip


@pytest.fixture(scope="module")
def results():
    """Each arm's run: ct_oracle, adaptive_ct and the NaN plug-in (a failed trial), 2 seeds."""
    out = {}
    for arm in ARMS:
        sc = _short(arm)
        ctrls = {name: scenario_controller(sc, name)[1] for name in sc.controllers}
        res = run_benchmark(sc, progress=False, controllers={**ctrls, "nan": NanAt()})
        out[arm] = (res, res.metrics())
    return out


def _keys(m: dict) -> dict:
    """The key sets of a metrics dict: top, controllers, segments, information tables."""
    ctrls = m["controllers"].values()
    segs = [s for c in ctrls for s in c["segments"]]
    infos = [s["information_time"] for s in segs if s["information_time"] is not None]
    return {
        "top": {frozenset(m)},
        "controller": {frozenset(c) for c in ctrls},
        "segment": {frozenset(s) for s in segs},
        "information_time": {frozenset(i) for i in infos},
    }


def test_the_metrics_have_one_schema_on_every_arm(results):
    """Every key on both arms, in every controller and segment, and nothing else: a key added on
    one path only (or for one kind of controller only) fails here."""
    two, urdf = _keys(results["two_link"][1]), _keys(results["urdf"][1])
    assert two == urdf
    assert two["top"] == {frozenset(TOP_KEYS)}
    assert two["controller"] == {frozenset(CONTROLLER_KEYS)}
    assert two["segment"] == {frozenset(SEGMENT_KEYS)}
    assert two["information_time"] == {frozenset(INFORMATION_KEYS)}


def test_a_figure_of_one_arm_only_is_a_documented_null_on_the_other(results):
    two = results["two_link"][1]["controllers"]
    urdf = results["urdf"][1]["controllers"]
    t1, u1 = two["adaptive_ct"]["segments"][1], urdf["adaptive_ct"]["segments"][1]
    # the paper's sigma holds no payload centre of mass; all-unknown is the two-link arm's alone
    assert t1["com_estimate"] is None and t1["com_learning_time"] is None
    assert t1["information_time"]["com_known"] is None and t1["information_time"]["com_axes"] is None
    assert t1["information_time"]["unknown"] is not None
    assert u1["information_time"]["unknown"] is None and u1["information_time"]["com_axes"] == "xyz"
    assert len(u1["com_estimate"]) == 3
    for c in (two, urdf):  # the same reference and seeds on both arms
        info = c["adaptive_ct"]["segments"][1]["information_time"]
        assert info["reference"] == "ct_oracle" and info["seeds"] == 2 and info["known"] > 0
        assert c["ct_oracle"]["false_alarms_per_seed"] is None  # no detector: None, not absent
        assert c["ct_oracle"]["segments"][1]["detected"] is None
        assert c["adaptive_ct"]["segments"][0]["information_time"] is None  # no swap before it
        assert c["adaptive_ct"]["failures"] == []


def test_the_long_table_and_the_csv_have_one_schema_on_every_arm(results, tmp_path):
    from adaptive_dd.benchmark.report import write_csv

    cols = {}
    for arm, (res, m) in results.items():
        df = res.to_frame()
        n = res.scenario.n_joints
        assert list(df.columns) == frame_columns(n)
        joints = {f"rms_error_joint{j}_rad" for j in range(1, n + 1)}
        cols[arm] = [c for c in df.columns if c not in joints]
        head = write_csv(m, tmp_path / f"{arm}.csv").read_text().splitlines()[0].split(",")
        cols[arm + ".csv"] = [c for c in head if not c.startswith("rms_error_joint")]
    assert cols["two_link"] == cols["urdf"] and cols["two_link.csv"] == cols["urdf.csv"]
    two = results["two_link"][0].to_frame()
    assert two.com_estimate_x_m.isna().all()  # the two-link arm's documented NaN
    assert {"rms_error_rad", "rms_torque_Nm", "mass_kg", "failed_at_s"} <= set(two.columns)


def test_the_cli_per_seed_csv_is_the_frame_pandas_writes(results, tmp_path):
    """``adaptive-dd benchmark`` writes ``per_seed.csv`` without pandas: byte for byte the text of
    ``to_frame().to_csv`` on both arms, with a failed trial (its reason, its blanks empty),
    estimates missing on one arm and whole-number columns holding NaN (``false_alarms_per_seed``)."""
    from adaptive_dd.benchmark.results import write_per_seed_csv

    for arm, (res, _) in results.items():
        want, got = tmp_path / f"{arm}_pandas.csv", tmp_path / f"{arm}.csv"
        res.to_frame().to_csv(want, index=False)
        write_per_seed_csv(res, got)
        assert "non-finite torque" in want.read_text() and ".0," in want.read_text(), arm
        assert got.read_text() == want.read_text(), arm


def test_the_benchmark_figures_fit_their_page_on_every_arm(results, assert_on_the_page):
    from adaptive_dd.plotting import plot_benchmark_estimates, plot_tracking_errors

    for res, _ in results.values():  # the paper's estimates on one, the payload's on the other
        assert_on_the_page(plot_tracking_errors(res))
        assert_on_the_page(plot_benchmark_estimates(res))


def test_a_diverged_trial_is_failed_blanked_and_explained_the_same_on_every_arm(results):
    """A NaN torque at 1.3 s on trial 1: failed there, its segments that end after 1.3 s blanked
    (the first kept), the same seed, time and reason on both arms, in the JSON and the table."""
    why = "non-finite torque command (joint 1: nan) at t = 1.300 s"
    for arm, (res, m) in results.items():
        c = m["controllers"]["nan"]
        assert c["failed_trials"] == 1, arm
        assert c["failures"] == [{"seed": 1, "t": pytest.approx(T_FAIL), "why": why}], arm
        per = [s["rms_error_per_seed"] for s in c["segments"]]
        assert per[0][1] is not None and per[1][1] is None and per[2][1] is None, arm
        assert all(p[0] is not None for p in per), arm
        df = res.to_frame()
        t1 = df[(df.controller == "nan") & (df.seed == 1)].sort_values("segment")
        assert t1.failed.all() and (t1.failure == why).all(), arm
        np.testing.assert_allclose(t1.failed_at_s, T_FAIL)
        assert np.isfinite(t1.rms_error_rad.iloc[0]) and t1.rms_error_rad.iloc[1:].isna().all(), arm
        t0 = df[(df.controller == "nan") & (df.seed == 0)]
        assert not t0.failed.any() and t0.failed_at_s.isna().all() and (t0.failure == "").all()


def test_a_runaway_is_failed_and_explained_the_same_on_every_arm():
    """Positive velocity feedback from 1.3 s on trial 1: the arm runs away on both arms (slower on
    the two-link arm, its torque saturating); each fails it when the divergence rule fires, says
    which rule and when, and blanks exactly the segments that end after that time."""
    for arm in ARMS:
        sc = dataclasses.replace(_short(arm, duration=3.0), controllers=("ct_oracle",))
        res = run_benchmark(sc, progress=False, controllers={"unstable": Unstable()})
        m = res.metrics()["controllers"]["unstable"]
        (f,) = m["failures"]
        assert f["seed"] == 1 and T_FAIL < f["t"] < sc.duration, (arm, f)
        assert f["why"].startswith(("runaway: the arm's state became non-finite", "tracking error |e| =")), f
        blank = [s["rms_error_per_seed"][1] is None for s in m["segments"]]
        assert blank == [end > f["t"] for _, end, _ in sc.segments()], (arm, f, blank)
        assert all(s["rms_error_per_seed"][0] is not None for s in m["segments"])


class NanWithAlarms(NanAt):
    """NanAt that declares alarms: at 0.6 s (the 0.5 s swap found), 1.0 s (a false alarm) and, on the
    trial that fails at ``T_FAIL``, one at 1.8 s, after its failure."""

    @property
    def alarm_times(self):
        return [[0.6, 1.0], [0.6, 1.0, 1.8]]


def test_a_failed_trials_detector_figures_are_blank_everywhere():
    """per_seed.csv gave a failed trial's false alarms and delays (metrics.json None), and the report's
    detection line counted it as a miss beside the missed-swaps line that did not."""
    from adaptive_dd.benchmark.report import detection_limit_lines
    from adaptive_dd.benchmark.results import to_frame

    sc = dataclasses.replace(_short("two_link"), controllers=("ct_oracle",))
    res = run_benchmark(sc, progress=False, controllers={"alarmy": NanWithAlarms()})
    m = res.metrics()["controllers"]["alarmy"]
    assert m["false_alarms_per_seed"] == [1, None] and m["missed_swaps"] == 1
    df = to_frame(res)
    rows = df[df["controller"] == "alarmy"]
    failed = rows[rows["seed"] == 1]
    assert failed["false_alarms"].isna().all() and failed["detection_delay_s"].isna().all()
    # per segment: the false alarm at 1.0 s in the segment that holds it alone (each row had the
    # trial's count, so the rows summed to one per segment)
    ok = rows[rows["seed"] == 0]
    holds = (ok["start_s"] <= 1.0) & (1.0 < ok["end_s"])
    assert (ok["false_alarms"] == holds.astype(int)).all() and ok["false_alarms"].sum() == 1
    line = next(x for x in detection_limit_lines({"alarmy": m}) if "swap at 1.5 s" in x)
    assert "missed in all 1 trials" in line, line


def test_a_segment_too_short_to_settle_has_no_settled_rms():
    """A 0.1 s segment (swaps at 0.5 and 0.6 s) has no sample after its first 0.5 s: its settled
    RMS was the error of one sample, clamped there; it is None, on both arms."""
    for arm in ARMS:
        sc = dataclasses.replace(_short(arm), swap_times=(0.5, 0.6), controllers=("ct_oracle",))
        res = run_benchmark(sc, progress=False)
        seg = res.metrics()["controllers"]["ct_oracle"]["segments"]
        assert seg[1]["rms_error_settled"] is None and seg[2]["rms_error_settled"] is not None, arm


def test_the_information_line_names_a_law_that_never_learns_and_judges_only_estimators():
    """A law whose median trajectory never learned the mass was left off the line, and off the
    centre of mass's; with no law estimating the payload the line printed the target 'NOT met'."""
    from adaptive_dd.benchmark.report import _information_lines

    info = {"known": 0.04, "unknown": 0.3, "seeds": 3, "reference": "ct_oracle"}

    def ctrl(t, seeds):
        segs = [{}, {"start": 5.0, "mass": 3.0, "information_time": info, "mass_learning_time": t,
                     "learning_seeds": seeds}]  # fmt: skip
        return {"segments": segs}

    (line,) = _information_lines({"a": ctrl(0.07, 3), "b": ctrl(None, 3), "pd": ctrl(None, 0)}, True)
    assert "a 70 ms, b never (median over 3 seed(s)" in line and "pd" not in line and ": met)" in line
    (line,) = _information_lines({"pd": ctrl(None, 0)}, True)
    assert "no controller here estimates the payload" in line and "NOT met" not in line
    # the centre of mass's line names the same laws: one that never learns the mass is on it too
    com = {**info, "com_axes": "xyz", "com_known": 0.05}

    def with_com(t, t_com, seeds):
        x = ctrl(t, seeds)
        x["segments"][1].update(information_time=com, com_learning_time=t_com)
        return x

    _, line = _information_lines({"a": with_com(0.07, 0.09, 3), "b": with_com(None, 0.2, 3)}, True)
    assert "a 90 ms, b 200 ms (median over 3 seed(s))" in line, line
