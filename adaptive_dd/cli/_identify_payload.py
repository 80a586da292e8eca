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
    ic, sd = pr.inertia_com, pr.inertia_com_std
    names = (("Ixx", 0, 0), ("Iyy", 1, 1), ("Izz", 2, 2), ("Ixy", 0, 1), ("Ixz", 0, 2), ("Iyz", 1, 2))

    def entry(i, j):
        v = f(ic[i, j], ".4g")
        if v == "-" or sd is None or not np.isfinite(sd[i, j]):
            return v
        return f"{v} +- {sd[i, j]:.2g}"

    if pr.com_defined:
        cells = ", ".join(f"{n} {entry(i, j)}" for n, i, j in names)
        print(f"  inertia about the centre of mass [kg m^2]: {cells}")
        low = [n for n, i, j in names[:3] if np.isfinite(ic[i, j]) and ic[i, j] < 0]
        if low and c is None:
            print(
                f"  {', '.join(low)} below 0: no rigid body's (noise about a small inertia); payload.json's "
                "scenario_payload holds 0 there"
            )
    else:
        print("  inertia about the centre of mass undefined (no centre of mass)")
    if c is None:  # some parameters not determined
        from adaptive_dd.identification.payload_pair import PARAM_NAMES

        gone = [n for n, ok in zip(PARAM_NAMES, pr.determined, strict=True) if not ok]
        print(
            f"  '-': not determined on this arm (its motion does not depend on the payload-frame "
            f"parameters {', '.join(gone)}, nor on what they enter); physical consistency not judged (it "
            "needs the whole body)"
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
