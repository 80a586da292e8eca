"""``simulate --plant-seed K``: the robot of the benchmark's seed K; ``validate``'s estimate of the
excitation phase."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.cli import main
from adaptive_dd.closed_loop.types import plant_of, plant_record, true_models

DRAWN = Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "sice_drawn.toml"


def _simulate(out: Path, *extra: str) -> int:
    argv = ["simulate", "--arm", str(DRAWN), "--experiment", "reference", "--duration", "0.02"]
    return main([*argv, "--out", str(out), *extra])


def test_plant_seed_simulates_the_benchmarks_robot_of_that_seed(tmp_path, capsys):
    sc = load_scenario(DRAWN)
    bench = true_models(plant_of(sc, [0, 3]))[:, 0]  # seeds 0 and 3's robots, no payload
    assert not np.allclose(bench[0], bench[1])  # the draws differ: the test can tell them apart
    assert _simulate(tmp_path / "k3", "--plant-seed", "3") == 0
    said = capsys.readouterr().out
    assert "seed index 3" in said and "link masses against the [plant]'s [%]" in said
    rec = np.load(tmp_path / "k3" / "trajectory.npz")
    np.testing.assert_allclose(rec["pi_true"], bench[1], rtol=1e-12, atol=1e-15)  # the robot simulated
    drawn = json.loads((tmp_path / "k3" / "plant.json").read_text())
    assert drawn["seed_index"] == 3 and drawn["drawn"] == plant_record(sc, [3])["seeds"][3]
    m, m0 = drawn["drawn"]["links"][0]["mass"], drawn["nominal"]["links"][0]["mass"]
    assert drawn["mass_relative_error"][0] == pytest.approx(m / m0 - 1.0)
    # without --plant-seed: the [plant] before any draw, as before
    assert _simulate(tmp_path / "nominal") == 0
    assert "before any draw" in capsys.readouterr().out
    exact = dataclasses.replace(sc, plant=dataclasses.replace(sc.plant, uncertainty=None))
    nominal = true_models(plant_of(exact))
    np.testing.assert_allclose(np.load(tmp_path / "nominal" / "trajectory.npz")["pi_true"], nominal[0, 0])
    assert not (tmp_path / "nominal" / "plant.json").exists()


def test_plant_seed_without_a_draw_is_refused(tmp_path, capsys):
    no_draw = tmp_path / "no_draw.toml"
    no_draw.write_text(DRAWN.read_text().split("[plant.uncertainty]")[0])
    assert main(["simulate", "--arm", str(no_draw), "--plant-seed", "1", "--out", str(tmp_path / "o")]) == 2
    assert "draws no plant (no [plant.uncertainty])" in capsys.readouterr().err
    no_plant = tmp_path / "no_plant.toml"
    no_plant.write_text(DRAWN.read_text().split("[plant")[0])
    assert main(["simulate", "--arm", str(no_plant), "--plant-seed", "1", "--out", str(tmp_path / "p")]) == 2
    assert "draws no plant (no [plant.uncertainty])" in capsys.readouterr().err
    argv = ["simulate", "--experiment", "table2", "--plant-seed", "1"]  # the SICE arm's Table 2
    assert main([*argv, "--out", str(tmp_path / "t")]) == 2
    assert "--plant-seed: options of --experiment reference" in capsys.readouterr().err


def test_the_estimate_includes_the_excitation_phase(tmp_path, capsys):
    sc = load_scenario(DRAWN)
    est = [dataclasses.replace(sc, excite=e).estimate() for e in (0.0, 10.0, 20.0)]
    assert est[0].excite_seconds == 0 and "excitation phase" not in str(est[0])
    assert 0 < est[1].excite_seconds < est[2].excite_seconds
    assert est[0].seconds < est[1].seconds < est[2].seconds
    assert est[2].seconds - est[0].seconds == pytest.approx(est[2].excite_seconds)
    more = dataclasses.replace(sc, excite=10.0, seeds=2 * sc.seeds).estimate()
    assert more.excite_seconds > est[1].excite_seconds  # an excitation and an identification per seed
    # validate says so, on a scenario with [run] excite
    excite = tmp_path / "excite.toml"
    excite.write_text(DRAWN.read_text().replace("[run]\n", "[run]\nexcite = 10.0\n", 1))
    assert main(["validate", str(excite)]) == 0
    said = capsys.readouterr().out
    assert f"excitation phase included: about {est[1].excite_seconds:.3g} s" in said, said[:400]
