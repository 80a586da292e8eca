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
    image = plt.imread(res.heatmaps[0])

# %%
# One row per grid point x controller x seed x segment in ``res.table``; the heat map's cells:
print(ratios.to_string(index=False))

fig, ax = plt.subplots(figsize=(6, 4.5))
ax.imshow(image)
ax.set_axis_off()
fig.suptitle(
    "Heat map of the sweep: median ratio of adaptive_ct's RMS error to ct_oracle's\n"
    "per payload mass [kg] and swap time [s]",
    fontsize=8,
    wrap=True,
)
