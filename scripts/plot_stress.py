#!/usr/bin/python3
"""Plots the fine stress and the coarsest level's stress of a 2D hierarchy (Chen et al. 2019,
Fig. 16).

Usage: /usr/bin/python3 scripts/plot_stress.py OUT.png STRESS.csv

STRESS.csv is written by `coarsegrain coarsen --method mra` on a 2D grid (coarsest_stress.csv):
one row per fine element with columns x, y (centroid), area, E (Young's modulus), fine_xx, fine_yy, fine_xy,
fine_von_mises, coarse_xx, coarse_yy, coarse_xy, coarse_von_mises (physical stress components;
"coarse" is the coarsest level's solve reconstructed on the fine grid). OUT.png has three
panels on one logarithmic colour scale: the von Mises stress of the fine solve, that of the
coarsest level, and the Frobenius norm of their stress difference per element. The title gives
the relative L2 stress error ||s_c - s|| / ||s|| (area-weighted), the summary's `stress_rel`,
and the same over the softest material alone (the elements of the smallest E), if E varies.
"""
import sys

import numpy as np
from plot_csv import read_table

REQUIRED = ["x", "y", "area", "E"] + [
    f"{which}_{c}" for which in ("fine", "coarse") for c in ("xx", "yy", "xy", "von_mises")
]


def read_csv(path):
    header, data = read_table(path, "plot_stress", REQUIRED)
    return {name: data[:, i] for i, name in enumerate(header)}


def frobenius(xx, yy, xy):
    return np.sqrt(xx**2 + yy**2 + 2 * xy**2)


def rel_error(area, s, diff):
    norm = np.sqrt(np.sum(area * s**2))
    return np.sqrt(np.sum(area * diff**2)) / norm if norm > 0 else float("nan")


def draw(ax, col, values, norm, title):
    """Cell values as an image when the centroids fill a regular grid, else as a triangulation."""
    xs, ys = np.unique(col["x"]), np.unique(col["y"])
    if len(xs) * len(ys) == len(values):
        image = np.empty((len(ys), len(xs)))
        image[np.searchsorted(ys, col["y"]), np.searchsorted(xs, col["x"])] = values
        extent = [1.5 * xs[0] - 0.5 * xs[1], 1.5 * xs[-1] - 0.5 * xs[-2],
                  1.5 * ys[0] - 0.5 * ys[1], 1.5 * ys[-1] - 0.5 * ys[-2]]
        artist = ax.imshow(image, origin="lower", extent=extent, norm=norm, cmap="inferno")
    else:
        artist = ax.tripcolor(col["x"], col["y"], values, norm=norm, cmap="inferno")
    ax.set_title(title, fontsize="medium")
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    return artist


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    out, path = argv
    col = read_csv(path)
    s = frobenius(col["fine_xx"], col["fine_yy"], col["fine_xy"])
    diff = frobenius(col["coarse_xx"] - col["fine_xx"], col["coarse_yy"] - col["fine_yy"],
                     col["coarse_xy"] - col["fine_xy"])
    error = rel_error(col["area"], s, diff)
    title = f"Stress on the fine grid: relative L2 stress error of the coarsest level {error:.3g}"
    soft = col["E"] == np.min(col["E"])
    if not np.all(soft):
        soft_error = rel_error(col["area"][soft], s[soft], diff[soft])
        title += f", {soft_error:.3g} in the softest material (E = {np.min(col['E']):g})"

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    panels = [(col["fine_von_mises"], "fine solve: von Mises"),
              (col["coarse_von_mises"], "coarsest level: von Mises"),
              (diff, "|stress difference|")]
    top = max(np.max(v) for v, _ in panels)
    if not top > 0:
        sys.exit(f"plot_stress: {path}: the stress is zero everywhere")
    norm = LogNorm(vmin=top * 1e-6, vmax=top, clip=True)
    fig, axes = plt.subplots(1, 3, figsize=(12, 4), layout="constrained")
    for ax, (values, label) in zip(axes, panels):
        artist = draw(ax, col, np.maximum(values, top * 1e-12), norm, label)
    fig.colorbar(artist, ax=axes, shrink=0.8, label="stress")
    fig.suptitle(title)
    fig.savefig(out, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1:])
