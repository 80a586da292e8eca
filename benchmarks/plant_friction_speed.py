"""Cost of the compiled plant step per friction law: ``python benchmarks/plant_friction_speed.py``.

Steps a batch of SICE arms (Table 2 torques) through ``step_kernel`` and prints
microseconds per trial and sample for stick-slip, tanh (two friction velocities)
and Stribeck. The smooth laws refine RK4 steps where the friction is stiff, so a
smaller friction velocity costs more.
"""

from __future__ import annotations

import time

import numpy as np

from adaptive_dd.experiments import table2_torque
from adaptive_dd.plant import ClosedFormTwoLink
from adaptive_dd.plant.two_link_integrator import step_kernel


def time_law(arm: ClosedFormTwoLink, n_trials: int = 60, n_samples: int = 3000) -> float:
    """Microseconds per trial and sample of one plant step under ``arm``'s friction law."""
    tau = np.ascontiguousarray(table2_torque(n_trials, n_samples).transpose(1, 0, 2))
    sig = np.ascontiguousarray(np.broadcast_to(arm.sigma, (n_trials, 7)))
    q, qd = np.zeros((n_trials, 2)), np.zeros((n_trials, 2))
    stuck, slip = np.ones((n_trials, 2), bool), np.ones((n_trials, 2))
    args = (1e-3, 2, arm.friction_code, arm.friction_params)
    step_kernel(q, qd, stuck, slip, tau[0], sig, *args)  # compile
    t0 = time.perf_counter()
    for k in range(n_samples):
        step_kernel(q, qd, stuck, slip, tau[k], sig, *args)
    return 1e6 * (time.perf_counter() - t0) / (n_trials * n_samples)


if __name__ == "__main__":
    for label, arm in (
        ("stick-slip", ClosedFormTwoLink.sice()),
        ("tanh, v = 0.02 rad/s", ClosedFormTwoLink.sice(friction="tanh", friction_velocity=0.02)),
        ("tanh, v = 0.005 rad/s", ClosedFormTwoLink.sice(friction="tanh", friction_velocity=0.005)),
        ("stribeck, v = 0.02, v_s = 0.1 rad/s", ClosedFormTwoLink.sice(friction="stribeck")),
    ):
        print(f"{label:<38s} {time_law(arm):6.2f} us per trial-sample")
