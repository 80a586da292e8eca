"""Prototype (offline): the momentum test against the residual's own recent rate instead of its
1 s mean. Replays records saved by ``studies/momentum_fa_trace.py --save`` (adaptive_ct's own
closed loop: ``rho``, ``M``, the model's Coulomb friction, the measured speeds) through the shipped
test's arithmetic (windows, whitening, the friction allowances of ``residual_observer._friction_allowance``,
levels learnt on windows without allowance) with one change: a window's sum ``S_w = E_k -
E_(k-w)`` less ``w / L`` times the sum over the ``L`` samples before it (``--ref L``; 0: less ``w``
times the 1 s mean, the shipped test). A payload's step is the same in both; a friction error that
drifts with the speed (a learnt friction law other than the plant's) is removed by the recent rate.

    python studies/momentum_detrend.py RECORD.npz [...] [--ref 0 32 64]
"""

from __future__ import annotations

import argparse

import numpy as np
from numba import njit
from scipy.stats import chi2, norm

from adaptive_dd.closed_loop.residual_observer import M_WINDOWS


@njit(cache=True)
def _allow(ql, qn, fc, slow, creep, margin):
    lo = min(abs(ql), abs(qn))
    if lo <= slow or ql * qn <= 0.0:
        return 2.0 * fc
    if lo <= creep:
        return margin * fc * (creep - lo) / (creep - slow)
    return 0.0


@njit(cache=True)
def detrended(rho, mass, fc, qd, T, windows, z, alpha, warm, slow, creep, margin, ref):
    """Per sample the statistic ``(K,)`` of one trial."""
    K, n = rho.shape
    W = windows.shape[0]
    E = np.zeros(K + 1 + 0 * n)
    E = np.zeros((K + 1, n))
    A = np.zeros((K + 1, n))
    V = np.zeros((W, n))
    b = np.zeros(n)
    out = np.zeros(K)
    sm = np.zeros(n)
    u = np.zeros(n)
    z2 = z * z
    mx = np.max(windows)
    for k in range(1, K):
        if mass[k, 0, 0] == 0.0:
            continue
        minv = np.linalg.inv(mass[k])
        for j in range(n):
            E[k + 1, j] = E[k, j] + T * (rho[k, j] - (b[j] if ref == 0 else 0.0))
            A[k + 1, j] = A[k, j] + T * _allow(qd[k - 1, j], qd[k, j], abs(fc[k, j]), slow, creep, margin)
        c = k + 1.0
        armed = c > warm
        bias = 1.0 - (1.0 - alpha) ** c
        bias0 = 1.0 - (1.0 - alpha) ** (c - 1.0)
        best = 0.0
        for w in range(W):
            m = windows[w]
            if k + 1 - m - ref < 0:
                continue
            r = m / ref if ref > 0 else 0.0
            clean = True
            al = np.zeros(n)
            for j in range(n):
                sm[j] = E[k + 1, j] - E[k + 1 - m, j]
                al[j] = A[k + 1, j] - A[k + 1 - m, j]
                if ref > 0:
                    sm[j] -= r * (E[k + 1 - m, j] - E[k + 1 - m - ref, j])
                    al[j] += r * (A[k + 1 - m, j] - A[k + 1 - m - ref, j])
                clean = clean and al[j] == 0.0
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += minv[i, j] * sm[j]
                u[i] = acc
            v = V[w]
            learnt = True
            raw = u * u
            for i in range(n):
                learnt = learnt and v[i] > 0.0
            if armed and learnt and not clean:
                for _ in range(3):
                    for j in range(n):
                        if al[j] <= 0.0:
                            continue
                        num, den = 0.0, 0.0
                        for i in range(n):
                            wi = bias / v[i]
                            num += minv[i, j] * wi * u[i]
                            den += minv[i, j] * minv[i, j] * wi
                        cj = min(max(num / den, -al[j]), al[j]) if den > 0.0 else 0.0
                        for i in range(n):
                            u[i] -= minv[i, j] * cj
            tot = 0.0
            for i in range(n):
                if armed and learnt:
                    tot += u[i] * u[i] * bias / v[i]
                if clean:
                    x = min(raw[i], z2 * v[i] / bias) if armed and learnt else raw[i]
                else:
                    x = v[i] / bias0 if bias0 > 0.0 else 0.0
                v[i] += alpha * (x - v[i])
            if tot > best:
                best = tot
        if k > mx:
            for j in range(n):
                b[j] += alpha * (rho[k, j] - b[j])
        out[k] = np.sqrt(best)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("records", nargs="+")
    ap.add_argument("--ref", type=int, nargs="+", default=[0, 32, 64])
    a = ap.parse_args()
    for path in a.records:
        f = np.load(path, allow_pickle=True)
        cfg = f["cfg"].item()
        rho, T, swaps = f["rho"], float(f["T"]), list(f["swaps"])
        S, K, n = rho.shape
        tests = len(M_WINDOWS) * 60 / T
        z = float(np.sqrt(chi2.isf(0.01 / tests, n)))
        slow = float(norm.isf(0.01 / (n * 60 / T))) * float(np.sqrt(5e-5))
        for ref in a.ref:
            fa, first = 0, np.full((S, len(swaps)), np.nan)
            for s in range(S):
                st = detrended(
                    rho[s, : K - 2], f["mass"][s], f["fc"][s], f["qd"][s], T, np.array(M_WINDOWS), z,
                    cfg["obs_alpha"], round(2.0 / T), slow, 0.25, 0.5, ref,
                )  # fmt: skip
                ts = (np.flatnonzero(st > z) + 1) * T
                inside = np.zeros(ts.shape, bool)
                for i, sw in enumerate(swaps):
                    hit = ts[(ts >= sw) & (ts < sw + 1.0)]
                    first[s, i] = hit[0] - sw if hit.size else np.nan
                    inside |= (ts >= sw - 0.002) & (ts < sw + 1.0)
                fa += bool((~inside).any())
            d = 1e3 * first
            cells = " / ".join(
                f"{np.nanmedian(c):.0f} ({np.nanmax(c):.0f})" if np.isfinite(c).any() else "-" for c in d.T
            )
            print(
                f"{path} ref {ref}: trials with a false crossing {fa} of {S}; first crossing after each "
                f"swap, median (max) [ms] {cells}; none within 1 s {int(np.isnan(d).sum())}",
                flush=True,
            )


if __name__ == "__main__":
    main()
