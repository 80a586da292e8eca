"""Which path an arm runs on: the one place the package asks (the arm says it: ``closed_form``).

Two arm types exist (issue 27 merges them step by step):

- :class:`~adaptive_dd.plant.two_link.ClosedFormTwoLink`, the paper's arm with its closed forms
  (eqs. 3-9): the benchmark's two-link loop (:mod:`adaptive_dd.benchmark`), the two-link
  controllers (:mod:`adaptive_dd.controllers`), the paper's estimator of sigma (seven base
  parameters, :mod:`adaptive_dd.identification.two_link_online`).
- :class:`~adaptive_dd.plant.arm.Arm`, any serial arm (a URDF, or ``Arm.sice()``): the N-joint
  loop (:mod:`adaptive_dd.closed_loop`), the payload estimator
  (:mod:`adaptive_dd.identification.online`).

Each class states its kind as the class attribute ``closed_form`` (True on ``ClosedFormTwoLink``); every
module that chooses between the two paths asks here (``is_two_link`` / ``is_chain``).
Whether an :class:`Arm` has the closed forms at all is
:func:`adaptive_dd.plant.two_link.closed_form_view`'s to say (the paper's geometry; a
:class:`~adaptive_dd.benchmark.scenario.Scenario` takes them automatically, and
:func:`require_two_link` returns them for an entry point that needs them).
``tests/test_arm_kind.py`` fails when a type test on the arm's class appears anywhere in the
package (the classes' own ``__eq__`` aside); the command line asks here too (through
``adaptive_dd.cli._common``, which imports :func:`is_two_link`).
"""

from __future__ import annotations

from typing import Any

from adaptive_dd.errors import ParameterError

__all__ = ["arm_kind", "is_chain", "is_two_link", "require_two_link"]


def is_two_link(arm: Any) -> bool:
    """True for the paper's closed-form arm (:class:`~adaptive_dd.plant.two_link.ClosedFormTwoLink`,
    ``closed_form`` True): it runs on the two-link path. False for an
    :class:`~adaptive_dd.plant.arm.Arm` and for anything that is not an arm."""
    return getattr(arm, "closed_form", None) is True


def is_chain(arm: Any) -> bool:
    """True for any serial arm as an :class:`~adaptive_dd.plant.arm.Arm` (``closed_form`` False: a
    URDF, or ``Arm.sice()``): it runs on the N-joint path (:mod:`adaptive_dd.closed_loop`). False for
    the two-link closed-form arm and for anything that is not an arm (``None``)."""
    return getattr(arm, "closed_form", None) is False


def arm_kind(arm: Any) -> str:
    """``"two_link"`` or ``"chain"`` (the path :func:`is_two_link` / :func:`is_chain` choose).

    Raises
    ------
    ParameterError
        ``arm`` is neither.
    """
    if is_two_link(arm):
        return "two_link"
    if is_chain(arm):
        return "chain"
    raise ParameterError(f"expected an arm (Arm or ClosedFormTwoLink), got {type(arm).__name__}")


def require_two_link(arm: Any, what: str):
    """The closed forms' record of ``arm`` (:func:`~adaptive_dd.plant.two_link.closed_form_view`: an
    :class:`~adaptive_dd.plant.arm.Arm` of the paper's geometry, or the record itself); a
    :class:`ParameterError` naming ``what`` when the arm has none."""
    from adaptive_dd.plant.two_link import closed_form_view

    view = closed_form_view(arm)
    if view is None:
        raise ParameterError(
            f"{what}: needs an arm of the paper's two-link geometry (Arm.sice(), or a URDF like it), got "
            f"{_describe(arm)}; any other arm runs on the N-joint path (adaptive_dd.closed_loop)"
        )
    return view


def _describe(arm: Any) -> str:
    if is_chain(arm):
        return f"{'the general kernels of ' if arm.general else ''}a {arm.n_joints}-joint Arm"
    return type(arm).__name__
