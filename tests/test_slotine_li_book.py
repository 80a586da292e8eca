"""Slotine and Li's adaptive two-link example (*Applied Nonlinear Control*, 1991, ch. 9,
Example 9.2) reproduced in kind with the project's ``slotine_li`` law kernel.

The book's arm is horizontal: link 1 (m1 = 1 kg, l1 = 1 m, lc1 = 0.5 m, I1 = 0.12 kg m^2) and an
"equivalent load" link 2 (me = 2 kg, lce = 0.6 m at delta_e = 30 deg, Ie = 0.25 kg m^2), with
``H11 = a1 + 2 a3 cos q2 + 2 a4 sin q2``, ``H12 = a2 + a3 cos q2 + a4 sin q2``, ``H22 = a2``,
``h = a3 sin q2 - a4 cos q2`` and the gains ``K_D = 100 I``, ``Lambda = 20 I``,
``Gamma = diag(0.03, 0.05, 0.1, 0.3)`` on ``a = (a1, a2, a3, a4)`` from ``a_hat = 0``, and
``q_d = (30 deg, 45 deg) (1 - cos 2 pi t)`` (checked against public reproductions of the example).
The book prints figures, not tables: the tracking errors fall within the first second and stay
small, the estimates stay bounded without converging to the true values.

In kind here: link 1 is the URDF's (known), link 2 is the payload the law adapts (its ten
parameters about joint 2's frame from zero, the book's Gamma on the parameter nearest each of
the book's: ``m`` <-> a1 (``me l1^2``), ``Izz`` <-> a2, ``m c_x`` <-> a3, ``m c_y`` <-> a4); the
feedback is the book's ``K_D s`` (``feedback_inertia = False``), the plant the book's closed form
integrated by RK4 (one step per sample) under a zero-order hold at 1 kHz.
"""

from __future__ import annotations

import numpy as np
import pytest

from adaptive_dd.closed_loop.controllers import SlotineLi
from adaptive_dd.closed_loop.laws import LawState, law_batch
from adaptive_dd.plant.arm import Arm

M1, L1, ME, DELTA, I1, LC1, IE, LCE = 1.0, 1.0, 2.0, np.pi / 6, 0.12, 0.5, 0.25, 0.6
A = np.array(
    [
        I1 + M1 * LC1**2 + IE + ME * LCE**2 + ME * L1**2,
        IE + ME * LCE**2,
        ME * L1 * LCE * np.cos(DELTA),
        ME * L1 * LCE * np.sin(DELTA),
    ]
)
BOOK_GAMMA = (0.03, 0.05, 0.1, 0.3)
KD, LAM, T = 100.0, 20.0, 1e-3

URDF = """<robot name="slotine_li_two_link">
  <link name="base"/>
  <link name="link1"><inertial><origin xyz="{lc1} 0 0"/><mass value="{m1}"/>
    <inertia ixx="{i1}" iyy="{i1}" izz="{i1}" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="link2"><inertial><mass value="1e-4"/>
    <inertia ixx="1e-8" iyy="1e-8" izz="1e-8" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="load"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/><axis xyz="0 0 1"/>
    <limit effort="1000" velocity="20" lower="-6" upper="6"/></joint>
  <joint name="q2" type="revolute"><parent link="link1"/><child link="link2"/><origin xyz="{l1} 0 0"/>
    <axis xyz="0 0 1"/><limit effort="1000" velocity="20" lower="-6" upper="6"/></joint>
  <joint name="frame" type="fixed"><parent link="link2"/><child link="load"/></joint>
</robot>
"""


def book_h(q2):
    """The book's inertia matrix H(q) (2, 2)."""
    a1, a2, a3, a4 = A
    c, s = np.cos(q2), np.sin(q2)
    h12 = a2 + a3 * c + a4 * s
    return np.array([[a1 + 2 * a3 * c + 2 * a4 * s, h12], [h12, a2]])


def book_qdd(q, qd, tau):
    """``H(q) qdd + C(q, qd) qd = tau`` of the book (horizontal: no gravity)."""
    a3, a4 = A[2], A[3]
    h = a3 * np.sin(q[1]) - a4 * np.cos(q[1])
    c = np.array([[-h * qd[1], -h * (qd[0] + qd[1])], [h * qd[0], 0.0]])
    (h11, h12), (_, h22) = book_h(q[1])
    r = tau - c @ qd
    det = h11 * h22 - h12 * h12
    return np.array([h22 * r[0] - h12 * r[1], h11 * r[1] - h12 * r[0]]) / det


def reference(t):
    amp = np.radians([30.0, 45.0])
    w = 2 * np.pi
    return amp * (1 - np.cos(w * t)), amp * w * np.sin(w * t), amp * w * w * np.cos(w * t)


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    p = tmp_path_factory.mktemp("book") / "two_link.urdf"
    p.write_text(URDF.format(lc1=LC1, m1=M1, i1=I1, l1=L1))
    zero = [0.0, 0.0]
    return Arm.from_urdf(p, "load", gravity=(0.0, 0.0, -9.81), viscous=zero, coulomb=zero, armature=zero)


def _payload_gamma() -> np.ndarray:
    """The book's Gamma on the payload parameter nearest each of the book's ``a`` (module docstring);
    the parameters a planar arm does not excite (``m c_z`` and the inertia but ``Izz``) at the
    smallest of them."""
    g = np.full(10, min(BOOK_GAMMA))
    g[0], g[9], g[1], g[2] = BOOK_GAMMA  # m, Izz, m c_x, m c_y
    return g


def run_book(arm, duration=6.0, sign=1.0, adapt=True):
    """The example: errors ``(K, 2)`` [rad], estimates ``(K, 10)``, torques ``(K, 2)`` [N m]."""
    law = SlotineLi(arm, max_mass=20.0, com_radius=2.0, gamma=_payload_gamma().tolist())
    cfg = law.law_config(T)._replace(
        lam=np.full(2, LAM), kd=np.full(2, KD), feedback_inertia=False, gamma=sign * _payload_gamma(),
        adapt=adapt,
    )  # fmt: skip
    st = LawState.start(cfg, 1)
    q, qd = np.zeros(2), np.zeros(2)
    n = round(duration / T)
    err, est, taus = np.empty((n, 2)), np.empty((n, 10)), np.empty((n, 2))
    for k in range(n):
        qd_ref = reference(k * T)
        tau = law_batch(law.ch, cfg, st, q[None], qd[None], *qd_ref)[0]
        err[k], est[k], taus[k] = qd_ref[0] - q, st.theta[0], tau
        h = T  # one RK4 step per sample, the torque held (the fastest pole, K_D / a2, ~100 rad/s)
        k1 = qd, book_qdd(q, qd, tau)
        k2 = qd + h / 2 * k1[1], book_qdd(q + h / 2 * k1[0], qd + h / 2 * k1[1], tau)
        k3 = qd + h / 2 * k2[1], book_qdd(q + h / 2 * k2[0], qd + h / 2 * k2[1], tau)
        k4 = qd + h * k3[1], book_qdd(q + h * k3[0], qd + h * k3[1], tau)
        q = q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        qd = qd + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    return err, est, taus


def converges(err, est) -> bool:
    """The book's figures in numbers, over six periods of the reference: the error norm's RMS over
    the last second at most a quarter of the first second's, each joint's lower than in the first
    second, within 0.01 rad; the estimates finite and within five times the largest true parameter
    (bounded, not necessarily converged)."""
    first, last = err[:1000], err[-1000:]
    rms = lambda x: np.sqrt(np.mean(x**2, axis=0))  # noqa: E731
    norm = lambda x: np.sqrt(np.mean(np.sum(x**2, axis=1)))  # noqa: E731
    falls = norm(last) < 0.25 * norm(first) and np.all(rms(last) < rms(first))
    bounded = np.all(np.isfinite(est)) and np.max(np.abs(est)) < 5 * np.max(A)
    return bool(falls and np.max(np.abs(last)) < 0.01 and bounded)


def test_the_urdf_is_the_books_arm(arm, rng):
    """The URDF with the book's load on link 2 has the book's H(q) (an identity, before any control)."""
    from adaptive_dd.plant.payload import payload_parameters

    c = LCE * np.array([np.cos(DELTA), -np.sin(DELTA), 0.0])  # a4 = me l1 lce sin(delta): below the axis
    pp = payload_parameters(ME, c, np.diag([IE, IE, IE]))
    for q2 in rng.uniform(-3, 3, 5):
        q = np.array([0.3, q2])
        pi = arm.pi.copy()
        pi[10:20] += arm.payload_map @ pp
        np.testing.assert_allclose(arm.mass_matrix(q, arm.base.B @ pi), book_h(q2), atol=2e-4)


def test_slotine_li_tracks_the_books_example_with_bounded_estimates(arm):
    err, est, taus = run_book(arm)
    assert converges(err, est), (np.abs(err[-1000:]).max(), np.abs(est).max())
    # adaptation, not the feedback alone: the same law without it tracks worse in the last second
    err0, _, _ = run_book(arm, adapt=False)
    assert np.sqrt(np.mean(err[-1000:] ** 2)) < 0.3 * np.sqrt(np.mean(err0[-1000:] ** 2))
    assert np.all(np.isfinite(taus)) and np.abs(taus).max() < 500.0


def test_a_sign_error_in_the_adaptation_law_fails_the_check(arm):
    """The check above catches a wrong law: the adaptation's sign flipped, it no longer holds."""
    err, est, _ = run_book(arm, sign=-1.0)
    assert not converges(err, est)
