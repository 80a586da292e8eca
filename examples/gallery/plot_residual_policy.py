"""
A hand-written residual policy on the UR5 tool swap
===================================================

A learned controller enters through :mod:`adaptive_dd.gym`: a Gymnasium environment whose
action is the joint torque, or, through :class:`~adaptive_dd.gym.ResidualTorque`, a torque
added to a base controller's command. :func:`~adaptive_dd.gym.evaluate` scores any policy
(a callable from the observation to the action) on the benchmark's trials against the floor,
seed by seed, as the benchmark scores its own laws.

Here the policy is tiny and hand-written, no learning: an integral of the measured tracking
error added to ``adaptive_ct`` (adaptive computed torque), on the UR5 tool swap (the robot drawn
around its URDF for each seed) cut to 6 s. Beside it, ``adaptive_ct`` alone (a zero residual).
"""

import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import adaptive_dd
from adaptive_dd.benchmark.scenario import parse_scenario
from adaptive_dd.gym import ResidualTorque, evaluate, make_env

# The UR5 tool swap, cut to 6 s: a 2 kg tool picked up at 2 s, put down at 4 s.
path = Path(adaptive_dd.__file__).parent / "scenarios" / "ur5_tool_swap.toml"
data = tomllib.loads(path.read_text())
data["run"]["duration"] = 6.0
data["payload"] = [data["payload"][0] | {"at": 2.0}, {"at": 4.0, "mass": 0.0}]
sc = parse_scenario(data, str(path), name="ur5_short")
n, T = sc.n_joints, sc.sample_period


class IntegralResidual:
    """``tau_r = Ki * integral of (q_d - q) dt`` on the measured q, per joint, bounded by 5 N m."""

    def __init__(self, ki):
        self.ki = np.asarray(ki, float)

    def reset(self):
        self.integral = np.zeros(n)

    def __call__(self, obs):
        q, q_d = obs[:n], obs[2 * n : 3 * n]
        self.integral += (q_d - q) * T
        return np.clip(self.ki * self.integral, -5.0, 5.0)


env = ResidualTorque(make_env(sc, floor=None), base="adaptive_ct")
seeds = [0, 1]
runs = {
    "adaptive_ct": evaluate(lambda obs: np.zeros(n), env, seeds, name="adaptive_ct"),
    "adaptive_ct + integral": evaluate(IntegralResidual(2000.0), env, seeds, name="adaptive_ct + integral"),
}

# %%
# The ratio of each trial's RMS tracking error to the floor's (``ct_oracle``, the same law
# with the true robot) on the same seed, per payload segment (mean over the seeds), and the
# tool frame's RMS position error.
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
width = 0.38
for j, (name, ev) in enumerate(runs.items()):
    x = np.arange(len(ev.segments)) + (j - 0.5) * width
    ax1.bar(x, np.nanmean(ev.ratio_to_floor, axis=0), width, label=name)
    ax2.bar(x, np.nanmean(ev.ee_position_rms, axis=0), width, label=name)
    for s, row in enumerate(ev.summary()):
        print(
            f"{name:24s} segment {s} ({row['mass_kg']:g} kg): ratio to the floor "
            f"{row['ratio_to_floor']['mean']:.3f}, tool frame {row['ee_position_rms_mm']:.3f} mm RMS"
        )
labels = [f"{a:g}-{b:g} s\n{m:g} kg" for a, b, m in sc.segments()]
for ax, title in ((ax1, "RMS error / floor's"), (ax2, "tool frame RMS error [mm]")):
    ax.set_xticks(range(len(labels)), labels)
    ax.set_title(title)
ax1.axhline(1.0, color="k", lw=0.8)
ax1.set_ylabel("RMS error / floor's [-]")
ax2.set_ylabel("RMS error [mm]")
ax1.legend()
fig.suptitle(
    "adaptive_ct with and without an integral residual on the UR5 tool swap, per payload segment "
    "[s, kg]: ratio of RMS error to the floor's [-] and the tool frame's RMS error [mm], mean over 2 seeds",
    fontsize=8,
)
fig.tight_layout()
