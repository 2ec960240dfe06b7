#!/usr/bin/env python3
"""Wall-clock comparison of a fine static solve: CalculiX (ccx) against `coarsegrain solve`.

The problem: a layered box [0,4] x [0,1.5] x [0,1.5] on a regular hex grid (default 48 x 18 x 18
cells, 17,689 nodes, 53,067 DOFs), layers of thickness 0.25 normal to x alternating material 1
(E = 1000, nu = 0.3, density 2) and 2 (E = 10, nu = 0.45, density 0.5), clamped at x = 0, under
gravity (0, 0, -9.81) and a pressure 4 on the face x = 4 (traction (-4, 0, 0)). The script writes
the same problem twice, as a CalculiX deck (C3D8 bricks, full 2x2x2 integration, SPOOLES) and as
a coarsegrain scene (DESIGN.md: "mesh": {"grid": ...}, "material_field": {"layers": ...}), runs
each program --repeat times (default 3), keeps the best wall-clock time of each, and prints a
table with both times and their ratio. It also checks that the two answers agree: a few probe
points sit on grid nodes; coarsegrain reports its displacement there in summary.json
("probes": [{"point", "u"}]) and ccx prints the same nodes' displacements (*NODE PRINT, 7
significant digits, so agreement is expected to about 1e-6).

Both times are of the whole program (read input, assemble, factorize, solve, write output);
coarsegrain's own phase timings from summary.json are printed too. Both programs get the same
thread count (--threads, default: all cores): coarsegrain through its --threads option, ccx
through OMP_NUM_THREADS and CCX_NPROC_EQUATION_SOLVER; the table shows the solver and thread count ccx reports using.

Usage:
    python3 bench/ccx_vs_coarsegrain.py [build/coarsegrain] [--cells 48 18 18] [--repeat 3]
                                        [--threads N] [--workdir DIR]
Needs ccx (Debian package calculix-ccx) and Debian's Python 3 with python3-numpy
(/usr/bin/python3 if another python3 comes first on the PATH).
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts",
                                "calculix"))
import make_reference as ccxref  # noqa: E402  (helpers shared with the test references)

MATERIALS = {
    1: {"E": 1000.0, "nu": 0.3, "density": 2.0},
    2: {"E": 10.0, "nu": 0.45, "density": 0.5},
}
LO, HI = [0.0, 0.0, 0.0], [4.0, 1.5, 1.5]
GRAVITY = [0.0, 0.0, -9.81]
PRESSURE = 4.0
LAYERS = {"axis": 0, "thickness": 0.25, "ids": [1, 2]}
# Probe points (snapped to the nearest grid node): the loaded end, its corners, mid-span.
PROBES = [[4.0, 0.75, 0.75], [4.0, 0.0, 0.0], [4.0, 1.5, 1.5], [2.0, 0.75, 1.5],
          [1.0, 0.0, 0.75]]
EPS = 1e-9


def run_timed(command, cwd, env, repeat):
    """Wall-clock times of `repeat` runs (sorted, best first), and the last run's stdout."""
    times, stdout = [], ""
    for _ in range(repeat):
        start = time.perf_counter()
        proc = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True)
        elapsed = time.perf_counter() - start
        if proc.returncode != 0:
            raise RuntimeError(f"`{' '.join(command)}` failed (exit {proc.returncode}):\n"
                               f"{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
        times.append(elapsed)
        stdout = proc.stdout
    return sorted(times), stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("coarsegrain", nargs="?", default="build/coarsegrain",
                        help="path of the coarsegrain binary (default build/coarsegrain)")
    parser.add_argument("--cells", type=int, nargs=3, default=[48, 18, 18])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--threads", type=int, default=os.cpu_count())
    parser.add_argument("--workdir", help="keep the inputs and outputs here (default: a "
                                          "temporary folder, removed at the end)")
    args = parser.parse_args()
    if shutil.which("ccx") is None:
        sys.exit("error: ccx not found; install the Debian package calculix-ccx")
    cg = os.path.abspath(args.coarsegrain)
    if not os.access(cg, os.X_OK):
        sys.exit(f"error: coarsegrain binary {cg} not found or not executable "
                 "(build it, or pass its path as the first argument)")
    workdir = os.path.abspath(args.workdir or tempfile.mkdtemp(prefix="ccx_vs_cg_"))
    os.makedirs(workdir, exist_ok=True)

    nodes, elements = ccxref.make_grid("hex", LO, HI, args.cells)
    mids = ccxref.layer_ids(nodes, elements, LAYERS["axis"], LO[LAYERS["axis"]],
                            LAYERS["thickness"], LAYERS["ids"])
    fixed_box = {"min": [LO[0] - EPS, LO[1] - EPS, LO[2] - EPS],
                 "max": [LO[0] + EPS, HI[1] + EPS, HI[2] + EPS]}
    load_box = {"min": [HI[0] - EPS, LO[1] - EPS, LO[2] - EPS],
                "max": [HI[0] + EPS, HI[1] + EPS, HI[2] + EPS]}
    fixed = np.nonzero(ccxref.in_box(nodes, fixed_box["min"], fixed_box["max"]))[0]
    faces = ccxref.faces_in_box("hex", nodes, elements, load_box["min"], load_box["max"])
    probe_nodes = [int(np.argmin(np.linalg.norm(nodes - np.asarray(p), axis=1)))
                   for p in PROBES]
    probe_points = [nodes[v].tolist() for v in probe_nodes]
    dofs = 3 * len(nodes)

    # CalculiX deck: print only the probe nodes' displacements.
    inp = os.path.join(workdir, "beam.inp")
    ccxref.write_inp(inp, "hex", nodes, elements, mids, MATERIALS, GRAVITY, faces, PRESSURE,
                     fixed)
    with open(inp) as f:
        deck = f.read()
    probe_set = "*NSET, NSET=PROBES\n" + ", ".join(str(v + 1) for v in probe_nodes) + "\n"
    deck = deck.replace("*MATERIAL", probe_set + "*MATERIAL", 1)
    deck = deck.replace("*NODE PRINT, NSET=NALL", "*NODE PRINT, NSET=PROBES")
    with open(inp, "w") as f:
        f.write(deck)

    scene = {
        "dimension": 3,
        "mesh": {"grid": {"min": LO, "max": HI, "cells": args.cells, "element": "hex"}},
        "materials": {str(k): v for k, v in MATERIALS.items()},
        "material_field": {"layers": LAYERS},
        "dirichlet": [{"box": fixed_box, "value": [0.0, 0.0, 0.0]}],
        "loads": {"gravity": GRAVITY,
                  "traction": [{"box": load_box, "value": [-PRESSURE, 0.0, 0.0]}]},
        "probes": probe_points,
    }
    scene_path = os.path.join(workdir, "beam.json")
    with open(scene_path, "w") as f:
        json.dump(scene, f, indent=2)

    env = dict(os.environ, OMP_NUM_THREADS=str(args.threads),
               CCX_NPROC_EQUATION_SOLVER=str(args.threads))
    print(f"problem: {args.cells[0]}x{args.cells[1]}x{args.cells[2]} hex cells, {len(nodes)} "
          f"nodes, {dofs} DOFs, {len(elements)} elements; best of {args.repeat} runs, "
          f"{args.threads} thread(s); files in {workdir}", flush=True)
    runs_ccx, ccx_out = run_timed(["ccx", "-i", "beam"], workdir, env, args.repeat)
    out_dir = os.path.join(workdir, "cg_out")
    runs_cg, _ = run_timed([cg, "--quiet", "--threads", str(args.threads), "solve", scene_path,
                         "--out", out_dir], workdir, env, args.repeat)

    u_ccx = ccxref.parse_displacements(os.path.join(workdir, "beam.dat"), probe_nodes)
    with open(os.path.join(out_dir, "summary.json")) as f:
        summary = json.load(f)
    probes = summary["probes"]
    if len(probes) != len(probe_nodes):
        sys.exit(f"error: summary.json has {len(probes)} probes, the scene {len(probe_nodes)}")
    u_cg = np.array([p["u"] for p in probes], float)

    solver = ccxref.ccx_solver(ccx_out)
    cpus = re.search(r"Using up to (\d+) cpu\(s\) for spooles", ccx_out)
    ccx_label = f"ccx {ccxref.ccx_version()} ({solver}"
    ccx_label += f", {cpus.group(1)} cpu(s))" if cpus else ")"
    timings = summary.get("fine", {}).get("timings", {})
    cg_label = "coarsegrain solve (" + ", ".join(f"{k} {v:.3f}s" for k, v in timings.items()) + ")"
    t_ccx, t_cg = runs_ccx[0], runs_cg[0]
    width = max(len(ccx_label), len(cg_label))
    print()
    print(f"{'program':<{width}}  {'best wall [s]':>13}  all runs [s]")
    print(f"{ccx_label:<{width}}  {t_ccx:13.3f}  " + " ".join(f"{t:.3f}" for t in runs_ccx))
    print(f"{cg_label:<{width}}  {t_cg:13.3f}  " + " ".join(f"{t:.3f}" for t in runs_cg))
    print(f"{'ratio ccx / coarsegrain':<{width}}  {t_ccx / t_cg:13.2f}")
    print("(coarsegrain's phase timings are those of its last run)")

    print()
    print(f"{'probe point':<28} {'u (ccx)':<48} {'rel. difference':>15}")
    scale = np.abs(u_ccx).max()
    worst = 0.0
    for p, a, b in zip(probe_points, u_ccx, u_cg):
        rel = np.abs(a - b).max() / scale
        worst = max(worst, rel)
        point = "(" + ", ".join(f"{x:.4g}" for x in p) + ")"
        u = "(" + ", ".join(f"{x:.6e}" for x in a) + ")"
        print(f"{point:<28} {u:<48} {rel:15.2e}")
    print(f"max |u_cg - u_ccx| / max |u_ccx| over the probes: {worst:.2e} "
          "(ccx prints 7 significant digits)")
    if not args.workdir:
        shutil.rmtree(workdir)


if __name__ == "__main__":
    main()
