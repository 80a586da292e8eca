"""What ``adaptive-dd identify`` prints and writes of an identified payload (``--payload-only``,
``--baseline``)."""

from __future__ import annotations

import numpy as np


def _print_payload(label: str, pr) -> None:
    c = pr.consistent

    def f(x, fmt):  # a parameter the arm does not determine: "-"
        return format(x, fmt) if np.isfinite(x) else "-"

    com = (  # a massless body has none
        f"centre of mass [{', '.join(f(x * 1e3, '.2f') for x in pr.com)}] +- "
        f"[{', '.join(f(x * 1e3, '.2g') for x in pr.com_std)}] mm in the payload frame"
        if pr.com_defined
        else "centre of mass undefined (the payload fitted has no mass: none seen, or one too light for "
        "these records to tell from none)"
    )
    print(f"{label} [+- 1 std]: mass {pr.mass:.5g} +- {pr.mass_std:.2g} kg; {com}")
    ic = pr.inertia_com
    print(
        f"  inertia about the centre of mass [kg m^2]: Ixx {f(ic[0, 0], '.4g')}, Iyy {f(ic[1, 1], '.4g')}, "
        f"Izz {f(ic[2, 2], '.4g')}, Ixy {f(ic[0, 1], '.3g')}, Ixz {f(ic[0, 2], '.3g')}, "
        f"Iyz {f(ic[1, 2], '.3g')}"
    )
    if c is None:  # some parameters not determined
        from adaptive_dd.identification.payload_pair import PARAM_NAMES

        gone = [n for n, ok in zip(PARAM_NAMES, pr.determined, strict=True) if not ok]
        print(
            f"  '-': not determined on this arm (its motion does not depend on {', '.join(gone)}); "
            "physical consistency not judged (it needs the whole body)"
        )
    elif c.was_physical:
        print(f"  physically consistent as estimated (pseudo-inertia min eigenvalue {c.min_eigenvalue:.3g})")
    else:
        print(
            "  the unconstrained estimate is not a rigid body (pseudo-inertia eigenvalue "
            f"{c.min_eigenvalue:.3g}); "
            f"constrained fit {c.distance:.2f} std away: values above are the constrained ones"
        )


def _write_payload(outputs, pr, source: str):
    """``payload.json`` (:func:`~adaptive_dd.identification.payload_pair.payload_record`); its path."""
    import json

    from adaptive_dd.identification.payload_pair import payload_record

    path = outputs.path("payload.json")
    with open(path, "w") as f:
        json.dump(payload_record(pr, source), f, indent=1)
    return path
