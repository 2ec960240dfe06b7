#!/usr/bin/python3
"""Plots the directional Young's modulus of coarsest cells (Chen et al. 2019, Fig. 17).

Usage: /usr/bin/python3 scripts/plot_youngs.py OUT.png CELLS.csv

CELLS.csv is written by `coarsegrain coarsen --method mra` (coarsest_youngs.csv): columns cell,
dx, dy[, dz], E, one row per cell and sampled direction d (unit). In 2D each cell is a closed
polar curve E(d) (d and -d give the same E); in 3D E is plotted against the direction index.
"""
import sys

import numpy as np
from plot_csv import read_table


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    out, path = argv
    header, data = read_table(path, "plot_youngs", ("cell", "dx", "dy", "E"))
    col = {name: data[:, i] for i, name in enumerate(header)}
    three_d = "dz" in col

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cells = np.unique(col["cell"]).astype(int)
    if three_d:
        fig, ax = plt.subplots(figsize=(5, 4))
    else:
        fig, ax = plt.subplots(figsize=(5, 5), subplot_kw={"projection": "polar"})
    for c in cells:
        rows = col["cell"] == c
        E = col["E"][rows]
        if three_d:
            ax.plot(np.arange(len(E)), E, "o-", label=f"cell {c}")
        else:
            angle = np.arctan2(col["dy"][rows], col["dx"][rows])
            angle = np.concatenate([angle, angle + np.pi, angle[:1]])
            ax.plot(angle, np.concatenate([E, E, E[:1]]), label=f"cell {c}")
    if three_d:
        ax.set_xlabel("direction (axes, face diagonals, body diagonals)")
        ax.set_ylabel("E(d)")
    ax.set_title("Directional Young's modulus of the coarsest cells")
    if len(cells) <= 8:
        ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1:])
