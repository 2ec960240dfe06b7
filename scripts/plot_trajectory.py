#!/usr/bin/python3
"""Plots probe displacements against time, the fine model and every method (Chen et al. 2019,
Fig. 18: a wing tip tracked over time, fine against coarse).

Usage: /usr/bin/python3 scripts/plot_trajectory.py OUT.png TRAJECTORY.csv

TRAJECTORY.csv is written by `coarsegrain simulate` (trajectory.csv): a column "time", then
<model>_p<probe>_<axis> for the model "fine" and each method, one row per saved time. One panel
per probe shows the component with the largest fine amplitude.
"""
import re
import sys

import numpy as np
from plot_csv import read_table


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    out, path = argv
    header, data = read_table(path, "plot_trajectory", ("time",))
    if header[0] != "time":
        sys.exit(f"plot_trajectory: {path}: the first column must be 'time'")
    columns = {}
    for i, name in enumerate(header[1:], start=1):
        m = re.fullmatch(r"(.+)_p(\d+)_([xyz])", name)
        if not m:
            sys.exit(f"plot_trajectory: {path}: unexpected column '{name}'")
        columns[(m.group(1), int(m.group(2)), m.group(3))] = data[:, i]
    models = list(dict.fromkeys(model for model, _, _ in columns))
    if "fine" not in models:
        sys.exit(f"plot_trajectory: {path}: no 'fine' columns")
    probes = sorted({p for _, p, _ in columns})
    time = data[:, 0]

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(probes), 1, figsize=(9, 2.6 * len(probes)), squeeze=False,
                             sharex=True)
    for ax, p in zip(axes[:, 0], probes):
        axis = max("xyz", key=lambda a: np.ptp(columns.get(("fine", p, a), np.zeros(1))))
        for model in models:
            style = {"color": "black", "linewidth": 2.2} if model == "fine" else {"linewidth": 1.2}
            ax.plot(time, columns[(model, p, axis)], label=model, **style)
        ax.set_ylabel(f"probe {p}: u_{axis}")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[-1, 0].set_xlabel("time")
    fig.suptitle("probe displacement over time: fine (black) and coarse models")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1:])
