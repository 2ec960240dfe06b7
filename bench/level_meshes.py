#!/usr/bin/env python3
"""Build cost and accuracy of the material-adapted hierarchy on given, non-nested level meshes.

The fibre block of examples/fibre_block (four stiff fibres, contrast 1e3, embedded in a soft
2 x 1 x 1 block clamped at one end, under gravity) at several fine element sizes (make_mesh's
FACTOR; the coarse box of 512 tets and the middle box of 397 nodes stay), coarsened by each
method with `coarsegrain coarsen --method M`: the hierarchy's build seconds (its own `build`
phase), the process's peak memory, and the coarsest level's errors against the fine solution. Every run is one process, one after the other; the build time grows with the fine
step's wavelet stiffness B (its density is printed), whose Cholesky factorization dominates for
the linear refinement between non-nested levels.

Usage:
    python3 bench/level_meshes.py [build/release/coarsegrain] [--factors 2 1.5 1.25 1]
                                  [--methods mra-dirac mra-linear] [--out docs/level-meshes.md]
Needs gmsh (installed by scripts/setup.sh).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
EXAMPLE = os.path.join(ROOT, "examples", "fibre_block")
HEADER = """# The hierarchy on non-nested level meshes: build cost and accuracy

The fibre block (examples/fibre_block: four stiff fibres, contrast 1e3, embedded in a soft
2 x 1 x 1 block clamped at one end, under gravity) at several fine element sizes (FACTOR, make_mesh's
factor on the example's size), its coarse box of 512 tets (107 nodes) and middle box of 397 nodes
unchanged, global solves. Build: the hierarchy's `build` phase; peak: the process's; B density:
the fine step's wavelet stiffness; errors: the coarsest level's against the fine solution.
Regenerate with

    python3 bench/level_meshes.py --out docs/level-meshes.md

"""


def run_method(cli, scene, method, out, timeout=None):
    """Runs one coarsen and returns the method's summary.json, or None if it ran out of
    `timeout` seconds."""
    cmd = [cli, "coarsen", scene, "--method", method, "--out", out]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    if p.returncode != 0:
        sys.exit(f"error: {' '.join(cmd)} failed:\n{p.stdout}\n{p.stderr}")
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def row(factor, method, summary):
    errors = summary["errors"]
    coarse = summary["coarse"]
    levels = coarse["levels"]
    return (f"| {factor:g} | {summary['fine']['nodes']} | {method} "
            f"| {coarse['timings']['build']:.1f} | {summary['peak_memory_mb'] / 1024:.2f} "
            f"| {levels[-2]['B_density']:.4f} "
            f"| {errors['energy_rel']:.4f} | {errors['l2_rel']:.4f} "
            f"| {errors['compliance_ratio']:.4f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cli", nargs="?", default=os.path.join(ROOT, "build/release/coarsegrain"))
    parser.add_argument("--factors", type=float, nargs="+", default=[2, 1.5, 1.25, 1])
    parser.add_argument("--methods", nargs="+", default=["mra-dirac", "mra-linear"])
    parser.add_argument("--out", help="also write the table to this markdown file (its sections "
                        "after the table are kept)")
    args = parser.parse_args()
    lines = ["| FACTOR | fine nodes | method | build s | peak GB | B density (fine step) "
             "| energy error | l2 error | compliance ratio |",
             "|---|---|---|---|---|---|---|---|---|"]
    print("\n".join(lines), flush=True)
    with tempfile.TemporaryDirectory() as work:
        for factor in args.factors:
            folder = os.path.join(work, f"f{factor:g}")
            subprocess.run([os.path.join(EXAMPLE, "make_mesh"), folder, f"{factor:g}"], check=True)
            scene = os.path.join(folder, "fibre_block.json")
            with open(os.path.join(EXAMPLE, "fibre_block.json")) as f:
                data = json.load(f)
            with open(scene, "w") as f:
                json.dump(data, f)
            for method in args.methods:
                summary = run_method(args.cli, scene, method, os.path.join(folder, method))
                lines.append(row(factor, method, summary))
                print(lines[-1], flush=True)
    if args.out:
        write_table(args.out, HEADER + "\n".join(lines) + "\n")


def write_table(path, text):
    """Writes text to path, keeping the sections (from the first "## " heading) it had."""
    kept = ""
    if os.path.exists(path):
        with open(path) as f:
            old = f.read()
        start = old.find("\n## ")
        if start >= 0:
            kept = old[start:]
    with open(path, "w") as f:
        f.write(text + kept)


if __name__ == "__main__":
    main()
