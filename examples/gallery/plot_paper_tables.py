"""
The paper's Tables 3 and 5
==========================

The paper's open-loop experiment (Table 2 torques, Table 4 sensor noise, 10 s at 1 kHz) and
its estimator (filtered regression, RLS with split 15) for the two derivative filters: M1
differentiates the measured position (Table 3), M2 filters the measured velocity (Table 5).
Here with 3 seeds and three filter time constants; ``adaptive-dd reproduce`` runs 10 seeds on
the paper's whole grid and prints the same comparison (read on :doc:`../results`).
"""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from adaptive_dd.identification.reproduce import paper_comparison, run_reproduce

res = run_reproduce(seeds=3, tau_f=(0.004, 0.01, 0.02), estimators=("paper",), splits=("15",), progress=False)

# %%
# Mean absolute error of each parameter over the seeds, in % of its true value, against the
# paper's, per filter time constant: ``ratio = ours / paper``.
tables = {m: pd.DataFrame(paper_comparison(res, m)) for m in ("M1", "M2")}
for m, df in tables.items():
    print(f"{m}:")
    print(df.pivot(index="param", columns="tau_f", values="ratio").round(2).to_string())

# %%
# Table 3 (M1) is reproduced; Table 5 (M2) in kind only. Not because of the velocity's noise: with
# noise-free sensors M2 stays where it is. The departure is M2's own on our experiment and moves
# with choices the paper does not state (how the held torque is paired with a sample, how the
# plant sticks at rest): see the results page.
fig, axes = plt.subplots(1, 2, figsize=(9, 4), sharey=True)
for ax, (m, df) in zip(axes, tables.items(), strict=True):
    sub = df[np.isclose(df["tau_f"], 0.01)]
    x = np.arange(len(sub))
    ax.bar(x - 0.2, sub["ours_pct"], 0.4, label="ours")
    ax.bar(x + 0.2, sub["paper_pct"], 0.4, label="paper")
    ax.set_xticks(x, sub["param"])
    ax.set_yscale("log")
    ax.set_title(f"{m}, tau_f = 0.01 s")
    ax.set_xlabel("base parameter")
axes[0].set_ylabel("mean |error| [%]")
fig.suptitle(
    "Mean estimation error [%] per base parameter, ours against the paper's Tables 3 (M1) and 5 (M2)",
    fontsize=9,
)
axes[0].legend()
fig.tight_layout()

# %%
# The ratio of our error to the paper's for each parameter against the filter time constant:
# 1 is the paper's value; Table 3 (M1) stays near it, Table 5 (M2) departs from 4 ms on.
fig, axes = plt.subplots(1, 2, figsize=(9, 3.8), sharey=True)
for ax, (m, df) in zip(axes, tables.items(), strict=True):
    wide = df.pivot(index="tau_f", columns="param", values="ratio")
    for name in wide.columns:
        ax.plot(1e3 * wide.index, wide[name], "o-", ms=3, label=name)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_yscale("log")
    ax.set_xlabel("filter time constant tau_f [ms]")
    ax.set_title(f"{m}: our mean |error| / the paper's", fontsize=9)
axes[0].set_ylabel("ratio to the paper's error [-]")
axes[1].legend(fontsize=7, ncol=2)
fig.suptitle(
    "Ratio of our mean estimation error to the paper's [-] per base parameter against tau_f [ms]", fontsize=9
)
fig.tight_layout()
