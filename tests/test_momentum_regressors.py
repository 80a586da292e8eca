"""The momentum regressors (``identification/regression.py``) against their definition through the
base regressor: ``Y_p(q, qd) = W(q, 0, qd) - W(q, 0, 0)`` and ``Y_r = W(q, qd, 0) - dY_p/dq qd``
(central difference along the motion), on the shipped three-joint arm and a drawn six-joint one."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.scenario import read_toml
from adaptive_dd.identification.model import arm_model, base_regressor
from adaptive_dd.identification.regression import DIRECTION_STEP, momentum_regressors
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import robot_urdf

TEMPLATE = Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "population_drawn.toml"


def _by_definition(model, q, qd):
    zero = np.zeros_like(q)

    def yp(x):
        return base_regressor(model, x, zero, qd) - base_regressor(model, x, zero, zero)

    e = DIRECTION_STEP
    return yp(q), base_regressor(model, q, qd, zero) - (yp(q + e * qd) - yp(q - e * qd)) / (2 * e)


@pytest.mark.parametrize("which", ["vertical3", "random:1"])
def test_the_momentum_regressors_are_their_definition(which):
    if which == "vertical3":
        arm = Arm.from_urdf(robot_urdf("vertical3"))
    else:
        arm = population_scenario(read_toml(TEMPLATE), str(TEMPLATE), 1).arm
    model = arm_model(arm)
    rng = np.random.default_rng(5)
    q = rng.uniform(-2, 2, (300, model.n))
    qd = rng.uniform(-1.5, 1.5, (300, model.n))
    qd[:5] *= 0.01  # within the Coulomb law's width too
    for got, want in zip(momentum_regressors(model, q, qd), _by_definition(model, q, qd), strict=True):
        assert got.shape == want.shape == (300, model.n, model.p)
        scale = np.maximum(np.abs(want).max(axis=(0, 1)), 1e-12)  # per base column
        assert np.all(np.abs(got - want).max(axis=(0, 1)) <= 1e-9 * scale)
    # the identity the regression rests on: W(q, qd, qdd) = Y_r + dY_p/dq qd + Y_p(q, qdd)
    qdd = rng.uniform(-3, 3, q.shape)
    Yp_qdd, _ = momentum_regressors(model, q, qdd)
    _, Yr = momentum_regressors(model, q, qd)
    W = base_regressor(model, q, qd, qdd)
    dYp = W - Yr - Yp_qdd
    e = DIRECTION_STEP
    zero = np.zeros_like(q)
    central = (
        base_regressor(model, q + e * qd, zero, qd) - base_regressor(model, q + e * qd, zero, zero)
        - base_regressor(model, q - e * qd, zero, qd) + base_regressor(model, q - e * qd, zero, zero)
    ) / (2 * e)  # fmt: skip
    assert np.abs(dYp - central).max() <= 1e-9 * np.abs(W).max()
