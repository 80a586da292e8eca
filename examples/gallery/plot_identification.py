"""
Identifying an arm from a record
================================

A record of joint angles, velocities and torques identifies the arm's base parameters, each with
its standard deviation. Here a 10 s record of the shipped three-joint arm (simulated, so the truth
is known) by weighted least squares on the exact filtered regression, the first stage of
``adaptive-dd identify --arm SCENARIO record.csv`` (which adds output error and the Cramér-Rao
bound; a real arm's CSV goes through the same function).
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import adaptive_dd
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.identification.model import arm_model
from adaptive_dd.identification.records import simulate_record
from adaptive_dd.identification.regression import filtered_regression, weighted_least_squares

sc = load_scenario(Path(adaptive_dd.__file__).parent / "scenarios" / "vertical3_payload.toml")
arm = sc.arm
rec = simulate_record(arm, sc.reference, 10.0, [np.random.default_rng(1)])
print(f"{rec.t.size} samples, {arm.n_joints} joints, {arm.base.count} base parameters")

# %%
# The record: the scenario's reference tracked for 10 s, the measured joint angles and the
# applied torques (what a real arm's CSV holds, with its velocities).
fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7, 4.5))
for j in range(arm.n_joints):
    ax1.plot(rec.t, rec.q[0, :, j], lw=1, label=f"joint {j + 1}")
    ax2.plot(rec.t, rec.tau[0, :, j], lw=1)
ax1.set_ylabel("q [rad]")
ax2.set_ylabel("tau [N m]")
ax2.set_xlabel("t [s]")
ax1.legend(fontsize=8, ncol=3)
fig.suptitle(
    "The record identified: joint angles [rad] and applied torques [N m] against time [s]", fontsize=9
)
fig.tight_layout()

# %%
# The regression filters both sides of the momentum form of the dynamics (no acceleration
# needed), then weights each joint's equation by its residual variance.
model = arm_model(arm)
reg = filtered_regression(model, rec.q[0], rec.qd[0], rec.tau[0], tau_f=0.01, sample_period=rec.sample_period)
wls = weighted_least_squares(reg, model.names)
for name, est, std, true in zip(arm.sigma_names, wls.sigma, wls.std, rec.sigma_true, strict=True):
    print(f"{name:>40}: {est:+.4f} +- {std:.4f} (true {true:+.4f})")

# %%
# Each estimate's error in units of its standard deviation. The standard deviation is the
# white-residual formula's, which is optimistic (the filtered residuals are coloured), so errors
# of a few of them are expected; ``adaptive-dd identify`` prints the Cramér-Rao bound beside it.
z = (wls.sigma - rec.sigma_true) / wls.std
print(f"largest |error| / std: {np.abs(z).max():.1f}")
labels = [n if len(n) <= 22 else n[:21] + "…" for n in arm.sigma_names]  # a base parameter's leading terms
fig, ax = plt.subplots(figsize=(7, 0.22 * z.size + 1.2))
ax.barh(np.arange(z.size), z, color=np.where(np.abs(z) > 2, "tab:red", "tab:blue"))
ax.axvline(2, color="k", lw=0.5)
ax.axvline(-2, color="k", lw=0.5)
ax.set_yticks(np.arange(z.size), labels, fontsize=7)
ax.invert_yaxis()
ax.set_xlabel("(estimate - true) / std [standard deviations]")
ax.set_title("Error of each named base parameter in standard deviations (red: beyond 2)", fontsize=9)
fig.tight_layout()
