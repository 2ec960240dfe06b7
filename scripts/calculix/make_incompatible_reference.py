#!/usr/bin/env python3
"""Reference displacements from CalculiX's C3D8I (incompatible modes) for
tests/fem/test_calculix.cpp (suite CalculixIncompatible).

What this produces
------------------
Three problems in tests/data/calculix/, in the format of make_reference.py (which this script
imports), solved by ccx with C3D8I bricks, so that fem::Formulation::Incompatible can be checked
against an independent code node by node:

  hex_incompatible.json   the hex problem of make_reference.py (box [0,2]x[0,1]x[0,1], 8x4x4
                          cells, checkerboard of 0.5-cubes, clamped at x = 0, gravity and a
                          pressure p = 4 on x = 2) with material 2 near-incompressible:
                          1: E = 1000, nu = 0.3, density 2; 2: E = 10, nu = 0.4999, density 0.5.
  hex_distorted.json      the same with every interior node moved by up to 0.2 cell sizes per
                          axis (numpy default_rng(7), uniform; boundary nodes stay, so the
                          clamped and loaded faces are the same). Not parallelepipeds: this is
                          where the variants of the incompatible-mode element differ.
  quad_extruded.json      a 2D plane-strain check: the quad grid 8x4 on [0,2]x[0,1] (the same
                          checkerboard and materials, gravity along -y, pressure 4 on x = 2),
                          extruded to one layer of C3D8I of depth 0.25 with u_z = 0 at every
                          node. Each C3D8I then carries the 2D element's two in-plane modes per
                          component; its other modes decouple (for isotropic materials their
                          strains are odd in z or pure out-of-plane shear, orthogonal to the
                          in-plane strains under the symmetric 2x2x2 rule), so the nodal
                          displacements are those of the 2D incompatible quad in plane strain
                          (per unit depth, loads and stiffness both scale with the depth).
                          CalculiX has no 2D incompatible element (CPE4 is expanded to C3D8);
                          the stored displacements are those of the z = 0 layer, and the script
                          checks that the z = 0.25 layer printed the same digits and u_z = 0.

Which element CalculiX computes (ccx 2.20, shape8hu.f and e_c3d.f): C3D8I is an 11-node element
whose nodes 9-11 carry the modes 1 - xi^2, 1 - eta^2, 1 - zeta^2 (one per reference axis, three
displacement components each), solved with the nodal DOFs (equivalent to static condensation).
The modes' shape values are 0 (no load on them) and their gradients are taken with the inverse
Jacobian at the element centre, J0^-1, but integrated with the local det J at each of the 2x2x2
Gauss points: Wilson's modes with Taylor's J0, without Taylor, Beresford and Wilson's factor
j0 / j. On parallelepipeds (constant J) that is the textbook element; on distorted bricks the
modes' mean strain is not zero and the element fails the patch test. coarsegrain's
Formulation::Incompatible keeps the factor (src/fem/element_kernels.hpp, ModeMapping::Taylor);
the test reproduces ccx with ModeMapping::CalculiX on hex_distorted and records how far the two
are apart there.

Rerun
-----
    python3 scripts/calculix/make_incompatible_reference.py            # writes the 3 files
    python3 scripts/calculix/make_incompatible_reference.py --keep DIR # keeps .inp/.dat in DIR
Needs ccx and numpy like make_reference.py.
"""

import json
import os
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_reference as ref  # noqa: E402

MATERIALS = {
    1: {"E": 1000.0, "nu": 0.3, "density": 2.0},
    2: {"E": 10.0, "nu": 0.4999, "density": 0.5},
}
DEPTH = 0.25  # of the extruded layer


def write_c3d8i_inp(path, nodes, elements, mids, gravity, faces, fixed, fix_z_everywhere=False):
    """make_reference.write_inp with C3D8I bricks (and u_z = 0 at every node if asked)."""
    ref.write_inp(path, "hex", nodes, elements, mids, MATERIALS, gravity, faces, ref.PRESSURE,
                  fixed)
    with open(path) as f:
        text = f.read()
    assert text.count("TYPE=C3D8,") == len(MATERIALS)
    text = text.replace("TYPE=C3D8,", "TYPE=C3D8I,")
    if fix_z_everywhere:
        text = text.replace("*BOUNDARY\nFIXED, 1, 3, 0.0\n",
                            "*BOUNDARY\nFIXED, 1, 3, 0.0\nNALL, 3, 3, 0.0\n")
        assert "NALL, 3, 3" in text
    with open(path, "w") as f:
        f.write(text)


def box(lo, hi):
    e = ref.EPS
    return [v - e for v in lo], [v + e for v in hi]


def hex_problem(distort):
    nodes, elements = ref.make_grid("hex", ref.LO, ref.HI, ref.CELLS)
    mids = ref.checkerboard_ids(nodes, elements, ref.LO, 0.5, 1, 2)
    if distort:
        h = (np.asarray(ref.HI) - np.asarray(ref.LO)) / np.asarray(ref.CELLS)
        lo, hi = np.asarray(ref.LO), np.asarray(ref.HI)
        interior = np.all((nodes > lo + 1e-9) & (nodes < hi - 1e-9), axis=1)
        rng = np.random.default_rng(7)
        shift = rng.uniform(-0.2, 0.2, size=nodes.shape) * h
        nodes = nodes + np.where(interior[:, None], shift, 0.0)
    fixed_box = box([ref.LO[0], ref.LO[1], ref.LO[2]], [ref.LO[0], ref.HI[1], ref.HI[2]])
    load_box = box([ref.HI[0], ref.LO[1], ref.LO[2]], [ref.HI[0], ref.HI[1], ref.HI[2]])
    fixed = np.nonzero(ref.in_box(nodes, *fixed_box))[0]
    faces = ref.faces_in_box("hex", nodes, elements, *load_box)
    return dict(nodes=nodes, elements=elements, mids=mids, fixed=fixed, fixed_box=fixed_box,
                faces=faces, load_box=load_box, gravity=ref.GRAVITY,
                field={"checkerboard": {"origin": ref.LO, "size": 0.5, "ids": [1, 2]}})


def quad_problem():
    lo2, hi2, cells2 = [0.0, 0.0], [2.0, 1.0], [8, 4]
    nodes3, elements3 = ref.make_grid("hex", lo2 + [0.0], hi2 + [DEPTH], cells2 + [1])
    mids = ref.checkerboard_ids(nodes3, elements3, lo2 + [0.0], 0.5, 1, 2)
    n2 = (cells2[0] + 1) * (cells2[1] + 1)
    nodes2 = nodes3[:n2, :2]
    # Quad4 corners (0,0),(1,0),(1,1),(0,1) of each cell: the z = 0 face of the brick (VTK order).
    elements2 = elements3[:, :4]
    assert elements2.max() < n2
    gravity = [0.0, -9.81, 0.0]
    fixed_box = box(lo2[:1] + [lo2[1], 0.0], [lo2[0], hi2[1], DEPTH])
    load_box = box([hi2[0], lo2[1], 0.0], [hi2[0], hi2[1], DEPTH])
    fixed = np.nonzero(ref.in_box(nodes3, *fixed_box))[0]
    faces = ref.faces_in_box("hex", nodes3, elements3, *load_box)
    return dict(nodes3=nodes3, elements3=elements3, nodes=nodes2, elements=elements2, mids=mids,
                fixed=fixed, faces=faces, gravity=gravity, n2=n2,
                fixed_box2=box(lo2[:1] + [lo2[1]], [lo2[0], hi2[1]]),
                load_box2=box([hi2[0], lo2[1]], [hi2[0], hi2[1]]),
                field={"checkerboard": {"origin": lo2, "size": 0.5, "ids": [1, 2]}},
                grid={"min": lo2, "max": hi2, "cells": cells2})


def record(name, description, element, p, u, version, stdout, extra):
    r = {
        "name": name,
        "description": description + "; made by scripts/calculix/make_incompatible_reference.py",
        "ccx": {"version": version, "element_type": "C3D8I", "solver": ref.ccx_solver(stdout),
                "output": "*NODE PRINT U, E13.6 (7 significant digits)"},
        "element": element,
        "formulation": "incompatible",
        "nodes": p["nodes"].tolist(),
        "elements": p["elements"].tolist(),
        "material_ids": p["mids"].tolist(),
        "material_field": p["field"],
        "materials": {str(k): v for k, v in MATERIALS.items()},
        "displacements": u.tolist(),
    }
    r.update(extra)
    return r


def main():
    args, version, workdir = ref.prepare(__doc__.split("\n")[0], "ccx_inc_")
    outputs = []

    for name, distort in (("hex_incompatible", False), ("hex_distorted", True)):
        p = hex_problem(distort)
        write_c3d8i_inp(os.path.join(workdir, name + ".inp"), p["nodes"], p["elements"],
                        p["mids"], p["gravity"], p["faces"], p["fixed"])
        stdout = ref.run_ccx(workdir, name)
        u = ref.parse_displacements(os.path.join(workdir, name + ".dat"), range(len(p["nodes"])))
        extra = {
            "grid": {"min": ref.LO, "max": ref.HI, "cells": ref.CELLS},
            "distorted": distort,
            "gravity": p["gravity"],
            **ref.conditions_record(p),
        }
        desc = ("heterogeneous box (nu = 0.3 / 0.4999) clamped at x = 0 under gravity and a "
                "pressure on x = 2, C3D8I" + (", interior nodes moved randomly" if distort else ""))
        outputs.append((name, record(name, desc, "hex", p, u, version, stdout, extra)))

    name = "quad_extruded"
    p = quad_problem()
    write_c3d8i_inp(os.path.join(workdir, name + ".inp"), p["nodes3"], p["elements3"], p["mids"],
                    p["gravity"], p["faces"], p["fixed"], fix_z_everywhere=True)
    stdout = ref.run_ccx(workdir, name)
    u3 = ref.parse_displacements(os.path.join(workdir, name + ".dat"), range(len(p["nodes3"])))
    n2 = p["n2"]
    if not (np.array_equal(u3[:n2], u3[n2:]) and np.all(u3[:, 2] == 0)):
        sys.exit(f"error: {name}: the two layers differ or u_z != 0: max |difference| "
                 f"{np.abs(u3[:n2] - u3[n2:]).max():.3e}, max |u_z| {np.abs(u3[:, 2]).max():.3e}")
    u = u3[:n2, :2]
    fixed2 = [int(v) for v in p["fixed"] if v < n2]
    extra = {
        "grid": p["grid"],
        "plane": "strain",
        "depth": DEPTH,
        "gravity": p["gravity"][:2],
        "pressure": {"value": ref.PRESSURE, "traction": "-p n, n the outward normal",
                     "box": {"min": p["load_box2"][0], "max": p["load_box2"][1]},
                     "faces": [[e, f] for e, f in p["faces"]],
                     "faces_note": "[brick element (0-based), ccx face number] of the 3D model"},
        "dirichlet": {"box": {"min": p["fixed_box2"][0], "max": p["fixed_box2"][1]},
                      "nodes": fixed2, "value": [0.0, 0.0]},
    }
    desc = ("2D plane-strain heterogeneous rectangle (nu = 0.3 / 0.4999), clamped at x = 0 under "
            "gravity and a pressure on x = 2, solved as one layer of C3D8I with u_z = 0")
    outputs.append((name, record(name, desc, "quad", p, u, version, stdout, extra)))

    for name, r in outputs:
        path = os.path.join(args.out, name + ".json")
        with open(path, "w") as f:
            json.dump(r, f, separators=(",", ":"))
            f.write("\n")
        u = np.asarray(r["displacements"])
        print(f"{path}: {len(r['nodes'])} nodes, {len(r['elements'])} {r['element']} elements, "
              f"max |u| = {np.abs(u).max():.6e}, ccx {version} ({r['ccx']['solver']})")
    if not args.keep:
        shutil.rmtree(workdir)


if __name__ == "__main__":
    main()
