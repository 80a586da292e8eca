"""The paper's view of an arm of its geometry: its base parameters as the paper's
``sigma = [J1 J2 r b1 b2 d1 d2]`` (eq. 9, :func:`paper_sigma`). Which arm has the closed forms is
decided by :func:`~adaptive_dd.plant.two_link.closed_form_view`."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.paper_geometry import paper_map
from adaptive_dd.plant.two_link import as_two_link_cached

__all__ = ["paper_sigma"]

Array = NDArray[np.float64]


def paper_sigma(arm, sigma: ArrayLike | None = None) -> Array:
    """The paper's base parameters ``[J1 J2 r b1 b2 d1 d2]`` (eq. 9) of ``arm``'s base parameters.

    A linear map ``S (7, p)``, the same for every value of the arm's parameters: the torque is
    ``Phi(q, qd, qdd) @ S @ sigma`` with ``Phi`` the closed-form regressor of eq. (8), ``S`` found once
    per arm by least squares on 40 sampled states (seed 0). On the SICE URDF's base parameters
    ``('Izz1 + 0.04*m2 + Ia1', 'mx2', 'my2', 'Izz2', 'fv1', 'fv2', 'fc1', 'fc2', 'Ia2')`` it reads
    ``J1 = Izz1 + l1^2 m2 + Ia1``, ``J2 = Izz2``, ``r = l1 mx2``, ``b = fv``, ``d = fc``. A base
    parameter the closed forms have no term for (there ``my2``, a centre of mass off the link's
    axis, and ``Ia2``, armature) maps to nothing: the map is exact where they are zero, as on every
    arm of the paper's geometry.

    Parameters
    ----------
    arm : Arm
        An arm of the paper's geometry (:func:`~adaptive_dd.plant.two_link.closed_form_view` is not
        None for it, or would not be without ``general=True``).
    sigma : array_like (..., p), optional
        Base parameters of ``arm`` (an estimate, a loaded arm's); default ``arm.sigma``.

    Returns
    -------
    ndarray (..., 7)
        On a :class:`~adaptive_dd.plant.two_link.ClosedFormTwoLink` (whose base parameters are the
        paper's) ``sigma`` itself.

    Raises
    ------
    ParameterError
        ``arm`` is not of the paper's geometry; ``sigma`` of the wrong length.
    """
    if getattr(arm, "closed_form", None) is True:
        return np.asarray(arm.sigma if sigma is None else sigma, dtype=float)
    if getattr(arm, "closed_form", None) is not False or as_two_link_cached(arm) is None:
        raise ParameterError(
            f"paper_sigma: the paper's sigma [J1 J2 r b1 b2 d1 d2] exists for an arm of its geometry "
            f"(two parallel revolute joints, centres of mass on the link axes, no armature), not "
            f"for this {getattr(arm, 'n_joints', '?')}-joint arm"
        )
    s = np.asarray(arm.sigma if sigma is None else sigma, dtype=float)
    if s.shape[-1:] != arm.sigma.shape:
        raise ParameterError(f"paper_sigma: sigma must have shape (..., {len(arm.sigma)}), got {s.shape}")
    return s @ paper_map(arm).T
