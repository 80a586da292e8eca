"""Identification from a real robot's log: the record description, vendor URDFs, the TIAGo record.

The TIAGo record (examples/tiago, FIGAROH's example, Apache-2.0: see its NOTICE) is real data;
the other tests build small logs whose truth is known.
"""

from __future__ import annotations

import gzip
import math
import types
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.errors import DataError, ScenarioError, UrdfError
from adaptive_dd.record import read_log, record_spec

ROOT = Path(__file__).resolve().parent.parent
TIAGO = ROOT / "examples" / "tiago"
SCENARIO = TIAGO / "tiago.toml"
NAMES = ("j_a", "j_b", "j_c")
KINDS = ("revolute", "revolute", "prismatic")


def _q(t):
    return np.column_stack([0.3 * np.sin(1.3 * t), 0.5 * np.cos(0.7 * t) - 0.2, 0.1 + 0.05 * np.sin(2.1 * t)])


def _write_log(tmp_path, rng, *, n=1500, jitter=0.2, deg=False, gain=(2.0, -3.0, 1.0)):
    """A 100 Hz log with jittered stamps in two files: positions (rad, or deg) and raw efforts."""
    T = 0.01
    t = np.arange(n) * T + rng.uniform(-jitter, jitter, n) * T
    t[0] = 0.0
    q = _q(t)
    tau = np.column_stack([np.sin(t), np.cos(2 * t), 5 + 0 * t])
    pos = q * np.array([180 / math.pi, 180 / math.pi, 1.0]) if deg else q
    p1, p2 = tmp_path / "pos.csv", tmp_path / "eff.csv"
    head = "stamp," + ",".join(f"{j}/pos" for j in NAMES)
    np.savetxt(p1, np.column_stack([t, pos]), delimiter=",", header=head, comments="", fmt="%.12g")
    head = "stamp," + ",".join(f"{j}/eff" for j in NAMES)
    raw = tau / np.asarray(gain)
    np.savetxt(p2, np.column_stack([t, raw]), delimiter=",", header=head, comments="", fmt="%.12g")
    return p1, p2, t, q, tau


def _table(p1, p2, **more):
    return {
        "files": [str(p1), str(p2)],
        "time": "stamp",
        "position": "{joint}/pos",
        "torque": "{joint}/eff",
        "torque_gain": [2.0, 3.0, 1.0],
        "torque_sign": [1, -1, 1],
        **more,
    }


def test_record_resamples_jittered_log_and_converts(tmp_path):
    """Jittered stamps (+-20 %) resampled by spline: positions, derived velocity, converted torque."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(1))
    spec = record_spec(
        _table(p1, p2, torque_offset=[0.0, 0.0, -5.0], exclude=["j_c"]), NAMES, KINDS, "s.toml"
    )
    rec = read_log(spec)
    assert rec.sample_period == pytest.approx(0.01, rel=1e-3)
    assert np.allclose(np.diff(rec.t), rec.sample_period)
    np.testing.assert_allclose(rec.q, _q(rec.t), atol=1e-6)
    true_tau = np.column_stack([np.sin(rec.t), np.cos(2 * rec.t), 0 * rec.t])  # offset -5 on joint 3
    np.testing.assert_allclose(rec.tau, true_tau, atol=1e-4)
    qd_true = np.column_stack(
        [0.39 * np.cos(1.3 * rec.t), -0.35 * np.sin(0.7 * rec.t), 0.105 * np.cos(2.1 * rec.t)]
    )
    inner = slice(10, -10)
    np.testing.assert_allclose(rec.qd[inner], qd_true[inner], atol=2e-4)
    assert not rec.qd_measured and rec.used.tolist() == [True, True, False]
    both = record_spec(_table(p1, p2, torque_weight=[1.0, 0.0, 2.0]), NAMES, KINDS, "s.toml")
    assert both.used.tolist() == [True, False, True] and both.weight.tolist() == [1.0, 0.0, 2.0]
    assert "resampled" in rec.notes[0] and "cubic spline" in rec.notes[0]
    # a window in the log's clock
    part = read_log(spec, window=(3.0, 8.0))
    assert part.t[0] >= 3.0 and part.t[-1] <= 8.0 and part.t.size == pytest.approx(500, abs=2)
    assert not [n for n in part.notes if "reaches beyond" in n]
    beyond = read_log(spec, window=(3.0, 30.0))  # the log ends at 15 s: read to there, and said
    (note,) = [n for n in beyond.notes if "reaches beyond" in n]
    assert note.startswith("the window 3-30 s reaches beyond the log: read 3") and beyond.t[-1] < 15.0


def test_a_file_that_ends_early_is_named_with_what_the_record_loses(tmp_path):
    """The effort file cut at 10 s of 15 silently cut the record to 10 s (its first line still gave
    the positions' span): a note names the file that ends first, where, and what the others lose."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(1))
    spec = record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml")
    whole = read_log(spec)
    assert not [n for n in whole.notes if "what every file covers" in n]
    lines = p2.read_text().splitlines()
    p2.write_text("\n".join(lines[:1001]) + "\n")  # 1000 rows: to about 10 s
    cut = read_log(spec)
    (note,) = [n for n in cut.notes if "what every file covers" in n]
    assert note.startswith(f"{p2} ends at 9.9") and f", {p1} at 14.9" in note and "s of " in note
    assert cut.t[-1] < 10.0 < whole.t[-1]


@pytest.mark.parametrize("gz", [False, True])
def test_a_last_line_cut_short_is_left_out_and_said(tmp_path, gz):
    """A logger that stopped mid-row: the cut number (0.51 written as 0) was read as a sample, its
    missing cells as 0 in excluded columns, without a word. A last line without a line end is left
    out and named; a file that ends with one keeps every row."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(1))
    spec = record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml")
    whole = read_log(spec)
    text = p2.read_text()
    cut = text.rstrip("\n")[:-7]  # the last number cut, no line end
    if gz:
        with gzip.open(p2.with_suffix(".csv.gz"), "wt") as fh:
            fh.write(cut)
        p2.unlink()
        p2 = p2.with_suffix(".csv.gz")
        spec = record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml")
    else:
        p2.write_text(cut)
    rec = read_log(spec)
    (note,) = [n for n in rec.notes if "has no line end" in n]
    assert note.startswith(f"{p2}: line 1501, the last, has no line end") and note.endswith("left out")
    assert rec.t[-1] < whole.t[-1] and not [n for n in whole.notes if "line end" in n]


def test_record_degrees_and_gear_ratio(tmp_path):
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(2), deg=True)
    spec = record_spec(_table(p1, p2, position_unit="deg", exclude=["j_c"]), NAMES, KINDS, "s.toml")
    rec = read_log(spec)
    np.testing.assert_allclose(rec.q, _q(rec.t), atol=1e-6)  # joint 3 (prismatic) stays in m
    spec = record_spec(
        _table(p1, p2, position_unit="deg", gear_ratio=[2.0, 1.0, 1.0], exclude=["j_c"]), NAMES, KINDS, "s"
    )
    np.testing.assert_allclose(read_log(spec).q[:, 0], _q(rec.t)[:, 0] / 2, atol=1e-6)


def test_record_table_errors_name_the_key(tmp_path):
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(3))
    with pytest.raises(ScenarioError, match=r"record.exclude.*j_a, j_b, j_c"):
        record_spec(_table(p1, p2, exclude=["elbow"]), NAMES, KINDS, "s.toml")
    with pytest.raises(ScenarioError, match=r"record.position_unit.*'deg' does not fit joint 'j_c'"):
        record_spec(_table(p1, p2, position_unit=["rad", "rad", "deg"]), NAMES, KINDS, "s.toml")
    with pytest.raises(ScenarioError, match=r"record.speed' is unknown"):
        record_spec(_table(p1, p2, speed=1), NAMES, KINDS, "s.toml")
    with pytest.raises(DataError, match=r"no column 'j_a/effort'.*near matches: \['j_a/eff'"):
        read_log(record_spec(_table(p1, p2, torque="{joint}/effort"), NAMES, KINDS, "s.toml"))
    # one column renamed: the near matches leave out the columns the others already take
    p1.write_text(p1.read_text().replace("j_b/pos", "j_b/position", 1))
    with pytest.raises(DataError, match=r"no column 'j_b/pos'.*near matches: \['j_b/position'\]"):
        read_log(record_spec(_table(p1, p2), NAMES, KINDS, "s.toml"))


def test_columns_numbered_from_0_name_the_list_to_give(tmp_path):
    """A ROS export numbers its joints from 0 (field.position0..2) where {i} counts from 1: the
    error says so and gives the lists of names, which then read the log."""
    t = np.arange(300) * 0.01
    head = "time," + ",".join(f"field.position{j}" for j in range(3)) + ","
    head += ",".join(f"field.effort{j}" for j in range(3))
    path = tmp_path / "ros.csv"
    data = np.column_stack([t, _q(t), np.sin(t), np.cos(t), 0 * t + 5])
    np.savetxt(path, data, delimiter=",", header=head, comments="", fmt="%.12g")
    table = {"files": [str(path)], "time": "time", "position": "field.position{i}", "exclude": ["j_c"]}
    table["torque"] = "field.effort{i}"
    with pytest.raises(
        DataError,
        match=r"ros.csv: no column 'field.position3' .*near matches: .*; \{i\} counts the joints from 1 "
        r"\(record.position = 'field.position\{i\}', record.torque = 'field.effort\{i\}'\) and the files "
        r'number them from 0: list the names instead, position = \["field.position0", "field.position1", '
        r'"field.position2"\]; torque = \["field.effort0", "field.effort1", "field.effort2"\]',
    ):
        read_log(record_spec(table, NAMES, KINDS, "s.toml"))
    table["position"] = [f"field.position{j}" for j in range(3)]
    table["torque"] = [f"field.effort{j}" for j in range(3)]
    np.testing.assert_allclose(read_log(record_spec(table, NAMES, KINDS, "s.toml")).q[:, 0], _q(t)[:, 0])
    table["position"] = "field.pos{i}"  # numbered from 1 or not: no hint where the columns are not there
    with pytest.raises(DataError, match=r"no column 'field.pos1'") as e:
        read_log(record_spec(table, NAMES, KINDS, "s.toml"))
    assert "counts the joints from 1" not in str(e.value)


def test_missing_values_in_velocity_columns_only_name_velocity_source_derived(tmp_path):
    """Only the optional velocity columns have missing values: derive the velocities from the
    positions (velocity_source = "derived"), which then reads the log."""
    p1, p2, t, *_ = _write_log(tmp_path, np.random.default_rng(5), jitter=0.0)
    p3 = tmp_path / "vel.csv"
    qd = np.column_stack([0.39 * np.cos(1.3 * t), -0.35 * np.sin(0.7 * t), 0.105 * np.cos(2.1 * t)])
    qd[200:300, 1] = np.nan
    head = "stamp," + ",".join(f"{j}/vel" for j in NAMES)
    np.savetxt(p3, np.column_stack([t, qd]), delimiter=",", header=head, comments="", fmt="%.12g")
    table = _table(p1, p2, exclude=["j_c"], velocity="{joint}/vel")
    table["files"].append(str(p3))
    with pytest.raises(
        DataError,
        match=r"vel.csv: 100 of the window's 1500 rows .*\(column 'j_b/vel': 100, .*\): only velocity "
        r'columns, which the fit can do without: set velocity_source = "derived" in \[record\] of s.toml '
        r"and drop its velocity key .*; or cut the window",
    ):
        read_log(record_spec(table, NAMES, KINDS, "s.toml"))
    table["velocity_source"] = "derived"  # the logged velocities still read (compared): drop them
    with pytest.raises(DataError, match=r"drop the velocity key of \[record\] in s.toml"):
        read_log(record_spec(table, NAMES, KINDS, "s.toml"))
    del table["velocity"]
    rec = read_log(record_spec(table, NAMES, KINDS, "s.toml"))
    assert not rec.qd_measured and np.isfinite(rec.qd).all() and rec.t.size == 1500
    # the simulator's format (no [record]): add one
    sim = tmp_path / "sim.csv"
    head = "t," + ",".join(f"{c}{j + 1}" for c in ("q", "qd", "tau") for j in range(3))
    data = np.column_stack([t, _q(t), qd, np.sin(t), np.cos(t), np.sin(2 * t)])
    np.savetxt(sim, data, delimiter=",", header=head, comments="", fmt="%.12g")
    with pytest.raises(
        DataError, match=r"\(column 'qd2': 100, .*add \[record\] with velocity_source = \"derived\" to s.toml"
    ):
        read_log(record_spec(None, NAMES, KINDS, "s.toml", files=[str(sim)]))
    rec = read_log(record_spec({"velocity_source": "derived"}, NAMES, KINDS, "s.toml", files=[str(sim)]))
    assert not rec.qd_measured and np.isfinite(rec.qd).all()


def _rewrite(path, edit):
    lines = path.read_text().splitlines()
    edit(lines)
    path.write_text("\n".join(lines) + "\n")


def test_bad_logs_name_file_line_column_and_remedy(tmp_path):
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))
    table = _table(p1, p2, exclude=["j_c"])

    def nan_run(lines, rows=range(200, 290)):
        for i in rows:
            cells = lines[i].split(",")
            cells[2] = "nan"
            lines[i] = ",".join(cells)

    def one_nan(lines):  # and one elsewhere, in another column: not the one to blame
        cells = lines[900].split(",")
        cells[1] = "nan"
        lines[900] = ",".join(cells)

    _rewrite(p1, nan_run)  # 90 of 1500 rows: more than a logger's missed samples
    _rewrite(p1, one_nan)
    with pytest.raises(
        DataError,
        match=r"pos.csv: 91 of the window's 1500 rows have an empty, non-numeric or non-finite cell in a "
        r"column the fit reads, more than the 5% left out as missed samples \(column 'j_b/pos': 90, the "
        r"first at line 201: non-finite value \(nan\); column 'j_a/pos': 1, the first at line 901: "
        r"non-finite value \(nan\)\): is each column the one meant\? Else cut the window",
    ):
        read_log(record_spec(table, NAMES, KINDS, "s"))
    # the NaN run outside the window is no problem
    assert read_log(record_spec(table, NAMES, KINDS, "s"), window=(5.0, 12.0)).t.size > 600
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))

    def repeat(lines):  # a row repeated whole: a logger's repeat, read once and said
        lines.insert(300, lines[299])

    _rewrite(p2, repeat)
    once = read_log(record_spec(table, NAMES, KINDS, "s"))
    said = "eff.csv: 1 row(s) repeated (a logger's repeats: the same values in every column read) read once"
    assert any(said in n for n in once.notes)

    def unread(lines):  # repeated, one cell differing in a column not read (j_c's effort, excluded)
        cells = lines[599].split(",")
        cells[3] = "nan"
        lines.insert(600, ",".join(cells))

    _rewrite(p2, unread)  # the same sample: read once (it was a "duplicated or reordered sample")
    twice = read_log(record_spec(table, NAMES, KINDS, "s"))
    assert any("eff.csv: 2 row(s) repeated" in n for n in twice.notes) and twice.t.size == once.t.size

    def conflict(lines):  # the same stamp with other values: which one is the sample? refused
        cells = lines[299].split(",")
        cells[1] = "0.123"
        lines.insert(300, ",".join(cells))

    _rewrite(p2, conflict)  # line 301 now; the whole repeat, line 302, is dropped and still counted
    with pytest.raises(DataError, match=r"eff.csv: line 301, column 'stamp': time .* repeats line 300"):
        read_log(record_spec(table, NAMES, KINDS, "s"))
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))
    # joint 3's effort is constant (5): a stuck channel unless excluded
    with pytest.raises(
        DataError, match=r"eff.csv: column 'j_c/eff' \(joint 'j_c'\) holds .*\(exclude = \[\"j_c\"\]"
    ):
        read_log(record_spec(_table(p1, p2), NAMES, KINDS, "s"))


def test_degrees_column_is_named_against_the_urdf_limits(tmp_path):
    from adaptive_dd.record_checks import _degrees_hint

    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(5), deg=True)
    arm = types.SimpleNamespace(position_limits=np.array([[-1.0, 1.0], [-1.5, 1.5], [0.0, 0.4]]))
    spec = record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s")
    # both joints logged in degrees are named in the one hint (it named the first only, so a user
    # fixed one joint per run)
    with pytest.raises(
        DataError,
        match=r"pos.csv: column 'j_a/pos' .* in degrees it would fit: set position_unit = "
        r'\["deg", "deg", "rad"\]',
    ):
        read_log(spec, arm=arm)
    # every joint revolute and in degrees: the one unit for all
    assert _degrees_hint(spec, [0, 1, 2], ("revolute",) * 3) == 'position_unit = "deg"'
    spec = record_spec(_table(p1, p2, exclude=["j_c"], position_unit="deg"), NAMES, KINDS, "s")
    assert read_log(spec, arm=arm).q.shape[1] == 3


def _qd(t):
    return np.column_stack([0.39 * np.cos(1.3 * t), -0.35 * np.sin(0.7 * t), 0.105 * np.cos(2.1 * t)])


@pytest.mark.parametrize(("logged", "refused"), [("rad/s", True), ("deg/s", False)])
def test_a_measured_velocity_in_another_unit_than_its_position_is_refused(tmp_path, logged, refused):
    """Positions in degrees scale the velocity column too: a velocity logged in rad/s beside them
    was read 57x too small and fitted a friction 50x too large, with a note only."""
    p1, p2, t, *_ = _write_log(tmp_path, np.random.default_rng(6), deg=True)
    qd = _qd(t) * (np.array([180 / math.pi, 180 / math.pi, 1.0]) if logged == "deg/s" else 1.0)
    p3 = tmp_path / "vel.csv"
    head = "stamp," + ",".join(f"{j}/vel" for j in NAMES)
    np.savetxt(p3, np.column_stack([t, qd]), delimiter=",", header=head, comments="", fmt="%.12g")
    table = _table(p1, p2, exclude=["j_c"], position_unit="deg", velocity="{joint}/vel")
    table["files"].append(str(p3))
    spec = record_spec(table, NAMES, KINDS, "s")
    if not refused:
        assert read_log(spec).qd.shape[1] == 3
        return
    with pytest.raises(
        DataError, match=r"vel.csv: column 'j_a/vel' \(joint 'j_a'\) is 0.0175x the derivative"
    ):
        read_log(spec)
    table["velocity_source"] = "derived"  # the remedy it names
    assert read_log(record_spec(table, NAMES, KINDS, "s")).qd.shape[1] == 3


def test_a_torque_far_beyond_the_urdfs_effort_limit_is_refused_as_a_unit_error(tmp_path):
    """Torques logged in mN m without a gain were fitted: every parameter held at the URDF's and
    explained as directions the record cannot see."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(7))
    limits = np.array([[-1.0, 1.0], [-1.5, 1.5], [0.0, 0.4]])
    spec = record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s")
    weak = types.SimpleNamespace(
        position_limits=limits, actuator=types.SimpleNamespace(torque_limit=[0.05, 5, 5])
    )
    with pytest.raises(
        DataError, match=r"eff.csv: column 'j_a/eff' \(joint 'j_a'\) reaches \|tau\| = 1 N m .* 20x"
    ):
        read_log(spec, arm=weak)
    fine = types.SimpleNamespace(
        position_limits=limits, actuator=types.SimpleNamespace(torque_limit=[0.5, 5, 0.01])
    )
    assert read_log(spec, arm=fine).tau.shape[1] == 3  # within 10x; the excluded channel not judged


# ----------------------------------------------------------------------------- vendor URDFs
def test_vendor_urdf_checks_only_the_chain_and_repairs_on_request():
    from adaptive_dd.plant.urdf import read_urdf, repair_inertia

    urdf = TIAGO / "tiago_48_hey5.urdf"
    with pytest.raises(UrdfError, match=r"link 'arm_1_link'.*triangle inequality.*repair_inertia = true"):
        read_urdf(urdf, "arm_tool_link")
    robot = read_urdf(urdf, "arm_tool_link", repair=True)
    assert robot.joint_names[0] == "torso_lift_joint" and len(robot.joints) == 8
    assert any("repaired link 'arm_1_link'" in n for n in robot.notes)
    assert any("base_antenna_left_link" in n and "not checked" in n for n in robot.notes)
    assert robot.xml is not None and "arm_1_link" in robot.xml
    # the repair: the triangle inequality restored by the least change, a consistent inertia kept
    bad = np.diag([0.00155679, 0.00597627, 0.00777394])
    lam = np.linalg.eigvalsh(repair_inertia(bad))
    assert lam[2] <= lam[0] + lam[1] and np.abs(lam - np.diag(bad)[[0, 1, 2]]).max() < 1.3e-4
    good = np.array([[2.0, 0.1, 0.0], [0.1, 1.5, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(repair_inertia(good), good, atol=1e-5)
    assert np.linalg.eigvalsh(repair_inertia(np.diag([-1e-8, 1e-8, 2e-8])))[0] > 0


# ----------------------------------------------------------------------------- the fit
def test_newey_west_std_matches_the_spread_under_correlated_residuals():
    """On a regression with AR(1) residuals the sandwich std matches the Monte-Carlo spread of the
    estimates (the white-residual formula is several times too small)."""
    from adaptive_dd.identification.log_covariance import newey_west as _newey_west
    from adaptive_dd.identification.log_fit import _solve

    rng = np.random.default_rng(0)
    N, _r = 3000, 3
    t = np.arange(N) * 0.01
    phi = np.stack([np.sin(0.7 * t), np.cos(1.9 * t), np.sin(3.1 * t + 1)], -1)[:, None, :]
    a = 0.97
    est, nw, white = [], [], []
    w = np.ones(1)
    for _ in range(150):
        e = np.empty(N)
        e[0] = rng.standard_normal()
        z = rng.standard_normal(N) * np.sqrt(1 - a * a)
        for k in range(1, N):
            e[k] = a * e[k - 1] + z[k]
        y = phi @ np.array([1.0, -2.0, 0.5]) + e[:, None]
        x, scale = _solve(phi, y, w)
        res = y - phi @ x
        cov, _ = _newey_west(phi, res, w, scale)
        est.append(x)
        nw.append(np.sqrt(np.diag(cov)))
        A = phi[:, 0, :]
        white.append(np.sqrt(np.diag(np.linalg.inv(A.T @ A)) * res.var()))
    spread = np.std(est, axis=0)
    ratio = spread / np.mean(nw, axis=0)
    assert np.all((ratio > 0.6) & (ratio < 1.6)), ratio
    assert np.all(spread / np.mean(white, axis=0) > 3)


def test_excluded_channels_hold_unseen_parameters_and_fit_the_rest():
    """A noise-free log of a perturbed vertical3 arm, joint 3's channel excluded: the parameters only
    channel 3 sees stay at the URDF's values, and the fitted channels are predicted exactly."""
    from adaptive_dd.identification.log_fit import fit_log, identifiable_subset, predict_torque
    from adaptive_dd.identification.model import arm_model
    from adaptive_dd.plant.arm import Arm
    from adaptive_dd.record import derivatives
    from adaptive_dd.robots import robot_urdf

    arm = Arm.from_urdf(robot_urdf("vertical3"))
    model = arm_model(arm)
    T = 0.002
    t = np.arange(5000) * T
    q = np.column_stack([0.8 * np.sin(1.1 * t), 0.6 * np.sin(1.7 * t + 1), 0.9 * np.sin(2.3 * t + 2)])
    qd, qdd = derivatives(q, T)
    truth = model.sigma_ref * np.random.default_rng(0).uniform(0.7, 1.3, model.p)
    tau = predict_torque(model, truth, q, qd, qdd)
    used = np.array([True, True, False])
    K = identifiable_subset(
        model, used, arm.position_limits[:, 0], arm.position_limits[:, 1], np.random.default_rng(0)
    )
    assert 0 < K.sum() < model.p
    fit = fit_log(model, q, qd, tau, used, K, tau_f=0.02, sample_period=T)
    np.testing.assert_array_equal(fit.sigma[~K], model.sigma_ref[~K])
    pred = predict_torque(model, fit.sigma, q, qd, qdd)
    inner = slice(200, -200)
    err = np.abs(pred - tau)[inner][:, used].max() / np.abs(tau[:, used]).max()
    assert err < 1e-3
    assert np.isnan(fit.residual_rms[2]) and fit.weights[2] == 0
    # this torque is sampled from a continuous signal, not held: taken as such, the filtered
    # regression has no half-sample delay and fits closer still
    sampled = fit_log(model, q, qd, tau, used, K, tau_f=0.02, sample_period=T, torque_held=False)
    assert sampled.residual_rms[0] < 0.5 * fit.residual_rms[0]


def test_consistent_arm_fit_takes_a_semidefinite_information():
    from adaptive_dd.identification.consistency import consistent_arm_fit
    from adaptive_dd.identification.model import arm_model
    from adaptive_dd.plant.arm import Arm
    from adaptive_dd.robots import robot_urdf

    model = arm_model(Arm.from_urdf(robot_urdf("vertical3")))
    F = np.eye(model.p)
    F[0, 0] = 0.0  # a direction the record did not see
    fit = consistent_arm_fit(model, model.sigma_ref, F)
    assert np.isfinite(fit.distance) and fit.distance < 1e-3


# ----------------------------------------------------------------------------- the TIAGo record
def test_tiago_held_out_prediction():
    """The shipped record: trained on 9.21-30 s, the held-out 48-67.9 s predicted on arm_1-4 with a
    pooled error (2 Hz low-pass) of 0.73 N m (measured), against 4.3 for the URDF."""
    from adaptive_dd.cli._common import load_arm, read_arm_log
    from adaptive_dd.cli.predict import lowpass
    from adaptive_dd.identification.log_fit import fit_log, identifiable_subset, predict_torque
    from adaptive_dd.identification.model import arm_model
    from adaptive_dd.record import derivatives

    arm = load_arm(str(SCENARIO))
    model = arm_model(arm)
    _, tr = read_arm_log(str(SCENARIO), arm, window=(9.21, 30.0))
    _, te = read_arm_log(str(SCENARIO), arm, window=(48.0, 67.9))
    assert tr.used.tolist() == [False, True, True, True, True, False, False, False]
    lim = arm.position_limits
    K = identifiable_subset(model, tr.used, lim[:, 0], lim[:, 1], np.random.default_rng(0))
    fit = fit_log(model, tr.q, tr.qd, tr.tau, tr.used, K, tau_f=0.02, sample_period=tr.sample_period)
    qd, qdd = derivatives(te.q, te.sample_period)

    def pooled(sigma):
        th = predict_torque(model, sigma, te.q, qd, qdd)
        e = lowpass(te.tau, 2.0, te.sample_period) - lowpass(th, 2.0, te.sample_period)
        return np.sqrt(np.mean(e[:, tr.used] ** 2))

    assert pooled(fit.sigma) < 0.85
    assert pooled(model.sigma_ref) > 4.0
    assert np.all(np.isfinite(fit.std[K])) and np.all(fit.std[K] > 0)


@pytest.mark.slow
def test_cli_identify_and_predict_on_the_tiago_record(tmp_path, capsys):
    """identify --out writes model.json (loadable) and model.urdf; predict prints the per-joint error and
    writes prediction.csv and the plot; a bad log through the CLI is a message, not a traceback."""
    from adaptive_dd.cli import main
    from adaptive_dd.identification.identified_model import load_identified_model

    out = tmp_path / "id"
    args = ["identify", "--arm", str(SCENARIO), "--window", "9.21", "25", "--output-error", "on"]
    assert main([*args, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "repaired link 'arm_1_link'" in text and "base_antenna_left_link" in text
    assert "output error: skipped (it simulates every joint" in text and "Newey-West" in text
    m = load_identified_model(out / "model.json")
    assert len(m.sigma) == len(m.names) == 66 and sum(m.identified) == 53
    assert m.used == [False, True, True, True, True, False, False, False]
    # a [record] log: a torque offset per fitted channel by default, 0 on those left out
    assert "torque offset per channel, fitted with the parameters (auto" in text
    assert m.torque_offset is not None and m.torque_offset[0] == 0.0 and m.torque_offset[5:] == [0.0] * 3
    assert "Coulomb friction fitted as fc tanh(qd / v), v per joint from the record's profile" in text
    extra = np.asarray(m.record["model_error_var"])  # for adaptive_ct's prior ([model] from)
    assert extra.shape == (66,) and np.all(extra >= 0) and np.all(extra[~np.asarray(m.identified)] == 0)
    assert np.any(extra > 0)
    # the 95 % bound is rebuilt from the files: the quantile (not 1.96) and each half-width
    c = m.record["quantile_95"]
    assert 1.96 < c < 3.0 and 0 < m.record["bandwidth_fraction"] < 1
    import pandas as pd

    est = pd.read_csv(out / "estimates.csv")
    np.testing.assert_allclose(est["half_width_95"], c * est["std"], rtol=2e-3, atol=1e-12)
    pred = tmp_path / "pred"
    args = ["predict", "--arm", str(SCENARIO), "--model", str(out / "model.json"), "--window", "48", "58"]
    assert main([*args, "--out", str(pred)]) == 0
    text = capsys.readouterr().out
    assert "low-passed 2 Hz" in text and "pooled over the fitted channels" in text
    head = (pred / "prediction.csv").read_text().splitlines()[0].split(",")
    assert head[:2] == ["t", "tau1"] and head[-1] == "tau_hat8" and len(head) == 17
    assert (pred / "prediction.png").is_file()
    # a column in degrees: exit 2 with the remedy
    bad = tmp_path / "deg.csv.gz"
    with gzip.open(TIAGO / "tiago_position.csv.gz", "rt") as fh:
        lines = fh.read().splitlines()
    rows = [lines[0]] + [
        ",".join([c[0], *(f"{float(x) * 180 / math.pi:.9g}" for x in c[1:])])
        for c in (r.split(",") for r in lines[1:])
    ]
    with gzip.open(bad, "wt") as fh:
        fh.write("\n".join(rows) + "\n")
    files = [str(bad), str(TIAGO / "tiago_velocity.csv.gz"), str(TIAGO / "tiago_effort.csv.gz")]
    assert main(["identify", "--arm", str(SCENARIO), *files, "--out", str(tmp_path / "x")]) == 2
    assert "in degrees it would fit" in capsys.readouterr().err


def test_a_window_too_short_for_its_columns_is_refused_not_fitted(tmp_path, capsys):
    """2.8 s of the TIAGo log (about 42 independent samples for 61 columns) gave exit 0, "held"
    estimates 1360 std from the URDF and a model predicting 1400 % errors: refused, with the window
    that would do, and nothing written; fit_log itself warns."""
    from adaptive_dd.cli import main

    out = tmp_path / "short"
    assert main(["identify", "--arm", str(SCENARIO), "--window", "9.21", "12", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "independent samples for 61 columns fitted: too few to tell them apart" in err
    need = float(err.split("a window of at least about ")[1].split(" s")[0])
    assert 5.0 < need < 12.0 and not (out / "model.json").exists()
    assert (
        main(
            [
                "identify",
                "--arm",
                str(SCENARIO),
                "--window",
                "9.21",
                str(9.21 + 1.2 * need),
                "--out",
                str(out),
            ]
        )
        == 0
    )


# ----------------------------------------------------------------------------- model files, pairs, validate
def test_fitted_urdf_carries_the_standard_parameters(tmp_path):
    """write_fitted_urdf: the arm read back from model.urdf has the written links and friction."""
    from adaptive_dd.plant.arm import Arm
    from adaptive_dd.plant.urdf_write import write_fitted_urdf
    from adaptive_dd.robots import robot_urdf

    arm = Arm.from_urdf(robot_urdf("vertical3"), "tool")
    n = arm.n_joints
    pi = np.array(arm.pi, dtype=float)
    pi[: 10 * n] *= np.repeat([1.1, 0.9, 1.3], 10)  # each link scaled: still a rigid body
    pi[10 * n :] = np.r_[[0.3, 0.2, 0.1], [0.5, 0.4, 0.3], [0.0, 0.0, 0.0]]
    back = Arm.from_urdf(write_fitted_urdf(arm, pi, tmp_path / "model.urdf"), "tool")
    np.testing.assert_allclose(back.pi_links, pi[: 10 * n], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(back.viscous, pi[10 * n : 11 * n])
    np.testing.assert_allclose(back.coulomb, pi[11 * n : 12 * n])


def test_model_file_round_trip_and_errors(tmp_path, capsys):
    from adaptive_dd.identification.identified_model import (
        IdentifiedModel,
        load_identified_model,
        save_identified_model,
    )
    from adaptive_dd.robots import robot_urdf

    p, n = 2, 3
    m = IdentifiedModel(
        urdf=str(robot_urdf("vertical3")),
        payload_frame="tool",
        gravity=[0.0, 0.0, -9.81],
        repair_inertia=False,
        joint_names=["joint1", "joint2", "joint3"],
        friction_velocity=0.02,
        names=["a", "b"],
        sigma=[1.0, 2.0],
        sigma_urdf=[1.0, 1.5],
        std=[0.1, 0.2],
        identified=[True, False],
        covariance=[[0.01, 0.0], [0.0, 0.0]],
        used=[True, True, False],
        residual_rms=[0.5, 0.4, float("nan")],
        noise_rms=[0.1, 0.1, 0.1],
        viscous=[0.0] * n,
        coulomb=[0.0] * n,
        armature=[0.0] * n,
        consistent_sigma=None,
        consistent_distance=None,
        fitted_urdf=None,
        record={"window": [0.0, 1.0]},
    )
    path = save_identified_model(tmp_path / "model.json", m)
    back = load_identified_model(path)
    # predict with a scenario of another arm: refused, naming the model's arm and what differs
    from adaptive_dd.cli import main

    scen = tmp_path / "ur5.toml"
    scen.write_text('[arm]\nrobot = "ur5"\n\n[record]\nfiles = ["log.csv"]\n')
    assert main(["predict", "--arm", str(scen), "--model", str(path), "--out", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err
    assert "identified on an arm of joints ['joint1', 'joint2', 'joint3'] (vertical3.urdf)" in err
    assert "ur5.toml has ['shoulder_pan_joint'" in err
    assert back.sigma == m.sigma and np.isnan(back.residual_rms[2]) and len(back.covariance) == p
    text = path.read_text()
    (tmp_path / "short.json").write_text(
        text.replace('"sigma": [\n  1.0,\n  2.0\n ]', '"sigma": [\n  1.0\n ]')
    )
    with pytest.raises(DataError, match=r"short.json: key 'sigma' has 1 entries, 'names' 2"):
        load_identified_model(tmp_path / "short.json")
    (tmp_path / "other.json").write_text('{"format": "something else"}')
    with pytest.raises(DataError, match=r"other.json: key 'format'"):
        load_identified_model(tmp_path / "other.json")
    with pytest.raises(DataError, match=r"no such model file"):
        load_identified_model(tmp_path / "none.json")


def test_payload_pair_names_what_the_pair_does_not_see():
    """Covariances that are zero where the fitted channels see nothing: a named ParameterError, not
    a LinAlgError; with full covariances the payload comes back."""
    from adaptive_dd.errors import ParameterError
    from adaptive_dd.identification.payload_pair import payload_from_pair
    from adaptive_dd.plant.arm import Arm, payload_parameters
    from adaptive_dd.robots import ROBOTS, robot_urdf

    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    P = arm.payload_basis
    load = payload_parameters(2.0, [0.01, 0.02, 0.05], radius=0.05)
    s0 = arm.sigma
    cov = 1e-8 * np.eye(len(s0))
    pr = payload_from_pair(arm, s0 + P @ load, cov, s0, cov)
    assert pr.mass == pytest.approx(2.0, rel=1e-3)
    blind = cov.copy()
    rows = np.flatnonzero(np.abs(P[:, 0]) > 0)  # every base parameter the payload's mass enters
    blind[rows, rows] = 0.0
    with pytest.raises(ParameterError, match=r"does not determine the payload's .*m"):
        payload_from_pair(arm, s0 + P @ load, blind, s0, blind)


def test_a_massless_pair_prints_its_centre_of_mass_as_undefined(capsys):
    """A record against itself: a zero payload, whose centre of mass is undefined, said so (no NaN
    printed, no division by zero)."""
    import warnings

    from adaptive_dd.cli._identify_log import _print_payload
    from adaptive_dd.identification.payload_pair import payload_from_pair
    from adaptive_dd.plant.arm import Arm, payload_parameters
    from adaptive_dd.robots import ROBOTS, robot_urdf

    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    s0, cov = arm.sigma, 1e-8 * np.eye(arm.sigma.size)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning (0 / 0) fails the test
        pr = payload_from_pair(arm, s0, cov, s0, cov)
    assert pr.mass == 0.0 and not pr.com_defined and np.isnan(pr.com).all()
    _print_payload("payload", pr)
    out = capsys.readouterr().out
    assert "centre of mass undefined" in out and "nan" not in out.lower(), out
    load = payload_parameters(2.0, [0.01, 0.02, 0.05], radius=0.05)
    pr = payload_from_pair(arm, s0 + arm.payload_basis @ load, cov, s0, cov)
    _print_payload("payload", pr)
    out = capsys.readouterr().out
    assert pr.com_defined and "centre of mass [10.00, 20.00, 50.00] +- " in out, out


def test_validate_an_identification_scenario(tmp_path, capsys):
    """A scenario with [arm] and [record] validates without a [reference]; a benchmark table is refused."""
    from adaptive_dd.cli import main

    t = np.arange(200) * 0.01
    cols = np.column_stack([t, np.sin(t), np.cos(t), 0.1 * t, np.sin(t), np.cos(t), t])
    np.savetxt(tmp_path / "log.csv", cols, delimiter=",", header="t,q1,q2,q3,tau1,tau2,tau3", comments="")
    scen = tmp_path / "id.toml"
    scen.write_text(
        '[arm]\nrobot = "vertical3"\ngeneral = true\n\n[record]\nfiles = ["log.csv"]\nexclude = ["joint3"]\n'
    )
    assert main(["validate", str(scen)]) == 0
    out = capsys.readouterr().out
    assert "no [reference]" in out and "record.joint3 = { joint = 'joint3'" in out and "excluded" in out
    # the files themselves are read, as identify reads them (validate read only the scenario before)
    assert "# the log as identify reads it: 200 samples at T = 0.01 s (0-1.99 s of its clock)" in out
    (tmp_path / "log.csv").write_text((tmp_path / "log.csv").read_text().replace("tau2", "tau_2"))
    assert main(["validate", str(scen)]) == 1  # a problem identify would meet, said with the way out
    err = capsys.readouterr().err  # where every problem validate finds is said
    assert "log.csv: no column 'tau2'" in err and "--window START END" in err
    iso = "".join(f"2023-11-14T22:13:{k:02d},0,0,0,0,0,0\n" for k in range(30))
    for body, said in (("", "no data rows"), (iso, "no numeric time stamp in any of its 30 rows")):
        (tmp_path / "log.csv").write_text("t,q1,q2,q3,tau1,tau2,tau3\n" + body)  # said, not a crash
        assert main(["validate", str(scen)]) == 1
        assert said in capsys.readouterr().err
    np.savetxt(tmp_path / "log.csv", cols, delimiter=",", header="t,q1,q2,q3,tau1,tau2,tau3", comments="")
    assert main(["identify", "--arm", str(scen), "--out", str(tmp_path / "m")]) == 0
    model = tmp_path / "m" / "model.json"
    scen.write_text(scen.read_text() + "\n[run]\nduration = 2.0\n")
    assert main(["validate", str(scen)]) == 2
    assert "[run]: an identification scenario" in capsys.readouterr().err
    # identify and predict read the same file by the same rule (they ignored the table before)
    for args in (
        ["identify", "--arm", str(scen), "--out", str(tmp_path / "o")],
        ["predict", "--arm", str(scen), "--model", str(model), "--out", str(tmp_path / "p")],
    ):
        assert main(args) == 2, args
        said = f"{scen}: [run]: an identification scenario (with [record]) holds only"
        assert said in capsys.readouterr().err


def test_identify_refuses_options_of_the_other_path(tmp_path, capsys):
    """Options that one identification path would ignore are errors naming them."""
    from adaptive_dd.cli import main

    scen = tmp_path / "id.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n\n[record]\nfiles = ["log.csv"]\n')
    assert main(["identify", "--arm", str(scen), "--method", "M1", "--out", str(tmp_path / "o")]) == 2
    assert "--method: options of the two-link identification" in capsys.readouterr().err
    assert main(["identify", "x.csv", "--window", "0", "1", "--out", str(tmp_path / "o")]) == 2
    assert "--window: only with --arm" in capsys.readouterr().err


def test_payload_pair_bounds_hold_with_an_estimated_covariance():
    """A covariance estimated from few independent samples (as the records' Newey-West sandwich is:
    a Wishart draw with 4 p degrees of freedom here): the GLS weight C^-1 picks the combinations whose
    estimated variance is low and its std is far too small; the diagonal weighting's sandwich holds.
    The same holds on the whole pipeline (benchmarks/log_bounds_coverage.py --cases pair)."""
    from adaptive_dd.errors import ParameterError
    from adaptive_dd.identification.payload_pair import pair_difference
    from adaptive_dd.plant.arm import Arm, payload_parameters
    from adaptive_dd.robots import ROBOTS, robot_urdf

    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    P = arm.payload_basis
    p = P.shape[0]
    rng = np.random.default_rng(3)
    load = payload_parameters(2.0, [0.01, 0.02, 0.05], radius=0.05)
    A = rng.standard_normal((p, p))
    C = 1e-6 * (A @ A.T / p + 0.05 * np.eye(p))  # correlated estimates, as a fit's are
    L = np.linalg.cholesky(C)
    z = {"gls": [], "diagonal": []}
    for _ in range(150):
        d = P @ load + L @ rng.standard_normal(p)
        X = rng.standard_normal((4 * p, p)) @ L.T
        for weighting, acc in z.items():
            pi, cov = pair_difference(P, d, X.T @ X / (4 * p), weighting)
            acc.append((pi - load) / np.sqrt(np.diag(cov)))
    rms = {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in z.items()}
    cover = {k: float(np.mean(np.abs(v) < 1.96)) for k, v in z.items()}
    assert 0.85 < rms["diagonal"] < 1.2 and cover["diagonal"] > 0.92, (rms, cover)
    # why the pair does not use it: 28 % too small a std, 88 % coverage
    assert rms["gls"] > rms["diagonal"] + 0.15 and cover["gls"] < 0.91, (rms, cover)
    with pytest.raises(ParameterError, match="weighting 'ols' is not"):
        pair_difference(P, d, C, "ols")
    blind = C.copy()
    rows = np.flatnonzero(np.abs(P[:, 0]) > 0)
    blind[rows, :] = blind[:, rows] = 0.0
    with pytest.raises(ParameterError, match=r"does not determine the payload's .*m"):
        pair_difference(P, d, blind, "diagonal")


def _drop_rows():
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import real_log
    finally:
        sys.path.pop(0)
    return real_log.drop_rows


@pytest.mark.parametrize(
    "urdf", ["sub/arm.urdf", "example-robot-data:ur_description/urdf/ur5_robot.urdf", "../up/arm.urdf"]
)
def test_real_log_gap_copy_keeps_the_urdf_reachable(tmp_path, urdf):
    """``benchmarks/real_log.py --drop``'s copy of a scenario: a relative URDF is copied where the copy
    looks for it (a subfolder kept), an example-robot-data one is left to the package (it tried to
    copy ``example-robot-data:...`` as a file)."""
    home = tmp_path / "home"
    for d in (home / "sub", tmp_path / "up"):
        d.mkdir(parents=True)
        (d / "arm.urdf").write_text("<robot name='a'/>")
    (home / "log.csv").write_text("t,a\n" + "".join(f"{0.01 * i},{i}\n" for i in range(50)))
    scenario = home / "s.toml"
    scenario.write_text(f'[arm]\nurdf = "{urdf}"\n\n[record]\nfiles = ["log.csv"]\ntime = "t"\n')
    copy = Path(_drop_rows()(str(scenario), 0.2, 5))
    assert copy.parent != home and len((copy.parent / "log.csv").read_text().splitlines()) == 46
    assert (copy.parent / "sub" / "arm.urdf").exists() == (urdf == "sub/arm.urdf")
    if urdf.startswith(".."):  # above the scenario: named by its absolute path, nothing written outside
        assert f'urdf = "{(tmp_path / "up" / "arm.urdf").resolve().as_posix()}"' in copy.read_text()
        assert not (copy.parent.parent / "up").exists()
    else:
        assert copy.read_text() == scenario.read_text()


@pytest.mark.parametrize(("unit", "factor"), [("ms", 1e3), ("ns", 1e9)])
def test_a_time_column_in_ms_or_ns_is_said_and_read_with_time_unit(tmp_path, unit, factor):
    """A log stamped in ms or ns (ROS stamps) was read as s: in ms a 10 s sample period and a silently
    wrong fit, in ns an internal error in the filters. Without ``time_unit`` it is refused naming the
    key; with it the record is the one stamped in s (the window in s either way)."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(1))
    ref = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    for p in (p1, p2):
        lines = p.read_text().splitlines()
        p.write_text(
            "\n".join(
                [lines[0]]
                + [f"{float(x.split(',')[0]) * factor:.17g}," + x.split(",", 1)[1] for x in lines[1:]]
            )
            + "\n"
        )
    with pytest.raises(DataError, match=rf"steps by .* read as s.*time_unit = \"{unit}\""):  # the unit meant
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"], time_unit=unit), NAMES, KINDS, "s.toml"))
    assert rec.sample_period == pytest.approx(ref.sample_period, rel=1e-9)
    np.testing.assert_allclose(rec.q, ref.q, atol=1e-9)
    np.testing.assert_allclose(rec.tau, ref.tau, atol=1e-9)
    for bad in ("sec", ["ms"]):
        with pytest.raises(ScenarioError, match=r"record\.time_unit' must be one of 's', 'ms', 'us', 'ns'"):
            record_spec(_table(p1, p2, time_unit=bad), NAMES, KINDS, "s.toml")
    with pytest.raises(DataError, match=r"time_unit"):  # a grid in s does not make the stamps s
        read_log(record_spec(_table(p1, p2, exclude=["j_c"], sample_period=0.01), NAMES, KINDS, "s.toml"))
    with pytest.raises(
        DataError, match=rf"holds \d samples .* need at least 20; its stamps step by .*time_unit = \"{unit}\""
    ):
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"), window=(4.1, 12.0))


def test_a_log_stepping_by_one_read_as_s_is_refused(tmp_path):
    """A 1 kHz log stamped in ms steps by exactly 1: it passed the old 1 s limit and was read as a
    1 Hz log (T = 1 s, tau_f = 2 s, a garbage fit with exit 0)."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(2))
    for p in (p1, p2):
        lines = p.read_text().splitlines()
        body = [f"{float(x.split(',')[0]) * 100:.17g}," + x.split(",", 1)[1] for x in lines[1:]]
        p.write_text("\n".join([lines[0], *body]) + "\n")
    with pytest.raises(DataError, match=r"steps by 0.99\d* per sample .* read as s.*time_unit = \"ms\""):
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))


@pytest.mark.parametrize("sep", [";", "\t"])
def test_a_semicolon_or_tab_separated_log_reads_as_a_comma_one(tmp_path, sep):
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(2))
    ref = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    for p in (p1, p2):
        p.write_text(p.read_text().replace(",", sep))
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    np.testing.assert_array_equal(rec.q, ref.q)


@pytest.mark.parametrize("sep", [";", "\t"])
def test_decimal_commas_of_a_semicolon_or_tab_log_are_read_and_said(tmp_path, sep):
    """A spreadsheet of a comma-decimal locale writes 0,5;1,25: read as numbers (they were text, then
    refused cell by cell), and said; a comma file is never read so."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(2))
    ref = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    for p in (p1, p2):
        p.write_text(p.read_text().replace(",", sep).replace(".", ","))
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    np.testing.assert_array_equal(rec.q, ref.q)
    assert sum("decimal comma" in nt for nt in rec.notes) == 2


def test_a_bad_cell_is_quoted_as_written(tmp_path):
    """The message quotes the cell (nan, a time), not numpy's repr (np.float64(nan)); one line is a line."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))

    def edit(lines):
        lines[100] = ",".join([*lines[100].split(",")[:2], "nan", *lines[100].split(",")[3:]])
        for i in range(400, 1500, 10):  # and enough others, apart, to be refused (7 %)
            lines[i] = ",".join([*lines[i].split(",")[:2], "", *lines[i].split(",")[3:]])

    _rewrite(p1, edit)
    with pytest.raises(
        DataError,
        match=r"pos.csv: 111 of .*\(column 'j_b/pos': 111, the first at line 101: non-finite value \(nan\)\)",
    ) as exc:
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    assert "np.float64" not in str(exc.value)


def _without_line(path, line: int):
    """A copy of ``path`` without its file line ``line`` (the header is line 1)."""
    lines = path.read_text().splitlines()
    out = path.with_name("cut_" + path.name)
    out.write_text("\n".join(lines[: line - 1] + lines[line:]) + "\n")
    return out


@pytest.mark.parametrize(("file", "cell"), [(0, "nan"), (0, ""), (1, "n/a"), (0, "inf")])
def test_a_lone_bad_cell_is_a_sample_the_logger_missed(tmp_path, file, cell):
    """A logger's empty or NaN cell in a fitted column refused the whole log. The row is left out, and
    the record is then the one read from the file without that row (bridged as a missed sample), the
    notes naming file, count and line."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))
    paths = [p1, p2]
    col = 2 if file == 0 else 1  # j_b/pos, or j_a/eff (fitted)

    def edit(lines):
        cells = lines[700].split(",")
        cells[col] = cell
        lines[700] = ",".join(cells)

    _rewrite(paths[file], edit)  # file line 701
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    cut = list(paths)
    cut[file] = _without_line(paths[file], 701)
    ref = read_log(record_spec(_table(*cut, exclude=["j_c"]), NAMES, KINDS, "s"))
    np.testing.assert_array_equal(rec.q, ref.q)
    np.testing.assert_array_equal(rec.tau, ref.tau)
    name = paths[file].name
    said = [n for n in rec.notes if "left out as samples the logger missed" in n]
    assert len(said) == 1 and said[0].startswith(str(paths[file])) and f"{name}: 1 row(s)" in said[0]
    assert "(line(s) 701)" in said[0] and f"reads ('{'j_b/pos' if file == 0 else 'j_a/eff'}')" in said[0]
    assert any("bridged 1 gap(s) of one missed sample" in n for n in rec.notes)


def test_a_run_of_bad_cells_is_a_gap_and_a_bad_time_places_its_row_nowhere(tmp_path):
    """Thirty rows of NaN in one column are a gap of the log, split at (its pieces); a row whose time is
    not a number is left out wherever it is, window or not."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))

    def edit(lines):
        for i in range(600, 630):
            cells = lines[i].split(",")
            cells[3] = "nan"  # j_c/pos: fitted (only j_c's torque is excluded)
            lines[i] = ",".join(cells)
        cells = lines[1300].split(",")
        cells[0] = "ERR"
        lines[1300] = ",".join(cells)

    _rewrite(p1, edit)
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    assert len(rec.spans) == 2
    assert any("pos.csv: 31 row(s)" in n and "(line(s) 601, 602, 603, 604, 605, ...)" in n for n in rec.notes)
    assert any(n.startswith("a gap of") and "pos.csv" in n for n in rec.notes)
    np.testing.assert_allclose(rec.q, _q(rec.t), atol=1e-5)  # no spline across the gap
    # within a window that leaves the NaN run out, the bad time still is (it places its row nowhere)
    part = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"), window=(0.5, 5.0))
    assert len(part.spans) == 1 and any("pos.csv: 1 row(s)" in n and "1301" in n for n in part.notes)


def test_a_bad_cell_in_an_excluded_channel_is_not_an_error(tmp_path):
    """An excluded torque channel is left out of the fit (docs/real_log.md): a NaN in it refused the
    whole record; it is read as 0 and said in the notes, while one in a fitted channel is refused."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))

    def nan_in(col):
        def edit(lines):
            cells = lines[100].split(",")
            cells[col] = "nan"
            lines[100] = ",".join(cells)

        return edit

    _rewrite(p2, nan_in(3))  # j_c/eff
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    assert np.all(np.isfinite(rec.tau))
    assert any(
        "column 'j_c/eff' (excluded, not fitted): 1 non-finite cell(s) read as 0" in n for n in rec.notes
    )
    _rewrite(p2, nan_in(2))  # j_b/eff, fitted: the row is a missed sample
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    assert any("eff.csv: 1 row(s)" in n and "(line(s) 101)" in n for n in rec.notes)


def test_a_file_logged_at_another_rate_than_the_grid_is_said(tmp_path):
    """The grid follows the first file (or sample_period); a file read at a coarser grid is decimated
    by interpolation without an anti-alias filter, and that was silent."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(3))
    same = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    assert not any("logged every" in n for n in same.notes)
    coarse = read_log(record_spec(_table(p1, p2, exclude=["j_c"], sample_period=0.02), NAMES, KINDS, "s"))
    said = [n for n in coarse.notes if "logged every" in n]
    assert len(said) == 2 and all("decimated, with no anti-alias filter" in n for n in said)


def test_line_numbers_count_a_repeated_row_that_was_dropped(tmp_path):
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(4))

    def edit(lines):
        cells = lines[1000].split(",")
        cells[2] = "x"
        lines[1000] = ",".join(cells)  # file line 1001
        lines.insert(300, lines[299])  # a whole repeat at line 301: the bad cell is on line 1002

    _rewrite(p1, edit)
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    assert any("pos.csv: 1 row(s)" in n and "(line(s) 1002)" in n for n in rec.notes)

    def more(lines):  # and a text column from line 1101 on: refused at the first cell
        for i in range(1101, len(lines)):
            cells = lines[i].split(",")
            cells[2] = "x"
            lines[i] = ",".join(cells)

    _rewrite(p1, more)
    with pytest.raises(
        DataError, match=r"column 'j_b/pos': \d+, the first at line 1002: not a number \('x'\)"
    ):
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))


def test_predict_checks_its_output_folder_before_any_work(tmp_path, capsys):
    """``predict --out FILE`` ran the whole prediction and printed it before failing on the folder."""
    from adaptive_dd.cli import main

    afile = tmp_path / "afile"
    afile.write_text("")
    argv = ["predict", "--arm", str(SCENARIO), "--model", str(tmp_path / "none.json"), "--out", str(afile)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "afile is a file" in err and "none.json" not in err  # the folder first, the model not read


def test_a_simulator_format_log_missing_a_column_says_which_format(tmp_path):
    """A record of a 6-joint arm read for a 7-joint one: the message named a [record] table the
    scenario does not have and cut the columns at twelve without saying so."""
    cols = np.zeros((20, 19))
    cols[:, 0] = np.arange(20) * 0.01
    head = "t," + ",".join(f"{k}{j}" for k in ("q", "qd", "tau") for j in range(1, 7))
    np.savetxt(tmp_path / "r.csv", cols, delimiter=",", header=head, comments="")
    spec = record_spec(
        None, [f"j{j}" for j in range(7)], ("revolute",) * 7, "arm7.toml", files=[str(tmp_path / "r.csv")]
    )
    with pytest.raises(
        DataError, match=r"no column 'q7' \(the simulator's format of the 7-joint arm of arm7.toml"
    ) as e:
        read_log(spec)
    assert "(19 in all)" in str(e.value) and "[record] of" not in str(e.value)


def test_decimal_commas_are_read_beside_whole_numbers(tmp_path):
    """A spreadsheet writes 0 as 0: a first row of an arm at rest (0;0;0;0) made every column mixed
    and the decimal commas were not recognised (each cell then refused as not a number)."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(2))
    ref = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    for p in (p1, p2):
        lines = p.read_text().splitlines()
        lines[1] = ",".join("0" for _ in lines[1].split(","))  # the arm at rest, written 0
        p.write_text("\n".join(lines).replace(",", ";").replace(".", ",") + "\n")
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    assert rec.q.shape == ref.q.shape and sum("decimal comma" in nt for nt in rec.notes) == 2


def test_a_reversed_window_is_named_as_reversed(tmp_path):
    """``--window 15 10`` said the window held 0 samples."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(8))
    spec = record_spec(_table(p1, p2), NAMES, KINDS, "s.toml")
    with pytest.raises(DataError, match=r"the window \[10, 5\] s: its start must be before its end"):
        read_log(spec, window=(10.0, 5.0))


def test_bad_times_are_named_in_the_bad_cells_error_and_a_short_log_is_not_a_reversed_window(tmp_path):
    """Empty stamps counted in the rows but listed under no column ('(): is each column the one
    meant?'); a one-row log was told its window [0, 0] was reversed, a window nobody gave."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(9))

    def no_time(lines):
        for i in range(200, 300):
            lines[i] = "," + lines[i].split(",", 1)[1]

    _rewrite(p1, no_time)
    with pytest.raises(
        DataError, match=r"\(column 'stamp': 100, the first at line 201: non-finite value \(nan\)"
    ):
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s"))
    one = tmp_path / "one.csv"
    one.write_text("stamp,j_a/pos,j_b/pos,j_c/pos\n0.0,0.1,0.2,0.3\n")
    eff = tmp_path / "one_eff.csv"
    eff.write_text("stamp,j_a/eff,j_b/eff,j_c/eff\n0.0,0.1,0.2,0.3\n")
    with pytest.raises(DataError, match=r"holds 1 samples .*need at least 20"):
        read_log(record_spec(_table(one, eff, exclude=["j_c"]), NAMES, KINDS, "s"))


def test_predict_writes_an_epoch_clock_s_times_in_full(tmp_path):
    """prediction.csv wrote every time with 8 digits: a log stamped in ns since 1970 read 1.7e+09 on
    every row. Its steps are kept now."""
    import argparse
    from types import SimpleNamespace

    from adaptive_dd.cli.predict import _write

    t = 1.7e9 + 0.002 * np.arange(50)
    tau = np.sin(t - t[0])[:, None] * np.ones((1, 2))
    rec = SimpleNamespace(t=t, tau=tau)
    args = argparse.Namespace(out=str(tmp_path / "p"))
    _write(args, rec, tau, ("all", tau, tau), ("j1", "j2"), np.ones(2, bool))
    back = np.loadtxt(tmp_path / "p" / "prediction.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(np.diff(back[:, 0]), 0.002, atol=1e-6)  # float64 at 1.7e9: 2.4e-7 s


def test_a_log_s_last_line_cut_short_is_said_so(tmp_path, capsys):
    """A file copied while its logger wrote it ends in a partial line: it was called a sample the
    logger missed. It is left out as before, and named as cut short (no line end)."""
    from adaptive_dd.cli import main

    t = np.arange(200) * 0.01
    cols = np.column_stack([t, np.sin(t), np.cos(t), 0.1 * t, np.sin(t), np.cos(t), t])
    np.savetxt(tmp_path / "log.csv", cols, delimiter=",", header="t,q1,q2,q3,tau1,tau2,tau3", comments="")
    with open(tmp_path / "log.csv", "a") as fh:
        fh.write("2.00,0.9,0.4")
    scen = tmp_path / "id.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n\n[record]\nfiles = ["log.csv"]\nexclude = ["joint3"]\n')
    assert main(["validate", str(scen)]) == 0
    out = capsys.readouterr().out
    assert "line 202, the last, has no line end" in out and "200 samples" in out
    text = (tmp_path / "log.csv").read_text().rsplit("\n", 1)[0]  # a whole last line, a middle cell empty
    (tmp_path / "log.csv").write_text(text + "\n2.00,0.9,,0.1,0.2,0.3,0.4\n")
    assert main(["validate", str(scen)]) == 0
    out = capsys.readouterr().out
    assert "(line(s) 202)" in out and "no line end" not in out


def test_a_window_from_the_log_s_start_on_an_epoch_clock_is_given_in_its_clock(tmp_path, capsys):
    """On a log stamped in seconds since 1970, --window 0 5 held no sample and said only so; the
    error now gives the same window in the log's clock."""
    from adaptive_dd.cli import main

    t = 1.7e9 + np.arange(200) * 0.01
    cols = np.column_stack([t, np.sin(t - t[0]), np.cos(t - t[0]), 0.1 * (t - t[0]), np.sin(t), np.cos(t), t])
    head = "t,q1,q2,q3,tau1,tau2,tau3"
    np.savetxt(tmp_path / "log.csv", cols, delimiter=",", header=head, comments="", fmt="%.15g")
    scen = tmp_path / "id.toml"
    scen.write_text('[arm]\nrobot = "vertical3"\n\n[record]\nfiles = ["log.csv"]\nexclude = ["joint3"]\n')
    argv = ["identify", "--arm", str(scen), "--window", "0", "1.5", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "starts at 1700000000 s: the same window from its start is --window 1700000000 1700000001.5" in err


def test_logs_as_a_walk_through_met_them(tmp_path):
    """A header with spaces ("stamp, j_a/pos") named as written crashed identify (internal KeyError);
    an excluded joint's torque column absent from the files, or a derived velocity's logged column
    absent, was required though never read; milliradians had no unit."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(1))
    ref = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    for p in (p1, p2):  # a header with a space after each comma, named with its spaces
        lines = p.read_text().splitlines()
        p.write_text("\n".join([lines[0].replace(",", ", "), *lines[1:]]) + "\n")
    spaced = _table(p1, p2, exclude=["j_c"], time=" stamp", position=" {joint}/pos", torque=" {joint}/eff")
    rec = read_log(record_spec(spaced, NAMES, KINDS, "s.toml"))
    np.testing.assert_array_equal(rec.q, ref.q)
    lines = p2.read_text().splitlines()  # the excluded joint's effort column gone
    p2.write_text(
        "\n".join([", ".join(lines[0].split(", ")[:3]), *(",".join(x.split(",")[:3]) for x in lines[1:])])
        + "\n"
    )
    rec = read_log(record_spec(spaced, NAMES, KINDS, "s.toml"))
    np.testing.assert_array_equal(rec.tau[:, :2], ref.tau[:, :2])
    assert np.all(rec.tau[:, 2] == 0.0) and any("['j_c/eff'] of excluded joint(s)" in n for n in rec.notes)
    with pytest.raises(DataError, match=r"j_c/eff"):  # fitted: still required
        read_log(record_spec({**spaced, "exclude": []}, NAMES, KINDS, "s.toml"))
    derived = {**spaced, "velocity": "{joint}/vel", "velocity_source": "derived"}
    rec = read_log(record_spec(derived, NAMES, KINDS, "s.toml"))
    np.testing.assert_array_equal(rec.q, ref.q)
    assert any("are derived from the positions" in n for n in rec.notes)
    lines = p1.read_text().splitlines()  # positions in mrad, the prismatic joint in m
    rows = [np.array(x.split(","), float) for x in lines[1:]]
    body = [",".join(f"{v:.12g}" for v in (r[0], 1e3 * r[1], 1e3 * r[2], r[3])) for r in rows]
    p1.write_text("\n".join([lines[0], *body]) + "\n")
    rec = read_log(record_spec({**spaced, "position_unit": ["mrad", "mrad", "m"]}, NAMES, KINDS, "s.toml"))
    np.testing.assert_allclose(rec.q, ref.q, atol=1e-12)


def test_the_degrees_hint_names_milliradians_and_millimetres_by_the_joints_kind():
    """The reverse map of units read 1e-3 as "mm" for a revolute joint logged in mrad: the hint then
    proposed a unit the check refuses."""
    from adaptive_dd.record_checks import _degrees_hint

    units = ["mrad", "deg", "mm"]
    spec = record_spec(_table(Path("a.csv"), Path("b.csv"), position_unit=units), NAMES, KINDS, "s.toml")
    assert _degrees_hint(spec, 1, KINDS).startswith('position_unit = ["mrad", "deg", "mm"]')


def test_a_decimal_comma_log_with_a_bad_cell_keeps_its_column(tmp_path):
    """One ERR cell in a decimal-comma file made its whole column text, every cell refused."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(2))
    ref = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))

    def edit(lines):
        cells = lines[700].split(",")
        lines[700] = ",".join([*cells[:2], "ERR", *cells[3:]])

    _rewrite(p1, edit)
    for p in (p1, p2):
        p.write_text(p.read_text().replace(",", ";").replace(".", ","))
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    assert rec.q.shape == ref.q.shape  # the ERR row is a missed sample, interpolated over
    np.testing.assert_allclose(rec.q, ref.q, atol=1e-3)
    assert any("decimal comma" in nt for nt in rec.notes)


def test_files_in_two_time_units_or_two_clocks_are_named(tmp_path):
    """A second file stamped in ms was interpolated as a 5 s log ('about 5 independent samples');
    clocks that do not overlap read 'no piece between the log's gaps holds 7 samples'."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(3))

    def scale(k):
        def edit(lines):
            for i in range(1, len(lines)):
                cells = lines[i].split(",")
                lines[i] = ",".join(
                    [repr(float(cells[0]) * k if k != "epoch" else float(cells[0]) + 1.7e9), *cells[1:]]
                )

        return edit

    _rewrite(p2, scale(1000.0))
    with pytest.raises(
        DataError, match=r"eff.csv: the time column 'stamp' steps by .*convert its time column"
    ):
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(3))
    _rewrite(p2, scale("epoch"))
    with pytest.raises(
        DataError, match=r"the files' time spans do not overlap \(.*pos.csv 0-.*eff.csv 1700000000"
    ):
        read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))


def test_positions_repeated_while_the_arm_moves_are_said(tmp_path):
    """A stale position sensor (every second row repeating the last) biased a viscous friction beyond
    its 95 % bound on every seed, without a word."""
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(5), jitter=0.0)

    def stale(lines):
        for i in range(3, len(lines), 2):
            lines[i] = ",".join([lines[i].split(",")[0], *lines[i - 1].split(",")[1:]])

    _rewrite(p1, stale)
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    assert any("samples while the arm moves repeat the previous sample's positions" in nt for nt in rec.notes)
    p1, p2, *_ = _write_log(tmp_path, np.random.default_rng(5), jitter=0.0)
    rec = read_log(record_spec(_table(p1, p2, exclude=["j_c"]), NAMES, KINDS, "s.toml"))
    assert not any("repeat the previous sample's positions" in nt for nt in rec.notes)
