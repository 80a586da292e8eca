"""The TIAGo's real log: what holding the directions a record cannot see does to the held-out
prediction (docs/learning_the_arm.md, "Directions a record cannot see").

``python studies/held_directions_tiago.py``: trained on 9.21-48 s as ``adaptive-dd identify --arm
examples/tiago/tiago.toml --window 9.21 48`` does, the torque of 48-67.9 s predicted (low-passed
2 Hz, as ``adaptive-dd predict``), with the Coulomb width of the arm (0.02 rad/s) and of the record
(:func:`~adaptive_dd.identification.friction_width.identification_model`), nothing held and the
hold at several thresholds (``HOLD_RATIO``, a ratio of variances; the rule's is 1).
"""

from __future__ import annotations

import numpy as np

from adaptive_dd.cli._common import load_arm, read_arm_log
from adaptive_dd.cli.predict import lowpass
from adaptive_dd.identification import held_directions
from adaptive_dd.identification.friction_width import identification_model
from adaptive_dd.identification.log_fit import fit_log, identifiable_subset, predict_torque
from adaptive_dd.identification.model import arm_model
from adaptive_dd.record import derivatives

SCENARIO = "examples/tiago/tiago.toml"


def main() -> int:
    arm = load_arm(SCENARIO, True)
    _, tr = read_arm_log(SCENARIO, arm, window=(9.21, 48.0))
    _, te = read_arm_log(SCENARIO, arm, window=(48.0, 67.9))
    lim = arm.position_limits
    qd, qdd = derivatives(te.q, te.sample_period)
    print("Coulomb width        hold        held  scale  arm_1 / 2 / 3 / 4 [N m]            pooled")
    for model in (arm_model(arm), identification_model(arm, tr.qd)):
        K = identifiable_subset(model, tr.used, lim[:, 0], lim[:, 1], np.random.default_rng(0))
        for ratio in (None, 1.0, 10.0, 100.0, 1e3, 1e4):
            held_directions.HOLD_RATIO = 1.0 if ratio is None else ratio
            fit = fit_log(
                model, tr.q, tr.qd, tr.tau, tr.used, K, tau_f=0.02, sample_period=tr.sample_period,
                hold=ratio is not None,
            )  # fmt: skip
            th = predict_torque(model, fit.sigma, te.q, qd, qdd)
            e = (lowpass(te.tau, 2.0, te.sample_period) - lowpass(th, 2.0, te.sample_period))[:, tr.used]
            per = np.sqrt(np.mean(e**2, axis=0))
            count = 0 if fit.held is None else fit.held.count
            scale = 1.0 if fit.held is None else np.sqrt(fit.held.scale2)
            label = "off" if ratio is None else f"ratio {ratio:g}"
            print(
                f"{model.friction_velocity:10.3g} rad/s  {label:<11} {count:4d} {scale:6.3g}  "
                f"{' / '.join(f'{x:.4f}' for x in per)}  {np.sqrt(np.mean(e**2)):.4f}",
                flush=True,
            )
    held_directions.HOLD_RATIO = 1.0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
