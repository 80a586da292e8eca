"""Every number of the Python (plug-in) path of both arms, dumped and compared bit for bit.

A refactoring's safety net for the driver of the Python path
(:func:`adaptive_dd.closed_loop.python_path.run_python_batch`)::

    PYTHONPATH=/old/tree python benchmarks/python_path_identity.py dump BEFORE.npz
    PYTHONPATH=. python benchmarks/python_path_identity.py dump AFTER.npz
    python benchmarks/python_path_identity.py compare BEFORE.npz AFTER.npz

(without ``PYTHONPATH`` the installed ``adaptive_dd`` is imported, not this tree's: ``dump``
prints which one it ran).

``dump`` runs, on the Python path and with measurement dropouts, the two-link arm (every
built-in through its Python form, the example plug-in ``examples/payload_gradient.py``, a
bare reset/command/observe class, a controller that goes NaN in one trial and one that
raises) and the N-joint arm (``vertical3_payload_exact``: the built-ins, a bare wrapper, a runaway
trial, a raising controller), and stores every array of every run (streamed sums, error
norm, trajectories, estimates, failures, dropouts, alarms, skipped samples, the error
message). ``compare`` asserts equality at rtol 0 (NaN equal to NaN), prints the count of
numbers compared and each difference, and exits 1 on any. The compiled path's runs of the same
built-ins are dumped too (they draw from the same noise blocks).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
RUN_FIELDS = ("e_norm", "sigma_end", "failed", "failed_at", "q", "qd", "tau", "saturated", "sigma_hat")
RUN_FIELDS += ("dropped", "skipped")


class _Bare:
    """A reset/command/observe class with no base class around another controller; after
    ``after`` commands it goes wrong in ``where``: ``reset``, ``command`` or ``observe`` raise,
    ``shape`` returns a command of the wrong shape, ``nan`` makes trial 0's command NaN."""

    def __init__(self, inner, after: int = 0, where: str = ""):
        self.inner, self.after, self.where, self.k = inner, after, where, 0

    def reset(self, n_trials, sample_period):
        if self.where == "reset":
            raise RuntimeError("boom")
        self.inner.reset(n_trials, sample_period)

    def command(self, q, qd, q_d, qd_d, qdd_d):
        self.k += 1
        tau = np.array(self.inner.command(q, qd, q_d, qd_d, qdd_d), dtype=float)
        late = self.where and self.k > self.after
        if late and self.where == "command":
            raise RuntimeError("boom")
        if late and self.where == "nan":
            tau[0] = np.nan
        return tau[:, :1] if late and self.where == "shape" else tau

    def observe(self, q, qd, tau):
        if self.where == "observe" and self.k > self.after:
            raise RuntimeError("boom")
        self.inner.observe(q, qd, tau)


def _two_link(engine: str = "python") -> dict:
    from adaptive_dd.benchmark import load_scenario, run_benchmark
    from adaptive_dd.controllers import DEFAULT_GAINS, make_controller

    sc = load_scenario(ROOT / "examples" / "plugin.toml")
    sc = dataclasses.replace(sc, seeds=3, duration=1.6, swap_times=(0.6, 1.1), swap_masses=(3.0, 1.0))
    sc = dataclasses.replace(sc, dropout=0.01)
    res = run_benchmark(sc, progress=False, engine=engine, keep_trajectories=2)
    if engine != "python":
        return res.runs
    extra = {
        "pd": make_controller("pd", DEFAULT_GAINS),
        "ct_oracle_textbook": make_controller("ct_oracle_textbook", DEFAULT_GAINS),
        "adaptive_ct_paper": make_controller("adaptive_ct_paper", DEFAULT_GAINS),
        "bare": _Bare(make_controller("adaptive_ct", DEFAULT_GAINS)),
        "nan": _Bare(make_controller("ct_nominal", DEFAULT_GAINS), 700, "nan"),
        **{
            f"raises_{w}": _Bare(make_controller("adaptive_ct", DEFAULT_GAINS), 900, w)
            for w in ("reset", "command", "observe", "shape")
        },
    }
    res2 = run_benchmark(sc, progress=False, controllers=extra, engine="python", keep_trajectories=2)
    return {**res.runs, **res2.runs}


def _n_joint(engine: str = "python") -> dict:
    from adaptive_dd.benchmark.scenario import parse_scenario
    from adaptive_dd.closed_loop.runner import run_closed_loop
    from adaptive_dd.controllers import make_controller

    path = resources.files("adaptive_dd.scenarios").joinpath("vertical3_payload_exact.toml")
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    data["run"] = {**data["run"], "duration": 1.2, "seeds": 3, "controllers": ["adaptive_ct", "ct_oracle"]}
    for p, at in zip(data["payload"], (0.5, 0.9), strict=False):
        p["at"] = at
    data["payload"] = data["payload"][:2]
    data["controllers"] = {}
    sc = dataclasses.replace(parse_scenario(data, "identity.toml", name="identity"), dropout=0.01)
    arm = sc.arm
    ctrls = {n: make_controller(n, arm=arm) for n in ("adaptive_ct", "slotine_li", "ct_oracle", "pd")}
    if engine != "python":
        return run_closed_loop(sc, ctrls, engine=engine, keep_trajectories=2).runs
    ctrls["bare"] = _Bare(make_controller("slotine_li", arm=arm))
    ctrls["nan"] = _Bare(make_controller("ct_nominal", arm=arm), 500, "nan")
    for w in ("reset", "command", "observe", "shape"):
        ctrls[f"raises_{w}"] = _Bare(make_controller("adaptive_ct", arm=arm), 700, w)
    return run_closed_loop(sc, ctrls, engine="python", keep_trajectories=2).runs


def _arrays(prefix: str, runs: dict) -> dict:
    out = {}
    for name, run in runs.items():
        key = f"{prefix}/{name}"
        for f in run.acc._fields:
            out[f"{key}/acc.{f}"] = np.asarray(getattr(run.acc, f))
        for f in RUN_FIELDS:
            v = getattr(run, f)
            out[f"{key}/{f}"] = np.array([]) if v is None else np.asarray(v)
            out[f"{key}/{f}.is_none"] = np.array(v is None)
        alarms = run.alarm_times
        out[f"{key}/alarm_times.is_none"] = np.array(alarms is None)
        if alarms is not None:
            out[f"{key}/alarm_times.count"] = np.array([len(a) for a in alarms])
            out[f"{key}/alarm_times"] = np.array([x for a in alarms for x in a], dtype=float)
        out[f"{key}/error"] = np.array(run.error)
        out[f"{key}/engine"] = np.array(run.engine)
        out[f"{key}/floor"] = np.array(str(run.floor))
    return out


def dump(path: str) -> None:
    arrays = {**_arrays("two_link", _two_link()), **_arrays("n_joint", _n_joint())}
    arrays |= _arrays("two_link_compiled", _two_link("auto"))  # the noise blocks are shared
    arrays |= _arrays("n_joint_compiled", _n_joint("compiled"))
    np.savez_compressed(path, **arrays)
    import adaptive_dd

    n = sum(a.size for a in arrays.values())
    print(f"{len(arrays)} arrays, {n} values of {adaptive_dd.__file__} -> {path}")


def compare(a_path: str, b_path: str) -> int:
    a, b = np.load(a_path), np.load(b_path)
    diffs, numbers = [], 0
    if set(a.files) != set(b.files):
        diffs.append(f"keys differ: {sorted(set(a.files) ^ set(b.files))}")
    for k in sorted(set(a.files) & set(b.files)):
        x, y = a[k], b[k]
        if x.shape != y.shape or x.dtype != y.dtype:
            diffs.append(f"{k}: {x.dtype}{x.shape} != {y.dtype}{y.shape}")
            continue
        if x.dtype.kind in "fc":
            numbers += x.size
            same = np.array_equal(x, y, equal_nan=True)
        else:
            numbers += x.size if x.dtype.kind in "biu" else 0
            same = np.array_equal(x, y)
        if not same:
            diffs.append(f"{k}: differs")
    print(f"{len(a.files)} arrays, {numbers} numbers compared at rtol 0: {len(diffs)} differences")
    for d in diffs:
        print("  " + d)
    return 1 if diffs else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    sub.add_parser("dump").add_argument("out")
    c = sub.add_parser("compare")
    c.add_argument("before")
    c.add_argument("after")
    args = ap.parse_args()
    if args.cmd == "dump":
        dump(args.out)
        return 0
    return compare(args.before, args.after)


if __name__ == "__main__":
    sys.exit(main())
