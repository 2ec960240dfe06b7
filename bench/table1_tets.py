#!/usr/bin/env python3
"""Table 1's tet rows (Chen et al. 2019) on the fibre block: two levels, a fixed coarse level.

The paper builds its dragon at 23,811 and 163,152 fine nodes onto one coarse mesh of 3,916 nodes
(2 levels, radius 5, cut-off 1e-7): 23.7 s and 914 s, 2.4 GB of storage. Here the fibre block of
examples/fibre_block (four stiff fibres, contrast 1e3, in a soft 2 x 1 x 1 block clamped at one
end, under gravity) is meshed at several fine element sizes (make_mesh's FACTOR) and coarsened by
`coarsegrain coarsen` onto one given coarse level, the plain box meshed by Gmsh at --coarse-size
(about 3.5K nodes, non-nested). Per size: the paper's setting (Dirac refinement, node-wise
localized solves of radius 5 fine rings, truncation 1e-7), the same at radius 3 (whose C^1 and
A^1 are as sparse as the paper's dragon rows), and the accurate default (linear refinement,
global solves) up to --accurate-max-nodes fine nodes, stopped after --accurate-timeout seconds.
Every run is one process, one after the other.

Usage:
    python3 bench/table1_tets.py [build/release/coarsegrain] [--factors 0.64 0.5 0.41 0.327]
                                 [--radii 5 3] [--accurate-max-nodes 30000]
                                 [--accurate-timeout 1800]
                                 [--out docs/table1-tets.md]
Needs gmsh (installed by scripts/setup.sh).
"""

import argparse
import json
import os
import subprocess
import tempfile

from level_meshes import run_method, write_table

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
EXAMPLE = os.path.join(ROOT, "examples", "fibre_block")
COLUMNS = ("| fine nodes | coarse nodes | method | radius | build s | localized solves s "
           "| storage GB | peak GB | C^1 sparsity | A^1 sparsity | B^1 sparsity "
           "| energy error | error / ‖g‖ | compliance ratio |")
HEADER = """# Table 1's tet rows on the fibre block

Chen et al. 2019, Table 1, build the dragon's hierarchy (2 levels, radius 5, cut-off 1e-7) at
23,811 fine nodes in 23.7 s and at 163,152 in 914 s with 2.4 GB of storage, both onto one coarse
mesh of 3,916 nodes. Here: the fibre block (examples/fibre_block: four stiff fibres, contrast
1e3, in a soft block clamped at one end, under gravity) at four fine element sizes, onto one
coarse level, the plain box meshed by Gmsh (not nested in the fine meshes, fibres not meshed);
2 threads. Methods: `mra-dirac` at the paper's radius 5 (fine rings, node-wise) and at radius 3,
truncation 1e-7; `mra-linear` with global solves, the accurate default, where it fits.

- *build*: the hierarchy's `build` phase; *localized solves*: its share in the fine step's local
  factorizations; *storage*: the bytes of C̃^k, A^k and B^k kept, all levels (the fine operator
  included), as the paper's storage column; *peak*: the process's high-water mark, which also
  holds the fine CHOLMOD solve the errors are measured against.
- *sparsity*: 1 - density of the coarse step's operators (the paper's columns; dragon_1: B^1
  99.95%, C^1 99.1%, A^1 92.98%).
- *energy error*: ‖u^1 - u‖_A / ‖u‖_A; *error / ‖g‖*: ‖u^1 - u‖_A / ‖g‖, the paper's
  "resid." (dragon_1 1.1, dragon_2 2.4; its scale depends on the model's units);
  *compliance ratio*: g^T u^1 / g^T u.

Regenerate with

    python3 bench/table1_tets.py --out docs/table1-tets.md

"""


def row(summary, method, radius):
    coarse = summary["coarse"]
    levels = coarse["levels"]
    step = levels[0]
    timings = coarse["timings"]
    solves = sum(v for k, v in timings.items() if "localized solves" in k)
    storage = sum(level.get(k) or 0 for level in levels
                  for k in ("bytes_A", "bytes_B", "bytes_C"))
    errors = summary["errors"]
    return (f"| {summary['fine']['nodes']} | {step['nodes']} | {method} | {radius} "
            f"| {timings['build']:.1f} | {solves:.1f} | {storage / 2**30:.2f} "
            f"| {summary['peak_memory_mb'] / 1024:.2f} "
            f"| {100 * step['sparsity_C']:.2f}% | {100 * step['sparsity_A']:.2f}% "
            f"| {100 * step['sparsity_B']:.3f}% "
            f"| {errors['energy_rel']:.3f} | {step['error_over_g']:.3f} "
            f"| {errors['compliance_ratio']:.3f} |")


def scene(folder, coarse_file, radius, name):
    with open(os.path.join(EXAMPLE, "fibre_block.json")) as f:
        data = json.load(f)
    data["coarse"] = {"level_meshes": [coarse_file], "radius": radius, "truncation": 1e-7,
                      "spectrum_max_dofs": 0}
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        json.dump(data, f)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cli", nargs="?", default=os.path.join(ROOT, "build/release/coarsegrain"))
    parser.add_argument("--factors", type=float, nargs="+", default=[0.64, 0.5, 0.41, 0.327])
    parser.add_argument("--radii", type=float, nargs="+", default=[5, 3])
    parser.add_argument("--coarse-size", type=float, default=0.085,
                        help="Gmsh element size of the coarse level (0.085: 3,557 nodes)")
    parser.add_argument("--accurate-max-nodes", type=int, default=30000,
                        help="also run mra-linear with global solves up to this many fine nodes")
    parser.add_argument("--accurate-timeout", type=float, default=1800,
                        help="seconds after which the accurate default's run is stopped")
    parser.add_argument("--out", help="also write the table to this markdown file (its sections "
                        "after the table are kept)")
    args = parser.parse_args()
    lines = [COLUMNS, "|" + "---|" * (COLUMNS.count("|") - 1)]
    print("\n".join(lines), flush=True)
    with tempfile.TemporaryDirectory() as work:
        coarse = os.path.join(work, "coarse.msh")
        subprocess.run(["gmsh", "-3", os.path.join(EXAMPLE, "fibre_block_coarse.geo"),
                        "-setnumber", "size", f"{args.coarse_size:g}", "-o", coarse],
                       check=True, capture_output=True)
        for factor in args.factors:
            folder = os.path.join(work, f"f{factor:g}")
            subprocess.run([os.path.join(EXAMPLE, "make_mesh"), folder, f"{factor:g}"],
                           check=True)
            for radius in args.radii:
                path = scene(folder, coarse, radius, f"dirac_{radius:g}.json")
                summary = run_method(args.cli, path, "mra-dirac", os.path.join(folder, "out"))
                fine_nodes = summary["fine"]["nodes"]
                lines.append(row(summary, "mra-dirac", f"{radius:g}"))
                print(lines[-1], flush=True)
            if fine_nodes <= args.accurate_max_nodes:
                path = scene(folder, coarse, "inf", "linear_global.json")
                summary = run_method(args.cli, path, "mra-linear", os.path.join(folder, "out"),
                                     args.accurate_timeout)
                lines.append(row(summary, "mra-linear", "global") if summary else
                             f"| {fine_nodes} | - | mra-linear | global | not done in "
                             f"{args.accurate_timeout:g} s |" + " |" * 9)
                print(lines[-1], flush=True)
    if args.out:
        write_table(args.out, HEADER + "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
