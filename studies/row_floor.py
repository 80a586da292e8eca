"""The whitened rows' floor (``OnlineConfig.row_floor``) on the open-loop records of
``tests/test_online.py`` that whitening without a floor failed: per setting, on the noise-free UR5
record (1 kg -> 2.5 kg at 1.5 s, three seeds) the centre of mass's error [mm] 100 ms after the
swap and the alarms, and on the record whose wrist creeps (a swap at 3 s) the alarms. Also the
rows' noise and floors in N m (RMS) on the UR5 and the Gen3 (``docs/any_arm.md``, "A floor on each
row's error"). Then, on the closed-loop stick-slip records of ``tests/test_online.py`` (unloaded,
6 s, seeds 21 and 22): the payload mass each setting estimates, and the rows' noise in N m that
:func:`~adaptive_dd.identification.online.whitening_scale` predicts at the last posture against the
detector's learnt level of the same rows.

    python studies/row_floor.py
    python studies/row_floor.py --dac   # the D/A step against the rows' noise, the UR5 scenario
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_online import PAY_A, PAY_B, POSTURE, T, _closed_loop, _com, _slow_wrist_record

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.filters import filter_record
from adaptive_dd.identification.online import (
    OnlineConfig,
    derived_row_weights,
    est_init,
    est_step,
    row_floors,
    run_online,
    whitening_noise,
    whitening_scale,
)
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

SETTINGS = {
    "independent rows": {},
    "whitened, no floor": {"whiten": True, "row_floor": "none"},
    "whitened, stated floor": {"whiten": True, "row_floor": "stated"},
    "whitened, learnt level": {"whiten": True, "row_floor": "level"},
}


def rows_in_newton_metres(arm: Arm, name: str) -> None:
    cfg = OnlineConfig(whiten=True)
    scale = whitening_scale(cfg, arm)
    lim = arm.position_limits
    M0 = arm.mass_matrix(np.where(np.isfinite(lim).all(axis=1), lim.mean(axis=1), 0.0))
    M0 = M0 + np.diag(arm.armature)
    vn = whitening_noise(arm)
    noise = np.sqrt(np.diag((M0 * vn**2) @ M0.T) * scale)
    w = derived_row_weights(arm)
    stated = np.sqrt(row_floors(OnlineConfig(whiten=True, row_floor="stated"), arm)[0] * scale)
    print(f"{name}: rows' sensor noise at mid-range [N m RMS] {np.round(noise, 4)}")
    print(f"{name}: stated floor (detector floor x weight) {np.round(stated, 4)}; weights {np.round(w, 3)}")


def main() -> None:
    ur5 = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    rows_in_newton_metres(ur5, "UR5")
    t = np.arange(2_000) * T
    clean = []
    for seed in (0, 1, 2):
        rng = np.random.default_rng(seed)
        motion = exciting_motion(ur5, t, rng, offset=POSTURE)
        clean.append(prescribed_record(ur5, t, motion, [PAY_A, PAY_B], [1_500]))
    creep = _slow_wrist_record(ur5, 3, 4_000, [PAY_A, PAY_B], [3_000])
    for name, kw in SETTINGS.items():
        errs, alarms = [], []
        for r in clean:
            rec = run_online(ur5, OnlineConfig(align=False, **kw), r.q_meas, r.qd_meas, r.tau)
            errs.append(1e3 * np.linalg.norm(rec.com[0, 1_600] - _com(PAY_B)))
            alarms.append(rec.alarm_times()[0])
        rec = run_online(ur5, OnlineConfig(**kw), creep.q_meas, creep.qd_meas, creep.tau)
        k = 3_250
        print(
            f"{name:24s} noise-free: com error at 100 ms {' / '.join(f'{e:.1f}' for e in errs)} mm, "
            f"alarms {[[round(a, 3) for a in x] for x in alarms]}; creeping wrist: alarms "
            f"{[round(a, 3) for a in rec.alarm_times()[0]]}, com error 250 ms after the swap "
            f"{1e3 * np.linalg.norm(rec.com[0, k] - _com(PAY_B)):.1f} mm"
        )
    closed_loop_levels(ur5)


def closed_loop_levels(ur5: Arm) -> None:
    """Unloaded closed-loop records: each setting's payload mass, and noise against level."""
    n = 6_000
    for seed in (21, 22):
        qm, qdm, tau = _closed_loop(ur5, seed, n, [np.zeros(10), PAY_A], n + 1)
        for name, kw in SETTINGS.items():
            m = run_online(ur5, OnlineConfig(**kw), qm, qdm, tau).mass[0]
            print(
                f"seed {seed} {name:24s} mass at 1 / 2 / 6 s {np.round(m[[999, 1_999, 5_999]], 4)} kg, "
                f"largest after 0.5 s {np.abs(m[500:]).max():.4f} kg"
            )
        cfg = OnlineConfig(whiten=True)
        c, s = est_init(cfg, ur5, 1)
        for k in range(n):
            est_step(c, s, qm[k : k + 1], qdm[k : k + 1], tau[k : k + 1])
        nl = np.maximum(s.learned[0], 1)
        level = np.sqrt(s.long[0] / (1.0 - (1.0 - c.floats[K.F_ALPHA_LONG]) ** nl)) * derived_row_weights(ur5)
        M = ur5.mass_matrix(qm[-1]) + np.diag(ur5.armature)
        noise = np.sqrt(np.diag((M * whitening_noise(ur5) ** 2) @ M.T) * whitening_scale(cfg, ur5))
        print(f"seed {seed} rows' noise predicted [N m RMS] {np.round(noise, 5)}")
        print(f"seed {seed} detector's learnt level   [N m RMS] {np.round(level, 5)}")


def dac_against_noise(path: str = "adaptive_dd/scenarios/ur5_tool_swap_exact.toml") -> None:
    """The D/A step (uniform, ``2 limit / 2^bits``) through ``G0`` against the velocity noise through
    the nominal inertia's diagonal and ``G1``, per row [N m RMS]."""
    from adaptive_dd.benchmark.scenario import load_scenario

    arm = load_scenario(path).arm
    bank = OnlineConfig().bank
    imp = np.zeros(4_000)
    imp[0] = 1.0
    h = filter_record(bank, imp)
    g0, g1 = np.sum(h[:, 0] ** 2), np.sum(h[:, 1] ** 2)
    lim = np.asarray(arm.actuator.torque_limit, dtype=float)
    dac = 2.0 * lim / 2**arm.actuator.dac_bits / np.sqrt(12.0) * np.sqrt(g0)
    noise = np.sqrt(g1 * np.asarray(arm.sensor.velocity_variance)) * arm.nominal_inertia()
    print(f"{path}: D/A step through G0 [N m RMS] {np.round(dac, 6)}")
    print(f"{path}: velocity noise through M and G1 [N m RMS] {np.round(noise, 4)}")


if __name__ == "__main__":
    if sys.argv[1:] == ["--dac"]:
        dac_against_noise()
    else:
        main()
