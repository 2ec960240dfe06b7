#!/usr/bin/python3
"""The demo's layered beam built in NumPy, coarsened with the effective tensors, and the
effective Young's modulus of every coarse element plotted along the beam.

The fine mesh (a hex grid of the 4 x 1 x 1 beam) and one elasticity tensor per element
(isotropic, stiff E = 1e7 and soft E = 1e4 layers 0.25 thick across the axis) are NumPy arrays;
the coarse mesh, conditions and load are the scene keys of `coarsegrain demo`. Writes
effective_young.png and result.json (the errors and the effective moduli) into --out.

    /usr/bin/python3 examples/python_layered_beam/layered_beam.py --out out/python_beam
"""
import argparse
import json
import pathlib

import numpy as np

import coarsegrain as cg

E_STIFF, NU_STIFF, E_SOFT, NU_SOFT = 1e7, 0.3, 1e4, 0.45
LENGTH, LAYER = 4.0, 0.25


def hex_grid(cells, size):
    """Nodes (#V x 3) and hexes (#E x 8, VTK ordering) of a box [0, size] with cells per axis."""
    nx, ny, nz = cells
    axes = [np.linspace(0, s, n + 1) for s, n in zip(size, cells)]
    x, y, z = np.meshgrid(*axes, indexing="ij")
    nodes = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    index = np.arange(len(nodes)).reshape(nx + 1, ny + 1, nz + 1)
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    corner = lambda a, b, c: index[i + a, j + b, k + c]  # noqa: E731
    elements = np.column_stack([corner(0, 0, 0), corner(1, 0, 0), corner(1, 1, 0),
                                corner(0, 1, 0), corner(0, 0, 1), corner(1, 0, 1),
                                corner(1, 1, 1), corner(0, 1, 1)])
    return nodes, elements


def isotropic_mandel(E, nu):
    """The 6 x 6 Mandel tensor of an isotropic material: lambda 1⊗1 + 2 mu I."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = 2 * mu * np.eye(6)
    C[:3, :3] += lam
    return C


def layered_beam(scale=1.0):
    """The scene dict: the demo beam's fine mesh and per-element tensors as arrays."""
    b = max(1, round(3 * scale))
    cells = (16 * b, 4 * b, 4 * b)
    nodes, elements = hex_grid(cells, (LENGTH, 1.0, 1.0))
    centre_x = nodes[elements, 0].mean(axis=1)
    stiff = (np.floor(centre_x / LAYER).astype(int) % 2) == 0
    C = np.where(stiff[:, None, None], isotropic_mandel(E_STIFF, NU_STIFF),
                 isotropic_mandel(E_SOFT, NU_SOFT))
    return {
        "mesh": {"nodes": nodes, "elements": elements, "C_mandel": C, "density": 1.0},
        "dirichlet": [{"box": {"min": [-1e-9, -1, -1], "max": [1e-9, 2, 2]}}],
        "loads": {"gravity": [0, 0, -9.81]},
        "coarse": {"mesh": {"grid": {"min": [0, 0, 0], "max": [LENGTH, 1, 1],
                                     "cells": [c // 4 for c in cells], "element": "tet"}}},
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="out/python_layered_beam")
    parser.add_argument("--scale", type=float, default=1.0,
                        help="1: the demo's 48x12x12 hexes; 0.25: 16x4x4")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    scene = cg.scene_from_dict(layered_beam(args.scale), source="layered_beam.py")
    result = cg.coarsen(scene, "effective-tensor")
    model = result.coarse_model
    C = model.element_tensors()  # #coarse elements x 6 x 6, Mandel
    centre = model.nodes[model.elements].mean(axis=1)
    young = {axis: np.array([cg.directional_young(c, d) for c in C])
             for axis, d in (("x", [1, 0, 0]), ("y", [0, 1, 0]), ("z", [0, 0, 1]))}
    # reference lines: the arithmetic (Voigt) and harmonic (Reuss) means of the two moduli in
    # equal parts. A coarse element's effective tensor is no homogenized laminate (it makes the
    # element's few DOFs respond like the fine region under it) and may leave this range.
    voigt, reuss = (E_STIFF + E_SOFT) / 2, 2 / (1 / E_STIFF + 1 / E_SOFT)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 4))
    for axis, marker in (("x", "o"), ("y", "s"), ("z", "^")):
        ax.semilogy(centre[:, 0], young[axis], marker, ms=4, label=f"E_{axis} effective")
    ax.axhline(voigt, color="k", ls="--", lw=1, label="arithmetic mean of E (Voigt)")
    ax.axhline(reuss, color="k", ls=":", lw=1, label="harmonic mean of E (Reuss)")
    ax.set_xlabel("x of the coarse element's centre")
    ax.set_ylabel("directional Young's modulus")
    ax.set_title(f"Effective tensors of the layered beam ({model.num_elements} coarse tets)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1))
    fig.tight_layout()
    fig.savefig(out / "effective_young.png", dpi=120)

    (out / "result.json").write_text(json.dumps({
        "errors": result.errors,
        "coarse_dofs": model.num_dofs,
        "effective_young": {axis: v.tolist() for axis, v in young.items()},
        "averages": {"voigt": voigt, "reuss": reuss},
    }, indent=1))
    print(f"{model.num_elements} coarse elements, {model.num_dofs} coarse DOFs; errors: "
          + ", ".join(f"{k} {v:.4g}" for k, v in sorted(result.errors.items())))
    print(f"effective E_x {young['x'].min():.4g} .. {young['x'].max():.4g} "
          f"(Reuss {reuss:.4g}), E_y {young['y'].min():.4g} .. {young['y'].max():.4g} "
          f"(Voigt {voigt:.4g}); wrote {out}/effective_young.png, result.json")


if __name__ == "__main__":
    main()
