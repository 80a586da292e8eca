"""
A sweep's heat map
==================

``adaptive-dd sweep`` runs a grid over scenario fields x controllers x seeds on Dask and draws
the median per-seed ratio of an adaptive controller to its floor. Here a tiny grid (2 payload
masses x 2 swap times, 2 seeds) on an in-process Dask client; the example sweep
``benchmarks/sweeps/payload_mass_swap_time.toml`` is 5 x 5 on a local cluster.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from distributed import Client

import adaptive_dd
from adaptive_dd.sweep import ratio_medians, run_sweep
from adaptive_dd.sweep_spec import parse_sweep

sweeps = Path(adaptive_dd.__file__).parent.parent / "benchmarks" / "sweeps"
spec = {
    "sweep": {
        "scenario": "short_swap.toml",  # 5 s, the payload appears at the tip mid-run
        "seeds": 2,
        "block": 2,
        "controllers": ["ct_oracle", "adaptive_ct"],
        "swap": 0,
    },
    "grid": {"payload_mass": [1.0, 5.0], "swap_time": [2.0, 3.0]},
    "heatmap": {
        "x": "payload_mass",
        "y": "swap_time",
        "adaptive": "adaptive_ct",
        "floor": "ct_oracle",
        "segment": 1,
    },
}
sweep = parse_sweep(spec, "tiny_sweep", base_dir=sweeps)

with (
    tempfile.TemporaryDirectory() as out,
    Client(processes=False, n_workers=1, threads_per_worker=1) as client,
):
    res = run_sweep(sweep, out, client=client, progress=False)
    ratios = ratio_medians(res.table, sweep.heatmap, [a for a, _ in sweep.axes])

# %%
# One row per grid point x controller x seed x segment in ``res.table``; the heat map's cells,
# the median over the seeds of ``adaptive_ct``'s RMS error over ``ct_oracle``'s after the swap:
print(ratios.to_string(index=False))

# %%
# The same cells drawn with their axes' units (``adaptive-dd sweep`` writes this figure as
# ``heatmap.png``, one per combination of the grid's other axes):
grid = ratios.pivot(index="swap_time", columns="payload_mass", values="ratio")
fig, ax = plt.subplots(figsize=(5.5, 4))
mesh = ax.imshow(grid.to_numpy(), origin="lower", cmap="viridis", aspect="auto")
ax.set_xticks(range(grid.shape[1]), [f"{m:g}" for m in grid.columns])
ax.set_yticks(range(grid.shape[0]), [f"{t:g}" for t in grid.index])
middle = np.nanmean([np.nanmin(grid.to_numpy()), np.nanmax(grid.to_numpy())])
for (i, j), r in np.ndenumerate(grid.to_numpy()):
    ax.text(j, i, f"{r:.3f}", ha="center", va="center", color="k" if r > middle else "w", fontsize=9)
ax.set_xlabel("payload mass [kg]")
ax.set_ylabel("swap time [s]")
fig.colorbar(mesh, label="median RMS error ratio, adaptive_ct / ct_oracle [-]")
ax.set_title(
    "Median ratio of adaptive_ct's RMS tracking error to ct_oracle's [-]\n"
    "per payload mass [kg] and swap time [s], 2 seeds",
    fontsize=8,
)
fig.tight_layout()
