"""Prototype (offline): a matched test on the integrated generalised-momentum error.

Records adaptive_ct's closed loop (Python path, its command unchanged) with, per sample and trial,
the observer's per-sample residual ``rho = tau - (p_now - p_last) / T - (wv_last + wv_now) / 2``
of the model the law uses at that sample (``residual_observer._observe``'s ``rho``, one sample summed), then
replays tests on it offline and prints each test's delay after every swap against the alarm of
adaptive_ct's detector, and its alarms outside the swaps' windows (false alarms).

The test: ``E_k = T sum_{i <= k} rho_i`` (the momentum error; its noise does not grow with the
window, only the two end momenta's), per row and window ``m`` in ``WINDOWS`` the window sum
``S_m = E_k - E_(k-m) - m T b`` (``b`` the row's slowly learnt mean of ``rho``: the arm's own
model error) over its learnt RMS ``sqrt(V_m)`` (both learnt over ``LEVEL_S`` seconds, winsorised
at the threshold); alarm when any ``|z_m|`` exceeds ``z``.

    python studies/momentum_prototype.py SCENARIO.toml [--seeds 10] [--z 5 6 7]
"""

from __future__ import annotations

import argparse
import copy
from pathlib import Path

import numpy as np
from _ablation import Delegating
from numba import njit
from scipy.stats import chi2, norm

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import make_controllers
from adaptive_dd.plant.chain import body_slotine_li_regressor_in, mass_matrix_in, momentum_form_in, workspace


@njit(cache=True)
def _momentum(ch, pi, q, qd, w, a, p, wv, py, wy):
    n = q.shape[0]
    momentum_form_in(ch, pi[: 10 * n], np.int64(0), q, qd, w, a, p, wv, py, wy)
    for j in range(n):
        p[j] += pi[12 * n + j] * qd[j]
        wv[j] += pi[10 * n + j] * qd[j] + pi[11 * n + j] * np.sign(qd[j])


@njit(cache=True)
def _mass(ch, pi, q, out):
    S, n = q.shape
    w = workspace(n)
    for i in range(S):
        mass_matrix_in(ch, pi[i, : 10 * n], q[i], w, out[i])
        for j in range(n):
            out[i, j, j] += pi[i, 12 * n + j]


@njit(cache=True)
def _direction(ch, j, pmap, q, qd, qdd, out):
    """Torque per kg of a point mass at the payload frame's origin: ``Y_j(q, qd, qd, qdd) P[:, 0]``."""
    S, n = q.shape
    w, a, yb = workspace(n), np.empty((6, 10)), np.empty((n, 10))
    for i in range(S):
        body_slotine_li_regressor_in(ch, j, q[i], qd[i], qd[i], qdd, w, a, yb)
        for r in range(n):
            acc = 0.0
            for c in range(10):
                acc += yb[r, c] * pmap[c, 0]
            out[i, r] = acc


@njit(cache=True)
def _rho(ch, pi, qp, qdp, q, qd, taup, T, rho):
    S, n = q.shape
    w, aa = workspace(n), np.empty((2, 6, 10))
    p0, w0, p1, w1 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    py, wy = np.empty((n, 10)), np.empty((n, 10))
    for i in range(S):
        _momentum(ch, pi[i], qp[i], qdp[i], w, aa, p0, w0, py, wy)
        _momentum(ch, pi[i], q[i], qd[i], w, aa, p1, w1, py, wy)
        for j in range(n):
            rho[i, j] = taup[i, j] - 0.5 * (w0[j] + w1[j]) - (p1[j] - p0[j]) / T


class Recorded(Delegating):
    """adaptive_ct, its command unchanged, recording rho (S, K, n) and |qd| (S, K, n)."""

    def __init__(self, inner, K):
        self.inner, self.K, self.name = inner, K, "adaptive_ct"
        self.floor = "ct_oracle"
        self.has_detector = True

    def reset(self, n_trials, T):
        self.inner.reset(n_trials, T)
        self.T, self.k = T, 0
        self.qp = None
        self.rho = None

    def command(self, q, qd, q_d, qd_d, qdd_d, sigma_true=None):
        out = self.inner.command(q, qd, q_d, qd_d, qdd_d)
        if self.rho is None:
            S, n = q.shape
            self.rho = np.zeros((S, self.K, n))
            self.speed = np.zeros((S, self.K, n))
            self.mass = np.zeros((S, self.K, n, n))
            self.fc = np.zeros((S, self.K, n))
            self.dirs = np.zeros((S, self.K, n))
        pi = self.inner._form.state.pi_model
        if self.qp is not None and self.k < self.K:
            r = np.empty_like(q)
            _rho(self.inner.ch, pi, self.qp, self.qdp, q, qd, self.taup, self.T, r)
            self.rho[:, self.k] = r
            self.speed[:, self.k] = np.abs(qd)
            mm = np.empty((q.shape[0], q.shape[1], q.shape[1]))
            _mass(self.inner.ch, pi, q, mm)
            self.mass[:, self.k] = mm
            self.fc[:, self.k] = pi[:, 11 * q.shape[1] : 12 * q.shape[1]]
            dr = np.empty_like(q)
            arm = self.inner.arm
            pmap = np.ascontiguousarray(arm.payload_map)
            _direction(self.inner.ch, int(arm.payload_joint), pmap, q, qd, np.asarray(qdd_d, float), dr)
            self.dirs[:, self.k] = dr
        self.qp, self.qdp = q.copy(), qd.copy()
        self.k += 1
        return out

    def observe(self, q, qd, tau):
        self.inner.observe(q, qd, tau)
        self.taup = np.array(tau, dtype=float)


def record(path: str, seeds: int):
    d = copy.deepcopy(read_toml(Path(path)))
    d["run"]["seeds"] = seeds
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    sc = parse_scenario(d, path, Path(path).stem)
    K = round(sc.duration / sc.sample_period) + 2
    rec = Recorded(make_controllers(sc)["adaptive_ct"], K)
    res = run_benchmark(sc, controllers={"adaptive_ct": rec}, progress=False, keep_trajectories=0)
    return sc, rec, res


WINDOWS = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32)
LEVEL_S = 1.0
WARMUP_S = 2.0
FA_AFTER = 0.0  # [s] after the warm-up: crossings counted as false from then


@njit(cache=True)
def momentum_test(rho, mass, fc, speed, dirs, T, windows, zcap, alpha, warmup, whiten, combine, v_slow):
    """Per sample the test statistic (S, K): the largest over windows of ``|u_j| / rms_j`` (the
    largest row) or ``sqrt(sum_j u_j^2 / V_j)`` (``combine``), ``u = M^-1 S_m`` (``whiten``; else
    ``S_m``), ``S_m`` the window sum of rho less the learnt drift; a sample whose joint is at most
    ``v_slow`` adds ``2 fc T`` to the row's allowance (the window sum soft-thresholded by it)."""
    S, K, n = rho.shape
    W = windows.shape[0]
    mx = np.max(windows)
    out = np.zeros((S, K))
    sm = np.zeros(n)
    for s in range(S):
        E = np.zeros((K + 1, n))
        A = np.zeros((K + 1, n))  # the Coulomb allowance, integrated
        D = np.zeros((K + 1, n))  # the payload's direction, integrated
        b = np.zeros(n)
        V = np.zeros((W, n))
        for k in range(K):
            for j in range(n):
                E[k + 1, j] = E[k, j] + T * rho[s, k, j]
                D[k + 1, j] = D[k, j] + T * dirs[s, k, j]
                A[k + 1, j] = A[k, j] + (2.0 * abs(fc[s, k, j]) * T if speed[s, k, j] <= v_slow else 0.0)
            c = k + 1.0
            bias = 1.0 - (1.0 - alpha) ** c
            best = 0.0
            Minv = np.linalg.inv(mass[s, k]) if (whiten and mass[s, k, 0, 0] > 0) else np.eye(n)
            for w in range(W):
                m = windows[w]
                if k + 1 - m < 0:
                    continue
                for j in range(n):
                    sm[j] = E[k + 1, j] - E[k + 1 - m, j] - m * T * b[j]
                u = Minv @ sm
                # a slow joint's Coulomb torque is known only within +-fc: remove from u the
                # friction torques within that allowance that explain it best (metric 1 / V)
                for _ in range(3):
                    for j in range(n):
                        al = A[k + 1, j] - A[k + 1 - m, j]
                        if al <= 0.0 or c <= warmup:
                            continue
                        num, den = 0.0, 0.0
                        for i in range(n):
                            wi = bias / V[w, i]
                            num += Minv[i, j] * wi * u[i]
                            den += Minv[i, j] * Minv[i, j] * wi
                        cj = min(max(num / den, -al), al)
                        for i in range(n):
                            u[i] -= Minv[i, j] * cj
                clean = True
                for j in range(n):
                    clean = clean and A[k + 1, j] == A[k + 1 - m, j]
                tot = 0.0
                for j in range(n):
                    if c > warmup:
                        zz = u[j] * u[j] / (V[w, j] / bias)
                        tot += zz
                        if combine == 0 and zz > best:
                            best = zz
                        s2 = min(u[j] * u[j], zcap * zcap * V[w, j] / bias)
                    else:
                        s2 = u[j] * u[j]
                    if clean or c <= warmup:
                        V[w, j] += alpha * (s2 - V[w, j])
                if combine == 1 and tot > best:
                    best = tot
                if combine == 2 and c > warmup:  # along the payload's mass direction
                    for j in range(n):
                        sm[j] = D[k + 1, j] - D[k + 1 - m, j]
                    g = Minv @ sm
                    num, den = 0.0, 0.0
                    for j in range(n):
                        num += g[j] * u[j] * bias / V[w, j]
                        den += g[j] * g[j] * bias / V[w, j]
                    if den > 0.0 and num * num / den > best:
                        best = num * num / den
            if k >= mx:
                for j in range(n):
                    b[j] += alpha * (rho[s, k, j] - b[j])
            out[s, k] = np.sqrt(best)
    return out


def delays(stat, z, swaps, T, alarm_times):
    S, K = stat.shape
    res = []
    for s in range(S):
        above = np.flatnonzero(stat[s] > z)
        ts = above * T + T  # sample k is the residual at time (k+1) T
        row = []
        for sw in swaps:
            hit = ts[(ts >= sw) & (ts < sw + FALSE_ALARM_WINDOW)]
            row.append(hit[0] - sw if hit.size else np.nan)
        inside = np.zeros(ts.shape, bool)
        for sw in swaps:
            inside |= (ts >= sw - 0.002) & (ts < sw + 1.0)
        fa = ts[(~inside) & (ts > WARMUP_S + FA_AFTER) & (ts < (K - 3) * T)]  # the last rows: not recorded
        det = []
        for sw in swaps:
            t = [x - sw for x in alarm_times[s] if 0 <= x - sw < FALSE_ALARM_WINDOW]
            det.append(min(t) if t else np.nan)
        res.append((row, fa, det))
    return res


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--z", type=float, nargs="+", default=None)
    ap.add_argument("--save", default=None)
    ap.add_argument("--load", default=None)
    ap.add_argument("--modes", nargs="+", default=["raw", "white", "white_slow", "chi_slow"])
    ap.add_argument("--v-slow", type=float, default=0.25)
    ap.add_argument("--diag", type=int, default=0)
    a = ap.parse_args()
    if a.load:
        f = dict(np.load(a.load, allow_pickle=True))
        f["alarms"] = list(f["alarms"])
    else:
        sc, rec, _ = record(a.scenario, a.seeds)
        f = dict(
            rho=rec.rho, speed=rec.speed, mass=rec.mass, fc=rec.fc, dirs=rec.dirs, T=sc.sample_period,
            swaps=np.array(sc.swap_times), alarms=rec.inner.alarm_times,
        )  # fmt: skip
        if a.save:
            np.savez(a.save, **{k: (np.array(v, dtype=object) if k == "alarms" else v) for k, v in f.items()})
    rho, T, swaps, at = f["rho"], float(f["T"]), list(f["swaps"]), f["alarms"]
    S, _, n = rho.shape
    tests = len(WINDOWS) * 60 / T
    zd = norm.ppf(1 - 0.01 / (2 * n * tests))
    cd = float(np.sqrt(chi2.ppf(1 - 0.01 / tests, n)))
    alpha = T / LEVEL_S
    print(f"{a.scenario}: {S} seeds, n {n}; derived z {zd:.2f} (row), {cd:.2f} (chi, {n} dof)")
    for mode in a.modes:
        whiten = mode != "raw"
        combine = 1 if mode.startswith("chi") else (2 if mode.startswith("dir") else 0)
        v_slow = a.v_slow if mode.endswith("slow") else -1.0
        z0 = cd if combine == 1 else (float(norm.isf(0.01 / (2 * tests))) if combine == 2 else zd)
        stat = momentum_test(
            rho, f["mass"], f["fc"], f["speed"], f["dirs"], T, np.array(WINDOWS), z0, alpha,
            round(WARMUP_S / T),
            whiten, combine, v_slow,
        )  # fmt: skip
        for z in a.z or [z0]:
            r = delays(stat, z, swaps, T, at)
            dl = np.array([x[0] for x in r]) * 1e3
            det = np.array([x[2] for x in r]) * 1e3
            nfa = sum(len(x[1]) > 0 for x in r)
            print(
                f"{mode:11s} z {z:.2f}: delay median {np.nanmedian(dl, 0)} max {np.nanmax(dl, 0)} "
                f"missed {int(np.isnan(dl).sum())}; detector {np.nanmedian(det, 0)}; "
                f"false-alarm trials {nfa}",
                flush=True,
            )
            for s, x in enumerate(r[: a.diag]):
                for t in x[1][:4]:
                    k = round(t / T) - 1
                    print(f"   seed {s} t {t:.3f} speeds {np.round(f['speed'][s, k], 3)}")


if __name__ == "__main__":
    main()
