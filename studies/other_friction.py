"""adaptive_ct on plants whose friction its model does not have: the N-joint scenario (default
the UR5 tool swap) with the plant's friction law replaced (stick-slip as shipped, ``tanh``,
``stribeck``), the estimator and controllers unchanged (their model keeps viscous + Coulomb
``sgn``). Per segment adaptive_ct / ct_oracle per seed (mean / p90 / max), trials with a false
alarm, swaps missed. The same seeds for every law.

    python studies/other_friction.py [SCENARIO.toml] [--seeds 50] [--set KEY=VALUE ...]
        [--adaptive KEY=VALUE ...] [--laws stick-slip tanh stribeck tanh@0.1]

``--set`` goes to the estimator's table, ``--adaptive`` to ``[controllers.adaptive_ct]`` itself
(e.g. ``--adaptive 'observer_momentum_test = true'``).

``LAW@V`` also sets the plant's ``friction_velocity`` V [rad/s] (tanh: how soft the friction is);
``stribeck@VSxK`` its Stribeck velocity VS [rad/s] and static / Coulomb ratio K (default 0.1, 1.5).
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

from _ablation import UR5, ablation_row

from adaptive_dd.benchmark.scenario import read_toml


def _plant(law: str) -> dict:
    """``LAW``, ``LAW@V`` or ``stribeck@VSxK`` as a ``[plant]`` table."""
    name, _, arg = law.partition("@")
    if not arg:
        return {"friction": name}
    if name == "stribeck":
        vs, _, k = arg.partition("x")
        return {"friction": name, "stribeck_velocity": float(vs)} | (
            {"stribeck_ratio": float(k)} if k else {}
        )
    return {"friction": name, "friction_velocity": float(arg)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario", nargs="?", default=str(UR5))
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--laws", nargs="+", default=["stick-slip", "tanh", "stribeck", "tanh@0.1"])
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--adaptive", action="append", default=[], metavar="KEY=VALUE")
    a = ap.parse_args()
    extra = tomllib.loads("\n".join(a.set))
    own = tomllib.loads("\n".join(a.adaptive))
    base = read_toml(Path(a.scenario))
    print(
        f"{a.scenario}: adaptive_ct / ct_oracle, {a.seeds} seeds, plant friction law replaced, "
        f"estimator settings {extra or 'as shipped'}, adaptive_ct's {own or 'as shipped'}"
    )
    head = "plant friction  per segment: mean / p90 / max"
    print(f"{head}{' ' * 24}trials with a false alarm, swaps missed")
    for law in a.laws:
        plant = _plant(law)
        row = ablation_row(base, a.scenario, a.seeds, extra, plant=plant, controller=own)
        print(f"{law:14s}  {row}", flush=True)


if __name__ == "__main__":
    main()
