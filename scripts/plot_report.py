#!/usr/bin/python3
"""Pictures of a comparison report (coarsegrain demo, coarsegrain coarsen --method a,b,...).

Usage: /usr/bin/python3 scripts/plot_report.py report_data.json

Reads report_data.json (written by the coarsegrain CLI next to report.md) and writes, in the
current folder:
- deformed.png: the fine solution and every method's solution on the fine mesh's surface
  (3D: boundary faces; 2D: all elements), displaced by one magnification factor, coloured by
  |u| on one scale, seen by one camera;
- methods.png: energy and l2 errors (log scale) and the speedup of each method.
"""
import json
import math
import sys

import numpy as np


def fail(message):
    sys.exit(f"plot_report: {message}")


def read(path):
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"cannot read {path}: {e}")
    for key in ("dimension", "points", "faces", "fine", "methods"):
        if key not in data:
            fail(f"{path}: missing key '{key}'")
    points = np.asarray(data["points"], dtype=float)
    faces = np.asarray(data["faces"], dtype=int)
    dim = data["dimension"]
    if points.ndim != 2 or points.shape[1] != dim or faces.ndim != 2:
        fail(f"{path}: points must be N x {dim} and faces F x k")
    if faces.size and (faces.min() < 0 or faces.max() >= len(points)):
        fail(f"{path}: a face refers to a point that does not exist")
    panels = [("fine", data["fine"])] + [(m["method"], m) for m in data["methods"]]
    for name, p in panels:
        u = np.asarray(p["u"], dtype=float)
        if u.shape != points.shape:
            fail(f"{path}: '{name}' has {u.shape} displacements for {points.shape} points")
        p["u"] = u
    return data, points, faces, panels


def magnification(points, u_fine):
    """Factor that makes the largest fine displacement a tenth of the object's diagonal."""
    diagonal = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    largest = np.linalg.norm(u_fine, axis=1).max()
    return 1.0 if largest == 0 else max(1.0, 0.1 * diagonal / largest)


def deformed(data, points, faces, panels, out):
    import matplotlib.pyplot as plt
    from matplotlib import cm, colors
    from matplotlib.collections import PolyCollection
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    dim = data["dimension"]
    fine_u = panels[0][1]["u"]
    scale = magnification(points, fine_u)
    norm = colors.Normalize(0.0, np.linalg.norm(fine_u, axis=1).max())
    cmap = plt.get_cmap("viridis")
    moved = [points + scale * p["u"] for _, p in panels]
    lo = np.min([m.min(axis=0) for m in moved], axis=0)
    hi = np.max([m.max(axis=0) for m in moved], axis=0)
    extent = np.maximum(hi - lo, 1e-12 * np.max(hi - lo))

    cols = min(4, len(panels))
    rows = math.ceil(len(panels) / cols)
    fig = plt.figure(figsize=(4.2 * cols, 3.6 * rows))
    for i, ((name, p), xyz) in enumerate(zip(panels, moved)):
        face_u = np.linalg.norm(p["u"], axis=1)[faces].mean(axis=1)
        title = name if name == "fine" else f"{name}\nl2 error {p['errors']['l2_rel']:.3f}"
        if dim == 3:
            ax = fig.add_subplot(rows, cols, i + 1, projection="3d")
            ax.add_collection3d(
                Poly3DCollection(xyz[faces], facecolors=cmap(norm(face_u)), edgecolors="none")
            )
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            ax.set_zlim(lo[2], hi[2])
            ax.set_box_aspect(extent)
            ax.view_init(elev=20, azim=-70)
        else:
            ax = fig.add_subplot(rows, cols, i + 1)
            ax.add_collection(
                PolyCollection(xyz[faces], array=face_u, cmap=cmap, norm=norm, edgecolors="none")
            )
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            ax.set_aspect("equal")
        ax.set_axis_off()
        ax.set_title(title, fontsize=10)
    fig.suptitle(f"{data.get('scene', '')}: displacement magnified x{scale:.3g}", fontsize=11)
    fig.colorbar(
        cm.ScalarMappable(norm=norm, cmap=cmap),
        ax=fig.axes,
        shrink=0.6,
        extend="max",
        label="|u| (scale of the fine solution)",
    )
    fig.savefig(out, dpi=110)
    plt.close(fig)


def methods(data, out):
    import matplotlib.pyplot as plt

    rows = data["methods"]
    names = [m["method"] for m in rows]
    y = np.arange(len(rows))
    floor = 1e-6  # log axes cannot show 0
    energy = [max(m["errors"]["energy_rel"], floor) for m in rows]
    l2 = [max(m["errors"]["l2_rel"], floor) for m in rows]
    speedup = [max(m["speedup"], floor) for m in rows]

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 0.5 * len(rows) + 1.8), sharey=True)
    left.barh(y - 0.2, energy, height=0.4, label="energy error")
    left.barh(y + 0.2, l2, height=0.4, label="l2 error")
    left.set_xscale("log")
    left.set_yticks(y, names)
    left.invert_yaxis()
    floored = any(m["errors"]["energy_rel"] < floor or m["errors"]["l2_rel"] < floor for m in rows)
    left.set_xlabel("relative error against the fine solution"
                    + (f" (errors below {floor:g} drawn at {floor:g})" if floored else ""))
    left.legend(loc="lower right", fontsize=8)
    right.barh(y, speedup, color="tab:green")
    right.set_xscale("log")
    right.axvline(1.0, color="gray", linewidth=0.8)
    right.set_xlabel(f"speedup of the solve over the fine one ({data['fine']['solve_seconds']:.2f} s)")
    for yi, s in zip(y, speedup):
        right.text(s, yi, f" {s:.0f}x", va="center", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main(argv):
    if len(argv) != 1:
        sys.exit(__doc__)
    data, points, faces, panels = read(argv[0])
    # Imported only once the input is known to be good: a bad file fails fast.
    import matplotlib

    matplotlib.use("Agg")
    deformed(data, points, faces, panels, "deformed.png")
    methods(data, "methods.png")


if __name__ == "__main__":
    main(sys.argv[1:])
