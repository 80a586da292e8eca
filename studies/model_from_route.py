"""The ``[model] from = "model.json"`` route on one drawn robot, as a user would take it.

``python studies/model_from_route.py SCENARIO OUT [--seed-index I] [--excite-seconds S]``:

1. seed ``I``'s robot drawn from ``SCENARIO``'s ``[plant.uncertainty]`` written as a URDF
   (:func:`~adaptive_dd.plant.urdf_write.write_urdf_links`) and made the ``[plant]`` of
   ``OUT/plant.toml`` (the controllers' ``[arm]`` unchanged);
2. ``adaptive-dd excite --arm OUT/plant.toml`` -> ``OUT/excited.toml``;
3. ``adaptive-dd simulate --arm OUT/excited.toml --duration S --plant benchmark`` -> ``OUT/sim``;
4. ``adaptive-dd identify --arm OUT/excited.toml OUT/sim/trajectory.csv --output-error off``
   -> ``OUT/ident/model.json``;
5. ``OUT/task.toml``: ``OUT/plant.toml`` with ``[model] from = "ident/model.json"``, which
   ``adaptive-dd benchmark OUT/task.toml --controllers ct_nominal adaptive_ct`` runs.

The Kinova Gen3's figures of docs/any_arm.md ("An arm nobody tuned for") are printed this way.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path


def _without_table(text: str, name: str) -> str:
    out, skip = [], False
    for line in text.splitlines():
        head = line.strip()
        if head.startswith("["):
            skip = head == f"[{name}]"
        if not skip:
            out.append(line)
    return "\n".join(out).rstrip() + "\n"


def _cli(*args: str) -> None:
    cmd = [sys.executable, "-m", "adaptive_dd.cli", *args]
    print("$ adaptive-dd " + " ".join(args), flush=True)
    subprocess.run(cmd, check=True)


def print_errors(sc, draw, model_json) -> None:
    """The identified base parameters against the robot's, ``|x - robot| / max(|robot|, 1 % of the
    largest)`` (the excitation phase's report's measure): median and worst."""
    import json

    import numpy as np

    B = sc.arm.base.B
    robot = B @ np.concatenate([draw.pi_links, draw.viscous, draw.coulomb, draw.armature])
    scale = np.maximum(np.abs(robot), 0.01 * np.abs(robot).max())
    m = json.loads(Path(model_json).read_text())
    for label, key in (
        ("URDF", "sigma_urdf"),
        ("weighted least squares", "sigma"),
        ("consistent fit", "consistent_sigma"),
    ):
        e = np.abs(np.asarray(m[key]) - robot) / scale
        worst = sc.arm.base.names[int(e.argmax())]
        print(
            f"{label}: base parameters vs the robot's, median {100 * np.median(e):.3g} %, "
            f"worst {100 * e.max():.3g} % ({worst[:30]})"
        )


def main(argv=None) -> int:
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.plant.uncertainty import plant_draws
    from adaptive_dd.plant.urdf_write import write_urdf_links

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("out")
    ap.add_argument("--seed-index", type=int, default=0)
    ap.add_argument("--excite-seconds", type=float, default=20.0)
    args = ap.parse_args(argv)
    src, out = Path(args.scenario).resolve(), Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    sc = load_scenario(src)
    d = plant_draws(sc, (args.seed_index,))[0]
    write_urdf_links(sc.arm, d.pi_links, out / "plant_robot.urdf", f"seed {args.seed_index}'s robot of {src}")
    text = _without_table(src.read_text(), "plant.uncertainty")
    text = text.replace('urdf = "../../', f'urdf = "{src.parent.parent.parent}/')
    vec = ", ".join
    text += (
        f'\n[plant]  # seed {args.seed_index}\'s drawn robot\nurdf = "plant_robot.urdf"\n'
        f"viscous = [{vec(repr(float(x)) for x in d.viscous)}]\n"
        f"coulomb = [{vec(repr(float(x)) for x in d.coulomb)}]\n"
        f"armature = [{vec(repr(float(x)) for x in d.armature)}]\n"
    )
    text = text.replace("excite = ", "# excite = ")
    (out / "plant.toml").write_text(text)
    _cli("excite", "--arm", str(out / "plant.toml"), "--out", str(out / "excited.toml"))
    _cli(
        "simulate", "--arm", str(out / "excited.toml"), "--duration", str(args.excite_seconds),
        "--plant", "benchmark", "--out", str(out / "sim"),
    )  # fmt: skip
    _cli(
        "identify", "--arm", str(out / "excited.toml"), str(out / "sim" / "trajectory.csv"),
        "--output-error", "off", "--out", str(out / "ident"),
    )  # fmt: skip
    (out / "task.toml").write_text(text + '\n[model]\nfrom = "ident/model.json"\n')
    print_errors(sc, d, out / "ident" / "model.json")
    print(f"wrote {out / 'task.toml'}: adaptive-dd benchmark {out / 'task.toml'} --seeds 10 ...")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
