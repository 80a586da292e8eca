"""A constant torque offset per channel, fitted with the parameters (``identify --torque-offset``).

The records are made here (:func:`adaptive_dd.identification.records.synthetic_log`), an offset
planted in each torque channel, so the truth is known.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from adaptive_dd.errors import DataError
from adaptive_dd.identification.log_fit import fit_log
from adaptive_dd.identification.model import arm_model
from adaptive_dd.identification.records import synthetic_log
from adaptive_dd.io import write_recording
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import robot_urdf

T = 0.005


@pytest.fixture(scope="module")
def vertical3():
    arm = Arm.from_urdf(robot_urdf("vertical3"))
    return arm, arm_model(arm)


def _fit(model, log, tau, offset):
    n = model.n
    return fit_log(
        model,
        log.q,
        log.qd,
        tau,
        np.ones(n, bool),
        np.ones(model.p, bool),
        tau_f=0.02,
        sample_period=T,
        hold=False,
        torque_held=False,
        offset=offset,
    )


def _planted(log):
    """Offsets of 5 % of each channel's torque rms, signs alternating [N m]."""
    rms = np.sqrt(np.mean(log.tau**2, axis=0))
    return 0.05 * rms * np.array([1.0, -1.0, 1.0])


def test_planted_offsets_are_found_within_their_bound(vertical3):
    """Offsets planted in every channel of a 24 s record: fitted, the offsets and the parameters are
    within their printed bounds of the truth; without the offsets the gravity terms absorb them and
    some parameter is many std off."""
    arm, model = vertical3
    log = synthetic_log(arm, 24.0, T, np.random.default_rng(3))
    b = _planted(log)
    fit = _fit(model, log, log.tau + b, offset=True)
    assert fit.offset is not None and fit.offset_std is not None
    assert np.all(fit.offset_std > 0)
    assert np.all(np.abs(fit.offset - b) < fit.quantile * 1.5 * fit.offset_std), (fit.offset, b)
    z = np.abs(fit.sigma - log.sigma_true) / fit.std
    assert np.mean(z < fit.quantile) >= 0.8 and z.max() < 4.0, z
    plain = _fit(model, log, log.tau + b, offset=False)
    assert plain.offset is None
    assert (np.abs(plain.sigma - log.sigma_true) / plain.std).max() > 6.0


def test_offsets_on_a_record_without_any_are_near_zero_and_leave_the_estimate(vertical3):
    """No offset in the record: the fitted offsets are within their bound of 0 and the estimate within
    a std of the fit without offsets; the offset columns cost information: the std of the gravity
    term they trade with (mx1 + 0.4 m2 + 0.4 m3, the first) grows many times, the others' hardly change."""
    arm, model = vertical3
    log = synthetic_log(arm, 24.0, T, np.random.default_rng(4))
    fit = _fit(model, log, log.tau, offset=True)
    plain = _fit(model, log, log.tau, offset=False)
    assert np.all(np.abs(fit.offset) < fit.quantile * 1.5 * fit.offset_std), fit.offset / fit.offset_std
    assert np.all(np.abs(fit.sigma - plain.sigma) < fit.std)
    ratio = fit.std / plain.std
    assert ratio[0] > 5.0 and 0.9 < np.median(ratio) < 1.5, ratio


def _scenario(tmp_path, table: str):
    scen = tmp_path / f"v3_{abs(hash(table))}.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n' + table)
    return str(scen)


def test_cli_fits_offsets_on_a_record_table_and_predict_adds_them(tmp_path, capsys, vertical3):
    """``identify --arm`` on a log read through a ``[record]`` table fits the offsets by default (auto),
    prints them, writes them to model.json, and ``predict`` adds them: the held-out error is that of a
    record without offsets. On the simulator's format (no ``[record]``) auto fits none; --torque-offset
    on forces them; a model.json with a bad offset is refused naming the key."""
    from adaptive_dd.cli import main

    arm, _ = vertical3
    logs = [synthetic_log(arm, 12.0, T, np.random.default_rng([8, s]), noise=0.01) for s in range(2)]
    b = _planted(logs[0])
    files = [
        str(write_recording(tmp_path / f"r{s}.csv", g.t, g.q, g.qd, g.tau + b)) for s, g in enumerate(logs)
    ]
    real = _scenario(tmp_path, '[record]\ntime = "t"\ntorque_held = false\n')
    out = tmp_path / "id"
    common = ["--coulomb-width", "noise", "--hold-unseen", "off"]
    assert main(["identify", "--arm", real, files[0], "--out", str(out), *common]) == 0
    text = capsys.readouterr().out
    assert "torque offset per channel, fitted with the parameters (auto" in text
    saved = json.loads((out / "model.json").read_text())
    got = np.array(saved["torque_offset"])
    std = np.array(saved["record"]["torque_offset_std"])
    assert np.all(np.abs(got - b) < 3 * std), (got, b, std)
    pred = tmp_path / "pred"
    assert (
        main(["predict", "--arm", real, "--model", str(out / "model.json"), files[1], "--out", str(pred)])
        == 0
    )
    text = capsys.readouterr().out
    pooled = [float(x.split(":")[1].split()[0]) for x in text.splitlines() if "pooled over the fitted" in x]
    assert max(pooled) < 0.5 * np.sqrt(np.mean(b**2)), (pooled, b)
    # the simulator's format: none by default, on when asked
    sim = _scenario(tmp_path, "")
    out2 = tmp_path / "id2"
    assert (
        main(["identify", "--arm", sim, files[0], "--out", str(out2), *common, "--output-error", "off"]) == 0
    )
    assert "torque offsets: none fitted (auto: the simulator's record)" in capsys.readouterr().out
    assert json.loads((out2 / "model.json").read_text())["torque_offset"] is None
    forced = ["--output-error", "off", "--torque-offset", "on"]
    assert main(["identify", "--arm", sim, files[0], "--out", str(out2), *common, *forced]) == 0
    assert "(--torque-offset on; added by predict)" in capsys.readouterr().out
    # output error has no offsets: asked for with --payload-only, a message, not an ignored option
    assert main(["identify", "--arm", real, files[0], "--payload-only", *forced[2:]]) == 2
    assert "--torque-offset on: --payload-only fits by output error" in capsys.readouterr().err
    # --payload-only with --baseline: refused, not ignored
    assert main(["identify", "--arm", real, files[0], "--baseline", files[0], "--payload-only"]) == 2
    assert "--baseline: --payload-only" in capsys.readouterr().err
    saved["torque_offset"] = [0.0, float("nan")]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(saved))
    from adaptive_dd.identification.identified_model import load_identified_model

    with pytest.raises(DataError, match="key 'torque_offset' must be 3 finite offsets"):
        load_identified_model(bad)
