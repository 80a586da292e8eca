"""A row back in use after a slow phase restarts its detector averages
(``online_kernel._back_in_use``; ``docs/change_detection.md``, "Back in use").

A row's short and fast averages stop while its joint is slow (out of the data selection). A row
out of use since before an alarm therefore held the errors of the swap that raised the alarm, and
came back into use with them, judged against the level kept from before the alarm: random:81 of
the population alarmed again 0.35 s after its put-down's alarm, in every seed. Back in use, the
averages restart at the level the row is judged against.
"""

import numpy as np
import pytest

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import OnlineConfig, est_init
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def test_a_row_without_a_level_since_the_alarm_restarts_at_the_level_kept(ur5):
    """No level learnt since the last alarm: the short and fast averages (random:81's were 21
    against a kept level of 0.23) restart at the kept level, its posture noise at the kept
    level's; the estimate's uncertainty averages at 0."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    j = 4
    s.learned[0, j] = 0
    s.ref[0, j], s.nref[0, j] = 0.232, 0.05
    s.short[0, j], s.fast[0, j], s.nshort[0, j] = 20.98, 98.5, 0.4
    s.pshort[0, j], s.pfast[0, j] = 0.3, 0.2
    K._back_in_use(c, s, 0, j)
    assert s.short[0, j] == s.fast[0, j] == 0.232
    assert s.nshort[0, j] == 0.05
    assert s.pshort[0, j] == s.pfast[0, j] == 0.0
    others = [k for k in range(ur5.n_joints) if k != j]
    assert np.all(s.short[0, others] == 0.0)  # only the row that came back


def test_a_row_with_a_level_restarts_at_its_mean(ur5):
    """A level learnt over ``nl`` samples: the averages restart at its bias-corrected mean."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    j, nl = 1, 40
    s.learned[0, j] = nl
    s.long[0, j], s.nlong[0, j] = 0.02, 0.004
    s.ref[0, j] = 5.0  # not used: the row has its own level
    s.short[0, j] = s.fast[0, j] = 30.0
    K._back_in_use(c, s, 0, j)
    den = 1.0 - (1.0 - c.alpha_long) ** nl
    assert s.short[0, j] == pytest.approx(0.02 / den)
    assert s.fast[0, j] == s.short[0, j]
    assert s.nshort[0, j] == pytest.approx(0.004 / den)
