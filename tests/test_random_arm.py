"""Drawn arms (adaptive_dd.robots.random_arm), ``robot = "random:SEED"`` in a scenario, and the
population's report (adaptive_dd.benchmark.population) on known numbers."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from adaptive_dd.benchmark.population import PopulationResult, format_population, pooled, population_scenario
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.errors import ParameterError, ScenarioError
from adaptive_dd.robots import random_arm

ROOT = Path(__file__).resolve().parent.parent
TEMPLATE = ROOT / "benchmarks" / "scenarios" / "population.toml"
SEEDS = range(12)


def _links(text: str) -> list[tuple[float, np.ndarray]]:
    """(mass, inertia) of every link with an <inertial>, read from the XML (not through the package)."""
    out = []
    for link in ET.fromstring(text).findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        m = float(inertial.find("mass").get("value"))
        e = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
        inertia = np.array(
            [[e["ixx"], e["ixy"], e["ixz"]], [e["ixy"], e["iyy"], e["iyz"]], [e["ixz"], e["iyz"], e["izz"]]]
        )
        out.append((m, inertia))
    return out


def test_same_seed_same_arm_and_seeds_differ():
    from adaptive_dd.robots.random_arm import _draw

    a = random_arm(4)
    _draw.cache_clear()  # drawn again, not read from the cache
    b = random_arm(4)
    assert a is not b
    assert a.urdf == b.urdf and a.reference == b.reference and a.task_torque == b.task_torque
    assert len({random_arm(s).urdf for s in range(6)}) == 6


@pytest.mark.parametrize("joints", [3, 4, 5, 6, 7])
def test_joint_count_as_asked(joints):
    arm = random_arm(11, joints=joints)
    assert arm.n_joints == joints
    kinds = [j.get("type") for j in ET.fromstring(arm.urdf).findall("joint")]
    assert kinds.count("revolute") == joints and kinds.count("fixed") == 1


@pytest.mark.parametrize("bad", [-1, 1.5, "3", True])
def test_bad_seed_is_an_error(bad):
    with pytest.raises(ParameterError, match="seed"):
        random_arm(bad)


@pytest.mark.parametrize("bad", [2, 8, 4.0])
def test_bad_joint_count_is_an_error(bad):
    with pytest.raises(ParameterError, match="joints"):
        random_arm(0, joints=bad)


def test_drawn_joint_counts_cover_three_to_seven():
    assert {random_arm(s).n_joints for s in range(40)} == {3, 4, 5, 6, 7}


@pytest.mark.parametrize("seed", SEEDS)
def test_links_are_rigid_bodies(seed):
    """Every link: mass > 0, inertia positive definite and within the triangle inequality."""
    links = _links(random_arm(seed).urdf)
    assert len(links) == random_arm(seed).n_joints
    for m, inertia in links:
        assert m > 0
        np.testing.assert_allclose(inertia, inertia.T)
        a, b, c = np.linalg.eigvalsh(inertia)
        assert a > 0
        assert c <= a + b + 1e-12


@pytest.mark.parametrize("seed", SEEDS)
def test_reference_within_limits_and_torque_within_effort(seed):
    """The reference stays inside the position and velocity limits, and inverse dynamics along it
    with the rated payload at the flange (Pinocchio, the URDF read back) within the effort limits."""
    import pinocchio as pin

    arm = random_arm(seed)
    model = pin.buildModelFromXML(arm.urdf)
    frame = model.frames[model.getFrameId("tool")]
    load = pin.Inertia(arm.payload_capacity, np.array([0.0, 0.0, 0.05]), np.eye(3) * 1e-3)
    model.inertias[frame.parentJoint] += frame.placement.act(load)
    data = model.createData()
    rows = [arm.reference[f"joint{j + 1}"] for j in range(arm.n_joints)]
    off = np.array([r["offset"] for r in rows])
    amp, ph = np.array([r["amplitude"] for r in rows]), np.array([r["phase"] for r in rows])
    w = 2 * np.pi * np.array([r["frequency"] for r in rows])
    for t in np.linspace(0.0, 30.0, 301):
        s, c = np.sin(w * t + ph), np.cos(w * t + ph)
        q, v, a = off + (amp * s).sum(1), (amp * w * c).sum(1), -(amp * w**2 * s).sum(1)
        assert np.all(q > model.lowerPositionLimit) and np.all(q < model.upperPositionLimit)
        assert np.all(np.abs(v) < model.velocityLimit)
        tau = pin.rnea(model, data, q, v, a) + np.asarray(arm.armature) * a
        tau += model.damping * v + model.friction * np.sign(v)
        assert np.all(np.abs(tau) < model.effortLimit / 1.5)
    assert 0 < arm.payload_capacity < sum(m for m, _ in _links(arm.urdf))


def _scenario(robot, **extra) -> dict:
    return {
        "arm": {"robot": robot, **extra},
        "run": {"duration": 3.0, "seeds": 1, "controllers": ["ct_oracle", "adaptive_ct"]},
        "payload": [{"at": 1.0, "mass": 0.5}],
    }


def test_scenario_robot_random_brings_capacity_armature_reference():
    sc = parse_scenario(_scenario("random:5"), "mem.toml")
    drawn = random_arm(5)
    assert sc.n_joints == drawn.n_joints
    assert sc.arm.payload_capacity == drawn.payload_capacity
    np.testing.assert_allclose(sc.arm.armature, drawn.armature)
    assert sc.reference.offset == tuple(
        drawn.reference[f"joint{j + 1}"]["offset"] for j in range(sc.n_joints)
    )
    # what the file states wins
    sc = parse_scenario(_scenario("random:5", payload_capacity=9.0), "mem.toml")
    assert sc.arm.payload_capacity == 9.0


@pytest.mark.parametrize("robot", ["random:x", "random:-1", "random:", "random:1e3"])
def test_scenario_bad_random_seed_names_key_and_value(robot):
    with pytest.raises(ScenarioError, match=r"mem\.toml: key 'arm\.robot'.*" + robot):
        parse_scenario(_scenario(robot), "mem.toml")


def test_unknown_robot_mentions_random():
    with pytest.raises(ScenarioError, match="random:SEED"):
        parse_scenario(_scenario("ur6"), "mem.toml")


def test_population_masses_are_shares_of_each_capacity():
    data = read_toml(TEMPLATE)
    shares = [p["mass"] for p in data["payload"]]
    for seed in (0, 3):
        sc = population_scenario(data, str(TEMPLATE), seed)
        cap = random_arm(seed).payload_capacity
        np.testing.assert_allclose(sc.swap_masses, np.array(shares) * cap, rtol=1e-6)
        assert sc.n_joints == random_arm(seed).n_joints
    data["arm"]["payload_capacity"] = 2.0  # the template's masses read against 2 kg
    sc = population_scenario(data, str(TEMPLATE), 3)
    np.testing.assert_allclose(
        sc.swap_masses, np.array(shares) / 2 * random_arm(3).payload_capacity, rtol=1e-6
    )


def test_population_drawn_swaps_in_order_and_seeded():
    data = read_toml(TEMPLATE)
    a = population_scenario(data, str(TEMPLATE), 2, draw_swaps=True).swap_times
    assert a == population_scenario(data, str(TEMPLATE), 2, draw_swaps=True).swap_times
    assert list(a) == sorted(a) and a != (4.0, 8.0, 12.0)


def test_population_refuses_a_two_link_template():
    with pytest.raises(ScenarioError, match="two-link"):
        population_scenario({"arm": {"l1": 0.2}, "payload": [{"at": 1.0, "mass": 1.0}]}, "t.toml", 0)


def _fake_population() -> PopulationResult:
    """Two arms x two seeds x two segments with known ratios."""
    arms = []
    rows = []
    ratios = {(7, 0): [1.0, 1.2], (7, 1): [1.1, 3.5], (9, 0): [0.9, 1.0], (9, 1): [1.05, 1.1]}
    for arm_seed in (7, 9):
        segs = [
            {"start": 0.0, "end": 2.0, "mass": 0.0, "floor_saturated": False},
            {"start": 2.0, "end": 4.0, "mass": 1.0, "floor_saturated": False},
        ]
        for i, s in enumerate(segs):
            r = ratios[(arm_seed, i)]
            s.update(mean=float(np.mean(r)), p90=float(np.quantile(r, 0.9)), max=float(max(r)))
            for seed, x in enumerate(r):
                for ctrl in ("adaptive_ct", "ct_oracle"):
                    rows.append(
                        {
                            "arm_seed": arm_seed,
                            "controller": ctrl,
                            "seed": seed,
                            "segment": i,
                            "mass_kg": s["mass"],
                            "ratio_to_floor": x if ctrl == "adaptive_ct" else np.nan,
                        }
                    )
        arms.append(
            {
                "arm_seed": arm_seed,
                "floor": "ct_oracle",
                "joints": 4,
                "kind": "palletizer",
                "capacity_kg": 2.0,
                "segments": segs,
                "false_alarm_trials": 1 if arm_seed == 9 else 0,
                "trials": 2,
                "missed_swaps": 0,
                "swaps": 2,
            }
        )
    return PopulationResult(arms, pd.DataFrame(rows))


def test_pooled_figures_and_worst_arm():
    pop = _fake_population()
    p = pooled(pop)
    assert [x["n"] for x in p] == [4, 4]
    np.testing.assert_allclose(p[0]["mean"], np.mean([1.0, 1.2, 0.9, 1.0]))
    np.testing.assert_allclose(p[1]["p90"], np.quantile([1.1, 3.5, 1.05, 1.1], 0.9))
    assert p[1]["max"] == 3.5 and p[1]["worst"] == (7, 1)
    np.testing.assert_allclose(p[1]["capacity_share"], 0.5)
    text = format_population(pop)
    assert "segment 1 (0.50 x capacity), 4 trials" in text and "NOT met" in text
    assert "trials with a false alarm: 1 of 4 (25.0 %)" in text
    assert text.split("worst arms: ")[1].startswith("random:7")
    assert "note:" not in text
    pop.floor_caveat = "the plant's friction law (lugre) is not the controllers' model's"
    assert "  note: the plant's friction law (lugre)" in format_population(pop)


def test_pooled_leaves_out_saturated_floor_segments():
    pop = _fake_population()
    pop.arms[0]["segments"][1]["floor_saturated"] = True
    p = pooled(pop)
    assert p[1]["n"] == 2 and p[1]["max"] == 1.1
    assert "1 arm segment(s) where ct_oracle saturates" in format_population(pop)


def test_population_header_names_the_floor_the_scenario_set():
    pop = _fake_population()
    for a in pop.arms:
        a["floor"] = "pd"
    text = format_population(pop)
    assert text.startswith("adaptive_ct / pd per seed") and "ct_oracle" not in text


def test_cli_arms_usage_errors(capsys):
    from adaptive_dd.cli import main

    assert main(["benchmark", "--arms", "2"]) == 2  # no template
    assert "--arms needs a template scenario FILE" in capsys.readouterr().err
    assert main(["benchmark", "--draw-swaps"]) == 2
    assert "give --arms N too" in capsys.readouterr().err
    assert main(["benchmark", "--first-arm", "5"]) == 2  # an option of the drawn arms, not ignored
    assert "--first-arm: applies to the drawn arms of --arms N" in capsys.readouterr().err
    pop = ROOT / "benchmarks" / "scenarios" / "population.toml"
    for opt in (["--template", str(pop)], ["--first-arm", "3"]):
        assert main(["leaderboard", *opt]) == 2
        assert f"{opt[0]}: applies to the drawn arms of --arms N" in capsys.readouterr().err
    two_link = ROOT / "benchmarks" / "scenarios" / "other_arm.toml"
    assert main(["benchmark", str(two_link), "--arms", "2"]) == 2
    assert "two-link" in capsys.readouterr().err


def test_cli_arms_reports_every_law_against_its_floor(capsys, tmp_path):
    """``--arms`` ran every listed law but reported adaptive_ct alone (a template without it was
    refused): a researcher's own law got no answer on the population. Each law measured against a
    floor now has its per-arm rows in arms.csv and its pooled line; the per-arm table is the first
    law's when adaptive_ct does not run."""
    import json

    import pandas as pd

    from adaptive_dd.cli import main

    text = (ROOT / "benchmarks" / "scenarios" / "population.toml").read_text()
    text = text.replace(
        'controllers = ["ct_oracle", "adaptive_ct"]', 'controllers = ["pd_gravity", "slotine_li"]'
    )
    text = text.replace("duration = 16.0", "duration = 1.5")
    for old, at in (("at = 4.0", "at = 0.5"), ("at = 8.0", "at = 1.0"), ("at = 12.0", "at = 1.25")):
        text = text.replace(old, at)
    pop = tmp_path / "pop.toml"
    pop.write_text(text)
    out = tmp_path / "out"
    argv = ["benchmark", str(pop), "--arms", "2", "--seeds", "1", "--out", str(out), "--no-progress"]
    assert main([*argv, "--figure-formats", "png", "svg", "--seed", "5"]) == 0
    printed = capsys.readouterr()
    assert "pd_gravity_oracle added (the floor of pd_gravity" in printed.err
    assert printed.out.startswith("pd_gravity / pd_gravity_oracle per seed, per arm")
    assert "target" not in printed.out.split("every law")[0]  # adaptive_ct's targets are not pd_gravity's
    every = printed.out.split("every law against its floor, pooled over 2 arms")[1].splitlines()
    assert every[1].startswith("  pd_gravity / pd_gravity_oracle: mean ")
    assert every[2].startswith("  slotine_li / slotine_li_oracle: mean ")
    frame = pd.read_csv(out / "per_seed.csv")
    for law in ("pd_gravity", "slotine_li"):
        rows = frame[frame["controller"] == law]
        mean = rows.groupby("segment")["ratio_to_floor"].mean().round(3).tolist()
        line = next(x for x in every if x.startswith(f"  {law} /"))
        assert line.split("mean ")[1].split(";")[0] == " / ".join(f"{m:.3f}" for m in mean)
    arms = pd.read_csv(out / "arms.csv")
    assert set(arms["controller"]) == {"pd_gravity", "slotine_li"} and len(arms) == 2 * 2 * 4
    summary = json.loads((out / "population.json").read_text())
    assert summary["lead"] == "pd_gravity" and set(summary["laws"]) == {"pd_gravity", "slotine_li"}
    assert summary["seed"] == 5  # --seed reaches every arm, and is recorded
    assert (out / "ratios.png").stat().st_size > 1000 and (out / "ratios.svg").is_file()  # no figure before
    assert "ratios.png" in printed.out.splitlines()[-1]


@pytest.mark.slow
def test_population_run_end_to_end():
    """Two arms, one seed each, a short schedule: the per-seed table carries each arm's seed and the
    per-arm summaries agree with it."""
    from adaptive_dd.benchmark.population import run_population

    data = read_toml(TEMPLATE)
    data["run"]["duration"] = 3.0
    data["payload"] = [{"at": 1.0, "mass": 0.8}, {"at": 2.0, "mass": 0.0}]
    pop = run_population(data, str(TEMPLATE), [0, 1], seeds=1)
    assert sorted(set(pop.frame["arm_seed"])) == [0, 1]
    for a in pop.arms:
        rows = pop.frame[
            (pop.frame["arm_seed"] == a["arm_seed"]) & (pop.frame["controller"] == "adaptive_ct")
        ]
        np.testing.assert_allclose(
            rows.sort_values("segment")["ratio_to_floor"], [s["mean"] for s in a["segments"]]
        )
    assert [p["n"] for p in pooled(pop)] == [2, 2, 2]


def test_a_population_narrowed_by_controllers_drops_the_others_tables(monkeypatch):
    """``benchmark TEMPLATE --arms N --controllers ct_nominal`` on a template with a plug-in's
    settings table runs each arm without that table (it failed: ``controllers.PayloadGradient: not
    a controller of run.controllers``); the tables of the controllers kept go with them."""
    import adaptive_dd.benchmark.runner as runner
    from adaptive_dd.benchmark.population import run_population

    data = read_toml(TEMPLATE)
    data["run"]["controllers"] = [
        "ct_nominal",
        "payload_gradient:PayloadGradient",
        "adaptive_ct",
        "ct_oracle",
    ]
    data["controllers"] = {"PayloadGradient": {"gamma": 200.0}, "adaptive_ct": {"boost_duration": 0.5}}
    ran = []

    class Ran(Exception):
        pass

    def run_benchmark(sc, **kw):
        ran.append(sc)
        raise Ran  # the scenario each arm runs is all this test needs

    monkeypatch.setattr(runner, "run_benchmark", run_benchmark)
    for names, tables in [(("ct_nominal", "ct_oracle"), []), (("adaptive_ct", "ct_oracle"), ["adaptive_ct"])]:
        with pytest.raises(Ran):
            run_population(data, str(TEMPLATE), [3], controllers=lambda sc, names=names: names)
        assert ran[-1].controllers == names
        assert [n for n, _ in ran[-1].controller_options] == tables


def test_benchmark_arms_runs_the_population_with_blas_on_one_thread(monkeypatch):
    """``benchmark FILE --arms N`` runs its arms under one BLAS thread (threadpoolctl), as the
    leaderboard does, and gives the count back after."""
    from contextlib import contextmanager

    from threadpoolctl import threadpool_info, threadpool_limits

    import adaptive_dd._numba_cache as cache
    import adaptive_dd.benchmark.population as population
    from adaptive_dd.cli import main

    def blas_threads():
        return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]

    if not blas_threads():
        pytest.skip("no BLAS that threadpoolctl can control is loaded")
    seen = []

    def run_population(*args, **kw):
        seen.append(blas_threads())
        raise ParameterError("stopped here: the thread count is all this test needs")

    class Compiling:
        def join(self):
            pass

    @contextmanager
    def announce_compilation(arm, stream=None, source=None):
        yield Compiling()  # no compile estimate, no second process

    monkeypatch.setattr(population, "run_population", run_population)
    monkeypatch.setattr(cache, "announce_compilation", announce_compilation)
    with threadpool_limits(limits=2, user_api="blas"):
        before = blas_threads()
        assert main(["benchmark", str(TEMPLATE), "--arms", "1", "--no-progress"]) == 2
        assert blas_threads() == before
    assert seen == [[1] * len(before)]


def test_the_joints_alone_are_the_drawn_arms_joints():
    """``random_arm_joints`` (the leaderboard's scheduler reads it) is the arm's first draw: the
    same number of joints as the whole arm's, on seeds of every size; a bad seed is refused."""
    from adaptive_dd.robots.random_arm import random_arm_joints

    seeds = range(40)
    got = [random_arm_joints(s) for s in seeds]
    assert got == [random_arm(s).n_joints for s in seeds]
    assert set(got) == {3, 4, 5, 6, 7}
    with pytest.raises(ParameterError, match="seed must be an integer >= 0, got -1"):
        random_arm_joints(-1)


def test_every_laws_line_keeps_each_segment_in_its_place():
    """A law whose floor saturates in a segment on every arm has no pooled row there: its line put
    the next segment's figures in that segment's place."""
    import copy

    pop = _fake_population()
    other = copy.deepcopy(pop.arms)
    for a in other:
        a["controller"], a["floor"] = "x", "x_oracle"
        a["segments"][0]["floor_saturated"] = True
    rows = pop.frame[pop.frame["controller"] == "adaptive_ct"].copy()
    rows["controller"] = "x"
    pop.frame = pd.concat([pop.frame, rows], ignore_index=True)
    pop.laws = {"adaptive_ct": pop.arms, "x": other}
    line = next(x for x in format_population(pop).splitlines() if x.startswith("  x / x_oracle"))
    p = pooled(pop, "x")
    assert [q["segment"] for q in p] == [1]
    assert line.startswith(
        f"  x / x_oracle: mean - / {p[0]['mean']:.3f}; p90 - / {p[0]['p90']:.3f}; max - / "
    )


def test_the_ratio_figure_leaves_out_what_the_pooled_lines_leave_out():
    """--arms's ratios.png plotted every row, a floor-saturated segment's too, while the pooled lines
    (and population.json) leave those out: the figure and the printed means differed."""
    from adaptive_dd.benchmark.population import judged_rows

    pop = _fake_population()
    pop.arms[0]["segments"][1]["floor_saturated"] = True
    rows = judged_rows(pop)
    ours = rows[(rows["controller"] == "adaptive_ct") & rows["ratio_to_floor"].notna()]
    by_seg = ours.groupby("segment")["ratio_to_floor"].mean()
    for p in pooled(pop):
        assert by_seg[p["segment"]] == pytest.approx(p["mean"])
    assert len(rows) < len(pop.frame)
