"""Real logs as they come: gaps, several records, a model named by its arm's content.

The records are made here (:func:`adaptive_dd.identification.records.synthetic_log`: inverse
dynamics of the identification's own model along a multi-sine, torque noise coloured and
heteroscedastic), so the truth is known.
"""

from __future__ import annotations

import itertools
import shutil

import numpy as np
import pytest

from adaptive_dd.errors import DataError
from adaptive_dd.identification.log_fit import fit_log
from adaptive_dd.identification.model import arm_model
from adaptive_dd.identification.records import synthetic_log
from adaptive_dd.io import write_recording
from adaptive_dd.plant.arm import Arm
from adaptive_dd.record import read_log, record_spec
from adaptive_dd.record_pieces import find_gaps, gap_threshold, merge_records
from adaptive_dd.robots import robot_urdf

T = 0.005


@pytest.fixture(scope="module")
def vertical3():
    arm = Arm.from_urdf(robot_urdf("vertical3"))
    return arm, arm_model(arm)


def _fit(model, q, qd, tau, pieces=None):
    n = model.n
    return fit_log(
        model,
        q,
        qd,
        tau,
        np.ones(n, bool),
        np.ones(model.p, bool),
        tau_f=0.02,
        sample_period=T,
        hold=False,
        torque_held=False,
        pieces=pieces,
    )


def test_a_gap_is_a_step_beyond_the_logs_own_spread():
    """Jittered steps (+-20 %) have no gap; a planted 3-step hole is one; on a clean clock a single
    missed sample is one, and the jitter of the float stamps is not."""
    rng = np.random.default_rng(0)
    steps = 0.01 * (1 + rng.uniform(-0.2, 0.2, 2000))
    t = np.concatenate([[0.0], np.cumsum(steps)])
    assert find_gaps(t)[0].size == 0
    t_gap = np.delete(t, [700, 701])  # two rows dropped: a step of about three
    idx, limit = find_gaps(t_gap)
    assert idx.tolist() == [699] and 0.012 < limit < 0.02
    clean = np.arange(3000) * 1e-3
    assert find_gaps(clean)[0].size == 0
    assert find_gaps(np.delete(clean, 1500))[0].tolist() == [1499]
    assert gap_threshold(np.diff(clean)) == pytest.approx(1.5e-3)


def _write(path, log, drop=()):
    keep = np.setdiff1d(np.arange(log.t.size), np.asarray(drop, dtype=int))
    return write_recording(path, log.t[keep], log.q[keep], log.qd[keep], log.tau[keep])


def test_synthetic_log_draws_its_noise_from_noise_rng(vertical3):
    """``noise_rng``: the same motion (and clean torque) from the same ``rng``, the noise drawn from
    ``noise_rng`` alone; without it both come from ``rng``."""
    arm, _ = vertical3
    a = synthetic_log(arm, 2.0, T, np.random.default_rng(4), noise_rng=np.random.default_rng(5))
    b = synthetic_log(arm, 2.0, T, np.random.default_rng(4), noise_rng=np.random.default_rng(6))
    c = synthetic_log(arm, 2.0, T, np.random.default_rng(4), noise=0.0)
    np.testing.assert_array_equal(a.q, b.q)
    assert not np.allclose(a.tau, b.tau)
    np.testing.assert_array_equal(a.q, c.q)
    noise = a.tau - c.tau
    assert 0.005 < np.std(noise) / np.sqrt(np.mean(c.tau**2)) < 0.1  # 2 % of the rms, at most doubled
    d = synthetic_log(arm, 2.0, T, np.random.default_rng(4), noise_rng=np.random.default_rng(5))
    np.testing.assert_array_equal(a.tau, d.tau)


def test_read_log_splits_at_gaps_and_names_what_it_left_out(tmp_path, vertical3):
    arm, _ = vertical3
    log = synthetic_log(arm, 6.0, T, np.random.default_rng(1))
    drop = [*range(400, 410), *range(800, 803), *range(1080, 1084)]
    path = _write(tmp_path / "gaps.csv", log, drop)
    spec = record_spec(None, arm.joint_names, arm.joint_kinds, str(tmp_path / "s.toml"), files=[str(path)])
    rec = read_log(spec)
    assert rec.sample_period == pytest.approx(T, rel=1e-9)
    assert len(rec.spans) == 4
    gaps = [nt for nt in rec.notes if nt.startswith("a gap of")]
    assert len(gaps) == 3 and "at 1.995-2.05 s" in gaps[0]
    # measured velocities: nothing cut beside the gaps; every sample kept is a logged one
    assert rec.t.size == log.t.size - len(drop)
    np.testing.assert_allclose(rec.q, np.delete(log.q, drop, axis=0), atol=1e-9)
    split = next(nt for nt in rec.notes if nt.startswith("split at the gaps"))
    assert split.endswith("each resampled on its own") and "left out" not in split  # not "0 samples (0 s"
    # velocities derived from the positions: half the derivative's window cut beside each gap
    spec_d = record_spec(
        {"files": [str(path)], "velocity_source": "derived"}, arm.joint_names, arm.joint_kinds, "s.toml"
    )
    rec_d = read_log(spec_d)
    h = 10  # 0.1 s at 5 ms: a window of 21 samples, half of it 10
    assert rec_d.t.size == rec.t.size - 2 * 3 * h
    assert any("left out: 10 samples (0.05 s" in nt for nt in rec_d.notes)
    a, b = rec_d.spans[1]
    np.testing.assert_allclose(rec_d.qd[a:b], log.qd[410 + h : 800 - h], rtol=0, atol=2e-3)


def test_single_missed_samples_are_bridged_not_split(tmp_path, vertical3):
    """A logger that drops 1 % of its rows one at a time: every grid sample is kept and the estimate
    is the whole log's to a tenth of its std (split at each, a fifth of the samples was lost and the
    std grew 8-30 %); a hole of two rows is still a gap, split and named."""
    arm, model = vertical3
    log = synthetic_log(arm, 12.0, T, np.random.default_rng(3))
    rng = np.random.default_rng(7)
    drop = np.flatnonzero(rng.random(log.t.size) < 0.01)
    drop = drop[(drop > 1) & (drop < log.t.size - 2) & (drop != 1200) & (drop != 1201)]
    drop = drop[np.diff(drop, prepend=-9) > 1]  # single rows only
    fits = {}
    for label, dr in (("whole", []), ("drops", drop), ("hole", [*drop, 1200, 1201])):
        path = _write(tmp_path / f"{label}.csv", log, dr)
        spec = record_spec(
            {"files": [str(path)], "velocity_source": "derived"}, arm.joint_names, arm.joint_kinds, "s.toml"
        )
        rec = read_log(spec)
        fits[label] = (rec, _fit(model, rec.q, rec.qd, rec.tau, rec.pieces or None))
    rec, fit = fits["drops"]
    whole_rec, whole = fits["whole"]
    assert drop.size >= 15 and rec.t.size == whole_rec.t.size and rec.pieces == ()
    assert any(nt.startswith(f"bridged {drop.size} gap(s) of one missed sample") for nt in rec.notes)
    assert (np.abs(fit.sigma - whole.sigma) / whole.std).max() < 0.1
    hole, _ = fits["hole"]
    assert len(hole.pieces) == 2 and any("a gap of 0.015 s" in nt for nt in hole.notes)


def test_estimate_with_gaps_within_its_bound_of_the_estimate_without(vertical3):
    """Four gaps planted in a 24 s record: the estimate from its pieces is within two of its std of
    the whole record's; the pieces run as one record (the filters across the gaps) are not."""
    arm, model = vertical3
    log = synthetic_log(arm, 24.0, T, np.random.default_rng(2))
    whole = _fit(model, log.q, log.qd, log.tau)
    holes = [(900, 912), (1900, 1960), (2900, 2902), (3900, 3917)]
    keep = np.setdiff1d(np.arange(log.t.size), np.concatenate([np.arange(a, b) for a, b in holes]))
    cuts = np.flatnonzero(np.diff(keep) > 1) + 1
    bounds = [0, *cuts.tolist(), keep.size]
    pieces = list(itertools.pairwise(bounds))
    q, qd, tau = log.q[keep], log.qd[keep], log.tau[keep]
    split = _fit(model, q, qd, tau, pieces)
    assert split.regression.pieces == tuple(pieces)
    z = np.abs(split.sigma - whole.sigma) / split.std
    assert z.max() < 2.0, z
    joined = _fit(model, q, qd, tau)  # the fault: the gaps taken as continuous
    assert (np.abs(joined.sigma - whole.sigma) / split.std).max() > 3.0


def test_several_records_fit_jointly(vertical3):
    """Two records of one arm, fitted together as the pieces of one: the truth within three std, the
    std smaller than either record's alone, both records' rows in the fit, and the bound's quantile
    (fixed-b) from the rows of both: nearer the normal's 1.96 than either record's alone."""
    arm, model = vertical3
    logs = [synthetic_log(arm, 12.0, T, np.random.default_rng(10 + s)) for s in range(2)]
    alone = [_fit(model, g.q, g.qd, g.tau) for g in logs]
    N = logs[0].t.size
    both = _fit(
        model,
        np.concatenate([g.q for g in logs]),
        np.concatenate([g.qd for g in logs]),
        np.concatenate([g.tau for g in logs]),
        [(0, N), (N, 2 * N)],
    )
    assert both.regression.y.shape[0] == sum(f.regression.y.shape[0] for f in alone)
    assert np.all(np.abs(both.sigma - logs[0].sigma_true) < 3 * both.std)
    assert np.median(both.std / np.minimum(alone[0].std, alone[1].std)) < 0.95
    # the bound's quantile from the rows of both records: nearer the normal's than either record's
    from adaptive_dd.identification.log_fit import fixed_b_quantile

    rows = both.regression.y.shape[0]
    assert both.quantile == pytest.approx(fixed_b_quantile(both.bandwidth))
    assert both.bandwidth >= 0.95 * (both.lag + 1) / rows
    assert 1.96 < both.quantile < min(f.quantile for f in alone), [both.quantile, [f.quantile for f in alone]]


def test_merge_records_refuses_another_period(tmp_path, vertical3):
    arm, _ = vertical3
    log = synthetic_log(arm, 2.0, T, np.random.default_rng(3))
    p1 = _write(tmp_path / "a.csv", log)
    p2 = write_recording(tmp_path / "b.csv", log.t[::2], log.q[::2], log.qd[::2], log.tau[::2])
    recs = [
        read_log(record_spec(None, arm.joint_names, arm.joint_kinds, "s.toml", files=[str(p)]))
        for p in (p1, p2)
    ]
    with pytest.raises(DataError, match=r"b.csv: sample period 0.01 s, the first record's 0.005 s"):
        merge_records(recs, [str(p1), str(p2)])
    rec = merge_records([recs[0], recs[0]], ["a", "a again"])
    assert rec.spans == ((0, log.t.size), (log.t.size, 2 * log.t.size)) and rec.piece_label(1) == "a again"


def test_command_line_files_are_grouped_into_records(tmp_path):
    from adaptive_dd.cli._records import group_records

    scen = tmp_path / "s.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n\n[record]\nfiles = ["p.csv", "e.csv"]\n')
    assert group_records(str(scen), ["p1", "e1", "p2", "e2"]) == [
        (str(scen), ["p1", "e1"]),
        (str(scen), ["p2", "e2"]),
    ]
    assert group_records(str(scen), ["other.toml", "p1", "e1"]) == [
        ("other.toml", None),
        (str(scen), ["p1", "e1"]),
    ]
    with pytest.raises(DataError, match=r"3 file\(s\) on the command line .* each record is 2 file\(s\)"):
        group_records(str(scen), ["p1", "e1", "p2"])


def test_model_names_its_arm_by_content(tmp_path):
    """A byte-identical copy of the URDF is the same arm; a moved joint or another fixed parameter is
    named."""
    from adaptive_dd.identification.identified_model import arm_identity, identity_differences

    src = robot_urdf("vertical3")
    copy = tmp_path / "copy.urdf"
    shutil.copy(src, copy)
    a, b = Arm.from_urdf(src), Arm.from_urdf(copy)
    ma = arm_model(a)
    K = np.ones(ma.p, bool)
    K[-1] = False  # one base parameter held at the URDF's value
    ia, ib = arm_identity(a, ma, K), arm_identity(b, arm_model(b), K)
    assert ia["hash"] == ib["hash"] and identity_differences(ia, ib) == []
    text = copy.read_text()
    at = text.index('<joint name="joint2"')
    at = text.index('<origin xyz="0.4 0 0"', at)
    moved = text[:at] + '<origin xyz="0.41 0 0"' + text[at + len('<origin xyz="0.4 0 0"') :]
    (tmp_path / "moved.urdf").write_text(moved)
    c = Arm.from_urdf(tmp_path / "moved.urdf")
    diff = identity_differences(ia, arm_identity(c, arm_model(c), K))
    assert diff and any("translation" in d for d in diff), diff
    d = dict(ia, hash="x", fixed={k: v + 1.0 for k, v in ia["fixed"].items()})
    assert any(s.startswith(f"fixed parameter {ma.names[-1]}") for s in identity_differences(d, ia))


@pytest.mark.slow
def test_cli_identify_several_records_with_gaps_and_predict_on_a_copy(tmp_path, capsys, vertical3):
    """``identify --arm`` on two records, one with a gap, then ``predict`` on two held-out records
    through a scenario whose URDF is a copy (the same arm), and refused on a moved joint."""
    from adaptive_dd.cli import main

    arm, _ = vertical3
    logs = [synthetic_log(arm, 8.0, T, np.random.default_rng([7, s]), noise=0.01) for s in range(4)]
    files = [
        str(_write(tmp_path / f"r{s}.csv", g, range(700, 720) if s == 0 else ())) for s, g in enumerate(logs)
    ]
    scen = tmp_path / "v3.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n')
    out = tmp_path / "id"
    assert main(["identify", "--arm", str(scen), *files[:2], "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "2 records fitted together, 3 continuous pieces in all" in text
    assert "a gap of 0.105 s at 3.495-3.6 s" in text
    assert "what a std means" in text
    # the bound's half-width: the fixed-b quantile of the fit, above the normal's
    import re

    c = float(re.search(r"estimate \+- (\d\.\d+) std \(not 1\.96", text).group(1))
    assert 1.97 < c < 2.6, c
    import json

    saved = json.loads((out / "model.json").read_text())
    assert len(saved["record"]["pieces"]) == 3 and len(saved["record"]["records"]) == 2
    copy = tmp_path / "copy.urdf"
    shutil.copy(robot_urdf("vertical3"), copy)
    scen2 = tmp_path / "copy.toml"
    scen2.write_text('[arm]\nurdf = "copy.urdf"\npayload_frame = "tool"\n')
    pred = tmp_path / "pred"
    assert (
        main(
            [
                "predict",
                "--arm",
                str(scen2),
                "--model",
                str(out / "model.json"),
                *files[2:],
                "--out",
                str(pred),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert text.count("record ") >= 2 and "all 2 records:" in text
    pooled = [float(x.split(":")[1].split()[0]) for x in text.splitlines() if "pooled over the fitted" in x]
    rms = np.sqrt(np.mean(logs[2].tau ** 2))
    assert len(pooled) == 6 and max(pooled) < 0.1 * rms
    moved = copy.read_text()
    at = moved.index('<origin xyz="0.4 0 0"', moved.index('<joint name="joint2"'))
    copy.write_text(moved[:at] + '<origin xyz="0.42 0 0"' + moved[at + len('<origin xyz="0.4 0 0"') :])
    assert (
        main(
            ["predict", "--arm", str(scen2), "--model", str(out / "model.json"), files[2], "--out", str(pred)]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert (
        "identified on another arm" in err and "joint 'joint2' translation: 0.4,0,0 against 0.42,0,0" in err
    )


def test_long_run_factor_counts_independent_samples():
    """White noise: each sample is one; AR(1) with coefficient a: (1 + a) / (1 - a) samples are one
    (less the Bartlett weights' shrinkage at a finite lag); two pieces pooled are as one."""
    from adaptive_dd.identification.log_fit import long_run_factor

    rng = np.random.default_rng(5)
    assert long_run_factor(rng.standard_normal(20000), 30) == pytest.approx(1.0, abs=0.1)
    a, N = 0.8, 40000
    e = np.empty(N)
    e[0] = 0.0
    z = rng.standard_normal(N)
    for k in range(1, N):
        e[k] = a * e[k - 1] + z[k]
    lag = 200
    m = np.arange(1, lag + 1)
    expected = 1 + 2 * np.sum((1 - m / (lag + 1)) * a**m)  # 8.8, against (1 + a) / (1 - a) = 9
    assert long_run_factor(e, lag) == pytest.approx(expected, rel=0.1)
    assert long_run_factor(e, lag, [(0, N // 2), (N // 2, N)]) == pytest.approx(expected, rel=0.1)


def test_kernel_bias_restores_the_whole_long_run_variance():
    """AR(1) with coefficient a: the whole long-run factor is (1 + a) / (1 - a); the Bartlett sum at a
    lag of three times the autocorrelation's 0.05 crossing (as newey_west picks it) discounts its
    weights' share and leaves out the lags beyond, about a tenth; the correction (the autocorrelation
    before the crossing, a geometric tail beyond) restores it, on one record and on two pieces (mean
    of 8 records); on white noise it is 1."""
    import scipy.signal

    from adaptive_dd.identification.log_fit import _kernel_bias, long_run_factor

    rng = np.random.default_rng(7)
    assert _kernel_bias(rng.standard_normal(20000), 30, [(0, 20000)]) == pytest.approx(1.0, abs=0.03)
    for a, N in ((0.9, 60000), (0.95, 120000)):
        lag = 3 * int(np.ceil(np.log(0.05) / np.log(a)))
        out = []
        for _ in range(8):
            e = scipy.signal.lfilter([1.0], [1.0, -a], rng.standard_normal(N))
            F = long_run_factor(e, lag)
            out.append(
                (F, F * _kernel_bias(e, lag, [(0, N)]), F * _kernel_bias(e, lag, [(0, N // 2), (N // 2, N)]))
            )
        bartlett, one, two = np.mean(out, axis=0)
        whole = (1 + a) / (1 - a)
        assert bartlett < 0.93 * whole
        assert one == pytest.approx(whole, rel=0.04) and two == pytest.approx(whole, rel=0.04)


def _filtered_derivative_noise(rng, N: int, tau: float) -> np.ndarray:
    """White noise differentiated and low-passed twice at ``tau`` samples (as a measured velocity's
    noise reaches the residual through ``G1 = s G0``): autocorrelation ``(1 - x) exp(-x)``,
    ``x = m / tau``, a positive core and a negative lobe that cancels it."""
    import scipy.signal

    a = np.exp(-1.0 / tau)
    e = np.diff(rng.standard_normal(N + 1))
    return scipy.signal.lfilter([1.0 - a], [1.0, -a], scipy.signal.lfilter([1.0 - a], [1.0, -a], e))


def test_the_least_lag_sums_the_lobe_that_cancels_the_core():
    """A slow regression whose residual is a velocity noise seen through the filters (a core and a
    lobe that cancels it) and a torque noise: over 200 draws the sandwich std as fit_log scales it
    (the kernel and degrees-of-freedom factors) at the filters' least lag (16 tau_f) is within
    15 % of the estimates' spread (0.93 and 1.00); at three times the 0.05 crossing alone (in the
    core) the sine's is 1.7 times its spread."""
    from adaptive_dd.identification.log_covariance import _dof_factor, _kernel_bias, newey_west

    rng = np.random.default_rng(9)
    N, tau = 6000, 20.0
    t = np.arange(N) / N
    phi = np.stack([np.sin(2 * np.pi * 10 * t), np.cos(2 * np.pi * 17 * t) + 0.3], axis=1)[:, None, :]
    one = np.ones(1)
    est, std = [], {0: [], int(16 * tau): []}
    for _ in range(200):
        e = _filtered_derivative_noise(rng, N, tau) + 0.005 * rng.standard_normal(N)
        x = np.linalg.lstsq(phi[:, 0], e, rcond=None)[0]
        res = (e - phi[:, 0] @ x)[:, None]
        est.append(x)
        for floor, out in std.items():
            cov, lag = newey_west(phi, res, one, np.ones(2), floor=floor)
            factor = _kernel_bias(res[:, 0], lag, [(0, N)]) * _dof_factor(res, one, lag, [(0, N)], 2)[1]
            out.append(np.sqrt(np.diag(cov) * factor))
    spread = np.std(est, axis=0, ddof=1)
    at_floor, in_core = spread / np.mean(std[int(16 * tau)], axis=0), spread / np.mean(std[0], axis=0)
    assert np.all(np.abs(at_floor - 1) < 0.15), at_floor
    assert in_core[0] < 0.7, in_core


def test_fit_log_takes_the_filters_least_lag_and_the_residual_s_longer_one(vertical3):
    """A record whose torque noise is white: the residual is that noise through the filters, its
    0.05 crossing short, and fit_log's lag is the filters' least (``16 tau_f / T``); with the synthetic
    log's noise correlated over 0.05 s the residual's own rule gives a longer one, kept."""
    from adaptive_dd.identification.log_covariance import filter_lag

    arm, model = vertical3
    clean = synthetic_log(arm, 12.0, T, np.random.default_rng(4), noise=0.0)
    tau = clean.tau + 0.02 * clean.tau.std(axis=0) * np.random.default_rng(5).standard_normal(clean.tau.shape)
    assert _fit(model, clean.q, clean.qd, tau).lag == filter_lag(0.02, T) == 64
    log = synthetic_log(arm, 12.0, T, np.random.default_rng(4))
    assert _fit(model, log.q, log.qd, log.tau).lag > 64


def test_identify_says_what_set_the_lag(vertical3, capsys):
    """The status line named the filters' least lag where a short record's cap (a quarter of its
    longest piece) had set a shorter one; it names what did: the cap (and the least it fell short
    of), the least, or the residual's own correlation."""
    from adaptive_dd.cli._identify_log import _print_fit

    arm, model = vertical3
    names = tuple(f"j{k}" for k in range(model.n))
    short = synthetic_log(arm, 1.2, T, np.random.default_rng(4))
    from adaptive_dd.errors import RunWarning

    with pytest.warns(
        RunWarning,
        match=r"about \d+ independent samples for 17 columns fitted: the std's small-sample factor is capped",
    ):
        fit = _fit(model, short.q, short.qd, short.tau)  # (a record this short is refused by identify)
    _print_fit(model, fit, names)
    assert (
        "lag 50 samples = 0.25 s (capped at a quarter of the longest piece, 200 rows; the filters' least"
        in (capsys.readouterr().out)
    )
    clean = synthetic_log(arm, 12.0, T, np.random.default_rng(4), noise=0.0)
    tau = clean.tau + 0.02 * clean.tau.std(axis=0) * np.random.default_rng(5).standard_normal(clean.tau.shape)
    _print_fit(model, _fit(model, clean.q, clean.qd, tau), names)
    assert "lag 64 samples = 0.32 s (the filters' least: 16 tau_f" in capsys.readouterr().out


def test_fixed_b_quantile_is_the_studentised_mean_s_under_a_bartlett_std():
    """The mean of white noise studentised by its Bartlett (Newey-West) std of bandwidth b T: the 95th
    percentile of |t| over many draws is Kiefer and Vogelsang's cubic (2.26 at b = 0.1, not the
    normal's 1.96: the std's own uncertainty and its bias from the estimated mean); b out of [0, 1]
    is refused."""
    from adaptive_dd.identification.log_fit import NORMAL_975, fixed_b_quantile

    rng = np.random.default_rng(11)
    T, b, draws = 500, 0.1, 6000
    M = round(b * T)
    u = rng.standard_normal((draws, T))
    e = u - u.mean(axis=1, keepdims=True)
    f = np.fft.rfft(e, 2 * T, axis=1)
    ac = np.fft.irfft(f * np.conj(f), axis=1)[:, :M] / T
    s2 = ac[:, 0] + 2 * np.sum((1 - np.arange(1, M) / M) * ac[:, 1:], axis=1)
    t = np.abs(np.sqrt(T) * u.mean(axis=1) / np.sqrt(s2))
    # the percentile's sampling error over 6000 draws is about 0.02
    assert np.quantile(t, 0.95) == pytest.approx(fixed_b_quantile(b), abs=0.06)
    assert np.quantile(t, 0.95) > NORMAL_975 + 0.15
    assert fixed_b_quantile(0.0) == pytest.approx(1.96, abs=1e-3)
    with pytest.raises(ValueError, match=r"b = 1\.5"):
        fixed_b_quantile(1.5)


def test_times_are_printed_to_the_microsecond_on_a_clock_far_from_zero():
    """An epoch clock read 1.7e+09 at every stamp, an uptime clock 20001 at 20001.05 and 20001.02:
    a window's ends and a gap's could not be told apart."""
    from adaptive_dd.record_pieces import clock

    assert clock(9.999) == "9.999" and clock(0) == "0" and clock(-3.25) == "-3.25"
    assert clock(20001.05) == "20001.05" and clock(1700000011.000034) == "1700000011.000034"
    assert clock(1700000011.02) != clock(1700000011.03)


def test_how_much_too_small_a_capped_std_is_reads_as_a_share_or_a_factor():
    """``the std is too small by about 1x`` read as not at all: below a factor of 2 a share."""
    from adaptive_dd.identification.log_covariance import MAX_DOF_FACTOR
    from adaptive_dd.identification.log_fit import too_few_samples

    k = 10
    near = k / (1 - 1 / (1.5**2 * MAX_DOF_FACTOR))  # n_eff whose std should be 1.5x larger
    far = k / (1 - 1 / (3.0**2 * MAX_DOF_FACTOR))  # 3x
    assert "the std is about 33 % too small;" in too_few_samples(near, k, 1.0)
    assert "the std is too small by about 3x;" in too_few_samples(far, k, 1.0)
