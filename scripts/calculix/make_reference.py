#!/usr/bin/env python3
"""Reference displacements from CalculiX (ccx) for tests/fem/test_calculix.cpp.

What this produces
------------------
tests/data/calculix/hex.json and tests/data/calculix/tet.json: two small heterogeneous
linear-elastic problems solved by CalculiX, an independent, established FEM code, so that
our FEM (tests/fem/test_calculix.cpp) can be checked against it node by node.

Both problems live on the box [0,2] x [0,1] x [0,1] meshed by a regular 8 x 4 x 4 grid:
  hex  C3D8 bricks (trilinear, full 2x2x2 Gauss integration: not C3D8R or C3D8I, which
       differ), a checkerboard of 0.5-cubes of materials 1 and 2;
  tet  C3D4 tetrahedra, each cell split into 6 tets exactly as src/mesh/grid.cpp does
       (Kuhn split, table kKuhnTets), layers of thickness 0.25 normal to x, ids 1, 2, 1, ...
Materials: 1: E = 1000, nu = 0.3, density 2; 2: E = 10, nu = 0.45, density 0.5.
Loads: gravity g = (0, 0, -9.81) (body force density * g) and a uniform pressure p = 4 on
the face x = 2 (traction t = -p n with n the outward normal, i.e. t = (-4, 0, 0)).
Dirichlet: every node on x = 0 clamped (u = 0).

How CalculiX is driven
----------------------
- Nodes and elements are written with ccx ids = our 0-based index + 1. C3D8 nodes are ordered
  as in VTK/Gmsh (and our mesh::ElementType::Hex8); C3D4 as in VTK (our Tet4).
- Gravity: *DENSITY per material and *DLOAD, <elset>, GRAV, |g|, g/|g|.
- Pressure: *DLOAD, <element>, P<face>, p on each element face lying on x = 2. ccx's face
  numbering, found by loading one face of a single element at a time and watching which nodes
  receive force and in which direction (a positive P pushes into the element):
      C3D8: P1 = 1-2-3-4, P2 = 5-8-7-6, P3 = 1-5-6-2, P4 = 2-6-7-3, P5 = 3-7-8-4, P6 = 4-8-5-1
      C3D4: P1 = 1-2-3,   P2 = 1-4-2,   P3 = 2-4-3,   P4 = 3-4-1
  (1-based local node numbers, as in the CalculiX manual's element face tables; the
  right-hand normal of each listed node cycle points into the element.)
- Dirichlet: *BOUNDARY, <nset>, 1, 3 (zero displacement).
- Output: *NODE PRINT, NSET=NALL with U, into <job>.dat; the displacements are parsed from
  there. ccx prints them in E13.6 format, i.e. 7 significant digits, so each stored value
  carries a relative rounding error of at most 5e-7 of itself; the stored numbers are the
  printed decimals exactly (json floats round-trip them).
- ccx's linear solver on Debian 12 (calculix-ccx 2.20) is SPOOLES (direct, symmetric).
- Cross-check when this was written: a 60-line dense numpy FEM of the same problems (Q1 with
  2x2x2 Gauss, P1, consistent gravity and pressure loads) matched the stored displacements to
  2.3e-7 (hex) and 9.1e-8 (tet) in max norm relative to max |u|, i.e. to the printed digits.

Each json file holds the exact problem (node coordinates, 0-based connectivity in our node
order, material ids and materials, gravity, pressure and the loaded faces, Dirichlet nodes),
the ccx displacements per node and the ccx version, so the C++ test needs nothing else.

Rerun
-----
    python3 scripts/calculix/make_reference.py            # writes tests/data/calculix/*.json
    python3 scripts/calculix/make_reference.py --keep DIR # also keeps the .inp/.dat in DIR
Needs ccx on the PATH (Debian package calculix-ccx, installed by scripts/setup.sh) and
Debian's Python 3 with python3-numpy (/usr/bin/python3 if another python3 comes first on
the PATH). bench/ccx_vs_coarsegrain.py imports the helpers of this file.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

# Kuhn split of the unit cube into 6 positively oriented tets, cube corner c having bits
# (x = 1, y = 2, z = 4): a copy of kKuhnTets in src/mesh/grid.cpp.
KUHN_TETS = [(0, 1, 3, 7), (0, 1, 7, 5), (0, 2, 7, 3), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 7, 6)]
# Hex8 corner order as bit patterns: kHexCorners in src/mesh/grid.cpp (VTK/Gmsh/CalculiX order).
HEX_CORNERS = [0, 1, 3, 2, 4, 5, 7, 6]
# CalculiX faces as 0-based local node numbers (see the module docstring).
CCX_FACES = {
    "hex": [(0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 4, 0)],
    "tet": [(0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0)],
}
CCX_TYPE = {"hex": "C3D8", "tet": "C3D4"}


def make_grid(element, lo, hi, cells):
    """Nodes (#V x 3) and 0-based elements of a regular grid, numbered as mesh::make_grid does:
    node (i,j,k) = i + (nx+1) (j + (ny+1) k), cell (i,j,k) = i + nx (j + ny k), and for tets
    the 6 tets of cell c are 6c .. 6c+5. Coordinates are lo + i h, the last one exactly hi."""
    lo, hi, n = np.asarray(lo, float), np.asarray(hi, float), np.asarray(cells, int)
    h = (hi - lo) / n
    axes = []
    for d in range(3):
        a = lo[d] + np.arange(n[d] + 1) * h[d]
        a[-1] = hi[d]
        axes.append(a)
    nv = n + 1
    kk, jj, ii = np.meshgrid(np.arange(nv[2]), np.arange(nv[1]), np.arange(nv[0]), indexing="ij")
    nodes = np.stack([axes[0][ii.ravel()], axes[1][jj.ravel()], axes[2][kk.ravel()]], axis=1)
    kc, jc, ic = np.meshgrid(np.arange(n[2]), np.arange(n[1]), np.arange(n[0]), indexing="ij")
    ic, jc, kc = ic.ravel(), jc.ravel(), kc.ravel()
    corner = np.stack(
        [(ic + (b & 1)) + nv[0] * ((jc + ((b >> 1) & 1)) + nv[1] * (kc + ((b >> 2) & 1)))
         for b in range(8)], axis=1)
    if element == "hex":
        elements = corner[:, HEX_CORNERS]
    else:
        elements = np.stack([corner[:, list(t)] for t in KUHN_TETS], axis=1).reshape(-1, 4)
    return nodes, elements


def centroids(nodes, elements):
    return nodes[elements].mean(axis=1)


def layer_ids(nodes, elements, axis, origin, thickness, ids):
    """material::layers: ids[floor((c_axis - origin) / thickness) mod len(ids)] at centroid c."""
    c = centroids(nodes, elements)[:, axis]
    return np.asarray(ids)[np.floor((c - origin) / thickness).astype(int) % len(ids)]


def checkerboard_ids(nodes, elements, origin, size, a, b):
    """material::checkerboard: a where the sum of the cube indices of the centroid is even."""
    c = centroids(nodes, elements)
    parity = np.floor((c - np.asarray(origin)) / size).astype(int).sum(axis=1) % 2
    return np.where(parity == 0, a, b)


def in_box(points, lo, hi):
    return np.all((points >= np.asarray(lo)) & (points <= np.asarray(hi)), axis=1)


def faces_in_box(element, nodes, elements, lo, hi):
    """(element, ccx face number 1..) of every element face whose nodes all lie in [lo, hi]."""
    inside = in_box(nodes, lo, hi)
    out = []
    for f, local in enumerate(CCX_FACES[element]):
        hit = np.all(inside[elements[:, list(local)]], axis=1)
        out.extend((int(e), f + 1) for e in np.nonzero(hit)[0])
    return sorted(out)


def write_inp(path, element, nodes, elements, material_ids, materials, gravity, pressure_faces,
              pressure, fixed_nodes):
    """A CalculiX input deck for one linear static step. materials: {id: {E, nu, density}}."""
    g = np.asarray(gravity, float)
    with open(path, "w") as out:
        out.write("*HEADING\ncoarsegrain reference problem\n*NODE, NSET=NALL\n")
        for i, p in enumerate(nodes):
            out.write(f"{i + 1}, {p[0]!r}, {p[1]!r}, {p[2]!r}\n")
        for mid in sorted(materials):
            sel = np.nonzero(material_ids == mid)[0]
            out.write(f"*ELEMENT, TYPE={CCX_TYPE[element]}, ELSET=M{mid}\n")
            for e in sel:
                out.write(f"{e + 1}, " + ", ".join(str(v + 1) for v in elements[e]) + "\n")
        out.write("*NSET, NSET=FIXED\n")
        for chunk in range(0, len(fixed_nodes), 8):
            out.write(", ".join(str(v + 1) for v in fixed_nodes[chunk:chunk + 8]) + ",\n")
        for mid in sorted(materials):
            m = materials[mid]
            out.write(f"*MATERIAL, NAME=MAT{mid}\n*ELASTIC\n{m['E']!r}, {m['nu']!r}\n"
                      f"*DENSITY\n{m['density']!r}\n"
                      f"*SOLID SECTION, ELSET=M{mid}, MATERIAL=MAT{mid}\n")
        out.write("*STEP\n*STATIC, SOLVER=SPOOLES\n*BOUNDARY\nFIXED, 1, 3, 0.0\n*DLOAD\n")
        gnorm = float(np.linalg.norm(g))
        if gnorm > 0:
            d = g / gnorm
            for mid in sorted(materials):
                out.write(f"M{mid}, GRAV, {gnorm!r}, {d[0]!r}, {d[1]!r}, {d[2]!r}\n")
        for e, f in pressure_faces:
            out.write(f"{e + 1}, P{f}, {pressure!r}\n")
        out.write("*NODE PRINT, NSET=NALL\nU\n*END STEP\n")


def run_ccx(workdir, job, env=None):
    """Runs `ccx -i job` in workdir; returns its standard output. Raises on failure."""
    proc = subprocess.run(["ccx", "-i", job], cwd=workdir, capture_output=True, text=True,
                          env=env)
    if proc.returncode != 0 or "Job finished" not in proc.stdout:
        raise RuntimeError(f"ccx failed on {os.path.join(workdir, job)}.inp "
                           f"(exit {proc.returncode}):\n{proc.stdout[-2000:]}\n{proc.stderr}")
    return proc.stdout


def parse_displacements(dat_path, nodes):
    """The U block of a *NODE PRINT in a .dat file at the given 0-based nodes: len(nodes) x 3,
    as printed (E13.6). Raises if a node is missing."""
    printed = {}
    reading = False
    with open(dat_path) as f:
        for line in f:
            if line.strip().startswith("displacements (vx,vy,vz)"):
                reading = True
                continue
            if reading:
                parts = line.split()
                if len(parts) == 4 and parts[0].isdigit():
                    printed[int(parts[0]) - 1] = [float(v) for v in parts[1:]]
                elif parts:
                    reading = False
    missing = [v for v in nodes if v not in printed]
    if missing:
        raise RuntimeError(f"{dat_path}: displacements of {len(missing)} of {len(nodes)} nodes "
                           f"missing (first: node {missing[0] + 1})")
    return np.array([printed[v] for v in nodes], float)


def ccx_version():
    out = subprocess.run(["ccx", "-v"], capture_output=True, text=True).stdout
    m = re.search(r"Version\s+(\S+)", out)
    if not m:
        raise RuntimeError(f"cannot read the version from `ccx -v`: {out!r}")
    return m.group(1)


def ccx_solver(stdout):
    """The solver ccx reports in its standard output, e.g. 'symmetric spooles solver'."""
    m = re.search(r"Factoring the system of equations using the (.*)", stdout)
    return m.group(1).strip() if m else "unknown"


MATERIALS = {
    1: {"E": 1000.0, "nu": 0.3, "density": 2.0},
    2: {"E": 10.0, "nu": 0.45, "density": 0.5},
}
LO, HI, CELLS = [0.0, 0.0, 0.0], [2.0, 1.0, 1.0], [8, 4, 4]
GRAVITY = [0.0, 0.0, -9.81]
PRESSURE = 4.0
EPS = 1e-9


def make_problem(element):
    nodes, elements = make_grid(element, LO, HI, CELLS)
    if element == "hex":
        mids = checkerboard_ids(nodes, elements, LO, 0.5, 1, 2)
        field = {"checkerboard": {"origin": LO, "size": 0.5, "ids": [1, 2]}}
    else:
        mids = layer_ids(nodes, elements, 0, LO[0], 0.25, [1, 2])
        field = {"layers": {"axis": 0, "origin": LO[0], "thickness": 0.25, "ids": [1, 2]}}
    fixed_lo, fixed_hi = [LO[0] - EPS, LO[1] - EPS, LO[2] - EPS], [LO[0] + EPS, HI[1] + EPS,
                                                                      HI[2] + EPS]
    load_lo, load_hi = [HI[0] - EPS, LO[1] - EPS, LO[2] - EPS], [HI[0] + EPS, HI[1] + EPS,
                                                                     HI[2] + EPS]
    fixed = np.nonzero(in_box(nodes, fixed_lo, fixed_hi))[0]
    faces = faces_in_box(element, nodes, elements, load_lo, load_hi)
    return dict(nodes=nodes, elements=elements, material_ids=mids, field=field, fixed=fixed,
                fixed_box=(fixed_lo, fixed_hi), faces=faces, load_box=(load_lo, load_hi))


def prepare(description, prefix):
    """The command line of a reference script (--out, --keep), checked for ccx: returns the
    arguments, ccx's version and the working folder of the ccx runs (args.keep or a new
    temporary one, which the caller removes unless args.keep)."""
    here = os.path.dirname(os.path.abspath(__file__))
    default_out = os.path.normpath(os.path.join(here, "..", "..", "tests", "data", "calculix"))
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", default=default_out, help="folder of the json files")
    parser.add_argument("--keep", help="keep the ccx input and output files in this folder")
    args = parser.parse_args()
    if shutil.which("ccx") is None:
        sys.exit("error: ccx not found; install the Debian package calculix-ccx")
    os.makedirs(args.out, exist_ok=True)
    version = ccx_version()
    workdir = args.keep or tempfile.mkdtemp(prefix=prefix)
    os.makedirs(workdir, exist_ok=True)
    return args, version, workdir



def conditions_record(p):
    """The "pressure" and "dirichlet" entries of a stored 3D problem p (prepare's result)."""
    return {
        "pressure": {"value": PRESSURE, "traction": "-p n, n the outward normal",
                     "box": {"min": p["load_box"][0], "max": p["load_box"][1]},
                     "faces": [[e, f] for e, f in p["faces"]],
                     "faces_note": "[element (0-based), ccx face number]"},
        "dirichlet": {"box": {"min": p["fixed_box"][0], "max": p["fixed_box"][1]},
                      "nodes": p["fixed"].tolist(), "value": [0.0, 0.0, 0.0]},
    }

def main():
    args, version, workdir = prepare(__doc__.split("\n")[0], "ccx_ref_")
    for element in ("hex", "tet"):
        p = make_problem(element)
        write_inp(os.path.join(workdir, element + ".inp"), element, p["nodes"], p["elements"],
                  p["material_ids"], MATERIALS, GRAVITY, p["faces"], PRESSURE, p["fixed"])
        stdout = run_ccx(workdir, element)
        u = parse_displacements(os.path.join(workdir, element + ".dat"),
                                 range(len(p["nodes"])))
        record = {
            "name": element,
            "description": "heterogeneous box clamped at x = 0 under gravity and a pressure on "
                           "x = 2, solved by CalculiX; made by scripts/calculix/make_reference.py",
            "ccx": {"version": version, "element_type": CCX_TYPE[element],
                    "solver": ccx_solver(stdout),
                    "output": "*NODE PRINT U, E13.6 (7 significant digits)"},
            "element": element,
            "grid": {"min": LO, "max": HI, "cells": CELLS},
            "nodes": p["nodes"].tolist(),
            "elements": p["elements"].tolist(),
            "material_ids": p["material_ids"].tolist(),
            "material_field": p["field"],
            "materials": {str(k): v for k, v in MATERIALS.items()},
            "gravity": GRAVITY,
            **conditions_record(p),
            "displacements": u.tolist(),
        }
        path = os.path.join(args.out, element + ".json")
        with open(path, "w") as f:
            json.dump(record, f, separators=(",", ":"))
            f.write("\n")
        print(f"{path}: {len(p['nodes'])} nodes, {len(p['elements'])} {CCX_TYPE[element]}, "
              f"{len(p['faces'])} loaded faces, max |u| = {np.abs(u).max():.6e}, "
              f"ccx {version} ({record['ccx']['solver']})")
    if not args.keep:
        shutil.rmtree(workdir)


if __name__ == "__main__":
    main()
