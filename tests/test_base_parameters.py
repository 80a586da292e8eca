"""The base-parameter finder's threshold: a URDF's rounded angles do not make base parameters.

Kinova's Gen3 URDF writes its right angles as 1.5708 and 3.1416; with round-off's threshold
(1e-9) the finder kept 65 base parameters, three of them columns at 3e-6 of the largest that no
record identifies. :data:`~adaptive_dd.plant.base_parameters.RTOL` keeps the 62 of the exact
robot, and leaves every shipped arm's structure as it was.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.plant.base_parameters import RTOL, base_parameters

# (scenario, base parameters): the counts of the exact robots (link 1 turns about gravity on
# every arm here but vertical3 and the paper's arm, whose structures are their own)
ARMS = [
    ("adaptive_dd/scenarios/ur5_tool_swap.toml", 52),
    ("adaptive_dd/scenarios/panda_payload.toml", 62),
    ("adaptive_dd/scenarios/iiwa14_payload.toml", 62),
    ("adaptive_dd/scenarios/vertical3_payload.toml", 17),
    ("benchmarks/scenarios/sice_drawn.toml", 9),
    ("benchmarks/scenarios/gen3_drawn.toml", 62),
]


def _sampled(arm):
    n = arm.n_joints
    lim = arm.position_limits
    rng = np.random.default_rng(0)
    lo = np.where(np.isfinite(lim[:, 0]), lim[:, 0], -np.pi)
    hi = np.where(np.isfinite(lim[:, 1]), lim[:, 1], np.pi)
    q = rng.uniform(lo, hi, (60, n))
    qd = rng.uniform(-2.0, 2.0, (60, n))
    qdd = rng.uniform(-5.0, 5.0, (60, n))
    return np.asarray(arm.standard_regressor(q, qd, qdd)).reshape(60 * n, 13 * n)


@pytest.mark.parametrize(("path", "p"), ARMS, ids=[a[0].split("/")[-1] for a in ARMS])
def test_each_arm_has_its_exact_robots_base_parameters_with_a_margin(path, p):
    arm = load_scenario(path).arm
    assert len(arm.base.names) == p
    # every kept column is at least 20x the threshold: its structure does not hang on RTOL
    W = _sampled(arm)
    norms = np.linalg.norm(W, axis=0)
    rel = norms / norms.max()
    genuine = rel[rel > RTOL]
    assert genuine.min() >= 20 * RTOL
    Ws = W[:, rel > RTOL] / norms[rel > RTOL]
    d = np.abs(np.diag(scipy.linalg.qr(Ws, mode="r")[0])) / np.sqrt(Ws.shape[0])
    assert np.sort(d)[-p] >= 20 * RTOL  # the p-th largest: the smallest kept


def test_round_off_threshold_keeps_the_gen3_rounded_angles_columns():
    """The planted fault: round-off's 1e-9 keeps three columns the rounded angles made."""
    arm = load_scenario("benchmarks/scenarios/gen3_drawn.toml").arm
    lim = arm.position_limits
    old = base_parameters(
        arm.standard_regressor, arm.n_joints, lim[:, 0], lim[:, 1], np.random.default_rng(0), rtol=1e-9
    )
    assert len(old.names) == 65
    assert len(arm.base.names) == 62
