"""A policy from observations to torques (a learned one, or this hand-written stand-in) entered in
the benchmark's table as a plain-Python plug-in: ``"policy_plugin:LinearPolicy"`` in a scenario's
``controllers``. ``adaptive_dd.gym.evaluate`` scores the same policy on the same trials to the
same figures (``tests/test_gym.py::test_a_policy_enters_the_benchmarks_table_as_a_plugin``).

The observation is the Gymnasium environment's (``adaptive_dd.gym.env``): measured ``q, qd`` and
the reference ``q_d, qd_d, qdd_d``, ``(5 n,)``. Replace :meth:`LinearPolicy.policy` with your
trained network's forward pass (load its weights in ``__init__``)."""

import copy

import numpy as np


class PolicyPlugin:
    """Runs ``self.policy(observation) -> torques (n,)`` on each trial of the benchmark's batch."""

    name = "policy"
    floor = "ct_oracle"  # what the table divides this policy's error by (a law told the true model)

    def __init__(self, arm, gains):
        self.arm, self.gains = arm, gains

    def policy(self, obs):
        raise NotImplementedError("a subclass gives the policy")

    def reset(self, n_trials, sample_period):
        """One copy of the policy per trial of the batch, each reset as ``evaluate`` resets it before
        an episode: a policy with state (an integral, a recurrent network's memory, a sample count)
        keeps one per trial."""
        proto = copy.copy(self)
        proto.__dict__.pop("_trials", None)
        self._trials = [copy.deepcopy(proto) for _ in range(n_trials)]
        for p in self._trials:
            p.reset_policy()

    def reset_policy(self):
        """Clear the policy's state before a trial (``evaluate`` calls a policy's ``reset()``)."""

    def command(self, q, qd, q_d, qd_d, qdd_d):
        ref = np.concatenate((q_d, qd_d, qdd_d))  # the same for every trial of the batch
        return np.stack([p.policy(np.concatenate((q[i], qd[i], ref))) for i, p in enumerate(self._trials)])

    def observe(self, q, qd, tau):
        pass


class LinearPolicy(PolicyPlugin):
    """``tau = K obs``: a PD on the error, its gains through the arm's nominal inertia (what a linear
    policy trained on this arm might have found; a stand-in for yours)."""

    name = "linear_policy"

    def __init__(self, arm, gains):
        super().__init__(arm, gains)
        n = arm.n_joints
        m0 = np.asarray(arm.nominal_inertia(), dtype=float)
        kp, kd = np.diag(gains.kp * m0), np.diag(gains.kd * m0)
        self.K = np.hstack((-kp, -kd, kp, kd, np.zeros((n, n))))  # on [q, qd, q_d, qd_d, qdd_d]

    def policy(self, obs):
        return self.K @ obs
