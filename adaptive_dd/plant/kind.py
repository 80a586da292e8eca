"""Which path a run takes: the paper's closed forms, or the general kernels (issue 27: one arm type).

There is one arm type, :class:`~adaptive_dd.plant.arm.Arm`. An arm of the paper's geometry has the
closed forms of eqs. (3-9) as its fast path; whether it has them is
:func:`~adaptive_dd.plant.two_link.closed_form_view`'s alone to say (the one place that asks an
arm's class, with :func:`~adaptive_dd.plant.two_link.as_arm`, which turns a closed-form record into
its arm). A :class:`~adaptive_dd.benchmark.scenario.Scenario` holds the record it runs as
``scenario.closed_forms`` (None: the general kernels). This module names the two paths for the
tables that are keyed by them (the controller registry's ``"two_link"`` / ``"chain"``).
``tests/test_arm_kind.py`` fails when a type test on the arm's class appears anywhere else in the
package.
"""

from __future__ import annotations

from typing import Any

from adaptive_dd.errors import ParameterError

__all__ = ["arm_kind", "is_chain", "is_two_link", "require_two_link", "run_kind"]


def arm_kind(arm: Any) -> str:
    """``"two_link"`` for an arm with the paper's closed forms
    (:func:`~adaptive_dd.plant.two_link.closed_form_view` not None), else ``"chain"``: the general
    kernels (:mod:`adaptive_dd.closed_loop`).

    Raises
    ------
    ParameterError
        ``arm`` is not an arm (no ``n_joints``).
    """
    from adaptive_dd.plant.two_link import closed_form_view

    if not hasattr(arm, "n_joints"):
        raise ParameterError(f"expected an arm (adaptive_dd.plant.Arm), got {type(arm).__name__}")
    return "chain" if closed_form_view(arm) is None else "two_link"


def is_two_link(arm: Any) -> bool:
    """True for an arm with the paper's closed forms (:func:`~adaptive_dd.plant.two_link.closed_form_view`
    not None: ``Arm.sice()``, a URDF of the paper's geometry, a closed-form record). Kept for callers
    of an earlier round; the package asks :func:`arm_kind` or a scenario's ``closed_forms``."""
    from adaptive_dd.plant.two_link import closed_form_view

    return closed_form_view(arm) is not None


def is_chain(arm: Any) -> bool:
    """True for an arm that runs the general kernels (:func:`~adaptive_dd.plant.two_link.closed_form_view`
    None); False for one with the closed forms and for ``None``. Kept for callers of an earlier round."""
    return arm is not None and hasattr(arm, "n_joints") and not is_two_link(arm)


def run_kind(scenario: Any) -> str:
    """``"two_link"`` when ``scenario`` runs the paper's closed forms (``scenario.closed_forms``),
    else ``"chain"`` (an arm of another geometry, ``general = true``, or a plant apart from the arm)."""
    return "chain" if scenario.closed_forms is None else "two_link"


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
    if hasattr(arm, "general") and hasattr(arm, "n_joints"):
        return f"{'the general kernels of ' if arm.general else ''}a {arm.n_joints}-joint Arm"
    return type(arm).__name__
