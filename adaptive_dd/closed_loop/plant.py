"""The plant step the closed loop calls: one trial, one sample, zero-order hold, in place.

:func:`adaptive_dd.plant.integrator.plant_step` (RK4 substeps; stick-slip, tanh or Stribeck
friction; LuGre's implicit micro-steps on trial i's bristles) on trial i's plant (its link
parameters in the current payload segment, its friction).
"""

from __future__ import annotations

from numba import njit

from adaptive_dd.plant.integrator import PlantParams, plant_scratch, plant_step_in, trial_law

__all__ = ["plant_scratch", "plant_step"]


@njit(cache=True, inline="always")
def plant_step(pl, i, seg, q, qd, tau, T, stuck, sc):  # pragma: no cover - compiled
    """Advance trial i's ``q, qd (n,)`` over one sample under ``tau (n,)`` in segment ``seg``.

    ``pl`` is the run's :class:`~adaptive_dd.closed_loop.types.Plant` (its ``chain`` the arm's
    kinematics); ``stuck (n,)`` receives the joints held by Coulomb friction; ``sc`` is the
    trial's scratch (:func:`plant_scratch`, allocated once). Returns False if the dynamics failed
    (a mass matrix not positive definite, a non-finite state); the loop's runaway rule catches
    the state.
    """
    law = trial_law(pl.friction_law, i)
    pp = PlantParams(pl.pi_seg[i, seg], pl.fv[i], pl.fc[i], pl.armature[i], law, pl.fparams)
    return plant_step_in(pl.chain, pp, q, qd, tau, T, pl.substeps, stuck, sc)
