#!/usr/bin/env python3
"""Reference natural frequencies and a transient from CalculiX (ccx) for the hex problem.

What this produces
------------------
tests/data/calculix/hex_dynamics.json: two dynamic references on the hex problem of
make_reference.py (which this script imports): box [0,2] x [0,1] x [0,1], 8 x 4 x 4 C3D8 bricks
(trilinear, full 2x2x2 Gauss), checkerboard of 0.5-cubes of materials 1: E = 1000, nu = 0.3,
density 2 and 2: E = 10, nu = 0.45, density 0.5, clamped at x = 0. The two densities differ, so
the consistent mass matrix M (int rho N_a N_b, exact with 2x2x2 Gauss on these bricks) is not a
multiple of a purely geometric one.

  frequency   the 10 lowest eigenpairs of K phi = omega^2 M phi on the free DOFs (*FREQUENCY,
              no loads): omega^2, the frequencies omega / (2 pi) in cycles per time unit, and the
              mode shapes at the probe nodes.
  transient   the static problem's loads (gravity g = (0, 0, -9.81), pressure p = 4 on x = 2)
              switched on at t = 0 and held, starting from rest (u = v = 0), no damping, linear
              geometry, integrated with the implicit midpoint rule with dt = 0.125 (about 1/21 of
              the first period 2.6025) for 64 steps (t = 8, about three periods):
                  u_{n+1} = u_n + dt/2 (v_n + v_{n+1}),
                  M (v_{n+1} - v_n) = dt (f - K (u_n + u_{n+1}) / 2),
              stored at t_n = n dt, n = 1 .. 64, at the probe nodes.

How CalculiX is driven
----------------------
The model part of the deck (nodes, elements, materials with *DENSITY, the clamped node set) and
the *DLOAD lines are those make_reference.write_inp writes for hex.json; only the steps differ.

- Frequencies: *FREQUENCY, STORAGE=YES with 10 eigenvalues, *NODE PRINT U. The .dat table prints
  omega^2, omega and omega / (2 pi) as 0.dddddddE+xx, i.e. 7 significant digits. STORAGE=YES
  makes ccx write <job>.eig, a binary file (C fwrite, native byte order) that holds, after four
  4-byte integers (cyclic-symmetry flag 0, Hermitian flag 1, perturbation flag 0, the number of
  eigenvalues), the eigenvalues omega^2 as doubles: "eigenvalues" are those, to full double
  precision; the script checks that each rounds to the printed digits. "frequencies_hz" are
  sqrt(omega^2) / (2 pi) computed here in double precision from them (and agree with the printed
  cycles/time to the printed digits); the printed values are stored as well. The mode shapes
  are the *NODE PRINT U blocks of the eigenmodes (E13.6, 7 significant digits), normalized by ccx
  to phi^T M phi = 1; the sign of each mode is arbitrary, and components that are zero by
  symmetry are printed as round-off (~1e-14 of the mode).
- Transient: *STEP (no NLGEOM, so geometrically linear) with *DYNAMIC, DIRECT, ALPHA=0.0
  (fixed increments dt; HHT with alpha = 0 is Newmark with beta = 1/4, gamma = 1/2), no *DAMPING
  or Rayleigh damping (ccx reports zero work of the damping forces at every increment; checked),
  *NODE PRINT of U and V at the probe nodes at every increment. ccx's first output is at t = dt
  (nothing at t = 0); the printed times are exactly n dt. U and V print as E13.6, 7 significant
  digits.
- Initial acceleration (ccx 2.20, nonlingeo.c): at the start of a *DYNAMIC step ccx computes a0
  from (M + beta (1 + alpha) (dt/10)^2 K) a0 = f(0) - K u0, i.e. with "a small amount of
  stiffness added to the mass matrix", not from M a0 = f(0) - K u0. Newmark's displacements and
  velocities equal the midpoint rule's only with the consistent a0, so with a load that is 1 at
  all times (*AMPLITUDE 1 throughout) ccx is off the midpoint rule by 1.4e-3 max|u| (4.9e-4
  already after the first increment). This was checked both ways: the numpy Newmark recursion
  with ccx's a0 matches that run to 1.3e-7 (the printed digits), and starting the step with a
  previous tiny *DYNAMIC step does not help (each *DYNAMIC step recomputes a0 that way).
  The fix used here: Newmark with gamma = 1/2 sees the loads only through the trapezoidal means
  (f_n + f_{n+1}) / 2 (M (v_{n+1} - v_n) = dt/2 (M a_n + M a_{n+1}) with M a_n = f_n - K u_n for
  n >= 1 from the increments' equilibrium), and u_{n+1} - u_n = dt/2 (v_n + v_{n+1}) always.
  So the loads carry the *AMPLITUDE MIDPOINT, piecewise linear through A(n dt) = 0 for even n
  and 2 for odd n. Then A(0) = 0 and u0 = 0 make ccx's right-hand side for a0 exactly zero,
  hence a0 = 0 = M^-1 (f(0) - K u0) whatever matrix it solves with, and every mean
  (A_n + A_{n+1}) / 2 is 1: ccx's printed u and v are exactly the midpoint rule's under the
  constant load f (its internal accelerations alternate, but are not output). The deck with the
  amplitude 1 at all times is run too, as a check of the explanation above.

Cross-check
-----------
A compact dense numpy FEM of the same mesh (Q1 with 2x2x2 Gauss for K and the consistent M,
gravity rho g N_a with the same rule, the pressure with 2x2 Gauss on the loaded faces, the x = 0
nodes removed) is assembled here on every run. Measured when this was written (ccx 2.20):
  - statics: its K u = f matches hex.json to 2.3e-7 of max|u| (the printed digits);
  - eigenvalues (scipy.linalg.eigh of (K, M), 600 free DOFs): max relative difference to the
    full-precision .eig values 6.6e-13 (ARPACK's tolerance; both solve the same discrete
    problem); to the printed .dat values 2.2e-7 (omega^2) and 3.7e-7 (cycles/time), each within
    half a unit of the last printed digit;
  - mode shapes at the probe nodes (signs aligned): 3.1e-7 of each mode's max at the probes;
  - transient: the midpoint recursion above matches ccx's u to 1.25e-7 of max|u| (max|u| = 4.0)
    over all probes and times, v to 6.3e-8 of max|v|, and every component of u and v lies
    within half a unit of ccx's last printed digit (plus 1e-12 of the largest);
  - the amplitude-1 deck: 1.4e-3 of max|u| from the midpoint rule, 1.25e-7 from Newmark with
    ccx's a0 (see above).
The script fails if the agreement gets worse than 1e-6 (2e-6 for mode shapes).

The json holds the problem in the format of hex.json (name "hex_dynamics", element, grid, nodes,
0-based elements, material_ids, material_field, materials, gravity, pressure, dirichlet; no
static displacements), "ccx" and "ccx_version", and the "frequency" and "transient" blocks
(see `record` below for the keys, shapes and units). So tests/fem/test_calculix.cpp rebuilds the
fine model from it as for hex.json: reference_mesh for the mesh, the materials with their
densities, gravity_load + traction_load on the facets in the pressure box, and the nodes in the
Dirichlet box; the mass matrix is the consistent one of the same mesh and materials.

Rerun
-----
    python3 scripts/calculix/make_dynamics_reference.py            # writes hex_dynamics.json
    python3 scripts/calculix/make_dynamics_reference.py --keep DIR # also keeps .inp/.dat/.eig
Needs ccx and numpy like make_reference.py (/usr/bin/python3 on Debian); scipy's generalized
eigensolver is used when available, else numpy on the Cholesky-reduced problem.
"""

import json
import os
import re
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_reference as ref  # noqa: E402

N_MODES = 10
DT = 0.125
STEPS = 64
# Probes: the corners and the centre of the loaded face x = 2, and two interior nodes.
PROBE_POINTS = [(2.0, 0.0, 0.0), (2.0, 1.0, 0.0), (2.0, 0.0, 1.0), (2.0, 1.0, 1.0),
                (2.0, 0.5, 0.5), (1.0, 0.5, 0.5), (0.5, 0.25, 0.75)]
PRINTED = "E13.6 (7 significant digits)"


# ------------------------------------------------------------------------------------------
# Decks


def model_and_loads(workdir, p):
    """The model part of make_reference's hex deck (everything before *STEP) and its *DLOAD
    data lines (gravity per material, pressure per face)."""
    path = os.path.join(workdir, "hex_static.inp")
    ref.write_inp(path, "hex", p["nodes"], p["elements"], p["material_ids"], ref.MATERIALS,
                  ref.GRAVITY, p["faces"], ref.PRESSURE, p["fixed"])
    with open(path) as f:
        text = f.read()
    model, step = text.split("*STEP\n")
    m = re.search(r"\*DLOAD\n(.*?)\*NODE PRINT", step, re.S)
    assert m and "*BOUNDARY\nFIXED, 1, 3, 0.0\n" in step
    return model, m.group(1)


def nset(name, nodes):
    lines = [f"*NSET, NSET={name}\n"]
    for chunk in range(0, len(nodes), 8):
        lines.append(", ".join(str(v + 1) for v in nodes[chunk:chunk + 8]) + ",\n")
    return "".join(lines)


def frequency_deck(model):
    return (model + "*STEP\n*FREQUENCY, STORAGE=YES\n" + f"{N_MODES}\n"
            "*BOUNDARY\nFIXED, 1, 3, 0.0\n*NODE PRINT, NSET=NALL\nU\n*END STEP\n")


def transient_deck(model, dloads, probes, amplitude):
    """A *DYNAMIC, DIRECT, ALPHA=0 step of STEPS increments DT with every load scaled by the
    piecewise linear amplitude [(t, value), ...]."""
    pairs = [f"{t!r}, {a!r}" for t, a in amplitude]
    amp = "".join(", ".join(pairs[i:i + 4]) + "\n" for i in range(0, len(pairs), 4))
    return (model + nset("PROBES", probes) + "*AMPLITUDE, NAME=LOADAMP\n" + amp +
            f"*STEP, INC={10 * STEPS}\n*DYNAMIC, DIRECT, ALPHA=0.0\n{DT!r}, {STEPS * DT!r}\n"
            "*BOUNDARY\nFIXED, 1, 3, 0.0\n*DLOAD, AMPLITUDE=LOADAMP\n" + dloads +
            "*NODE PRINT, NSET=PROBES\nU\n*NODE PRINT, NSET=PROBES\nV\n*END STEP\n")


def constant_amplitude():
    return [(0.0, 1.0), (STEPS * DT, 1.0)]


def midpoint_amplitude():
    """0 at even and 2 at odd multiples of DT (see the module docstring)."""
    return [(n * DT, 0.0 if n % 2 == 0 else 2.0) for n in range(STEPS + 1)]


# ------------------------------------------------------------------------------------------
# ccx output


def parse_blocks(dat_path):
    """Every nodal block of a .dat file, in order: (quantity, set, time, {0-based node: [3]})."""
    blocks = []
    with open(dat_path) as f:
        for line in f:
            m = re.match(r"\s*(displacements|velocities) \(vx,vy,vz\) for set (\S+) "
                         r"and time\s+(\S+)", line)
            if m:
                blocks.append((m.group(1), m.group(2), float(m.group(3)), {}))
                continue
            parts = line.split()
            if blocks and len(parts) == 4 and parts[0].isdigit():
                blocks[-1][3][int(parts[0]) - 1] = [float(v) for v in parts[1:]]
    return blocks


def parse_eigenvalue_table(dat_path):
    """The E I G E N V A L U E   O U T P U T table: (omega^2, cycles/time) per mode, as printed."""
    rows = []
    with open(dat_path) as f:
        text = f.read()
    table = text.split("E I G E N V A L U E   O U T P U T", 1)[1]
    table = table.split("P A R T I C I P A T I O N", 1)[0]
    for line in table.splitlines():
        parts = line.split()
        if len(parts) == 5 and parts[0].isdigit():
            rows.append((float(parts[1]), float(parts[3])))
    return np.array(rows)


def read_eig(path):
    """Eigenvalues omega^2 at full precision from a *FREQUENCY, STORAGE=YES .eig file."""
    with open(path, "rb") as f:
        head = np.frombuffer(f.read(16), dtype=np.int32)
        cyclic, hermitian, perturbation, nev = (int(v) for v in head)
        if (cyclic, hermitian, perturbation) != (0, 1, 0) or nev != N_MODES:
            raise RuntimeError(f"{path}: unexpected header {head.tolist()}")
        return np.frombuffer(f.read(8 * nev), dtype=np.float64).copy()


def transient_history(blocks, quantity, probes):
    """times (n) and values (len(probes) x n x 3) of one quantity of the PROBES blocks."""
    sel = [b for b in blocks if b[0] == quantity and b[1] == "PROBES"]
    times = np.array([b[2] for b in sel])
    values = np.array([[b[3][v] for b in sel] for v in probes])
    return times, values


def check_ccx_log(stdout, name):
    work = re.findall(r"work performed by the damping forces\s*=\s*(\S+)", stdout)
    if len(work) != STEPS or any(float(w) != 0.0 for w in work):
        raise RuntimeError(f"{name}: damping work {work[:3]}... over {len(work)} increments")


# ------------------------------------------------------------------------------------------
# Cross-check: dense numpy FEM

HEX_REF = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)  # VTK order
GAUSS = 1.0 / np.sqrt(3.0)


def elasticity(E, nu):
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = np.zeros((6, 6))
    C[:3, :3] = lam
    C[range(6), range(6)] += [2 * mu] * 3 + [mu] * 3  # Voigt xx yy zz xy yz zx, engineering
    return C


def assemble(p):
    """K, M (consistent) and f (gravity + pressure) of the whole mesh, 3 DOFs per node."""
    X, E, mids = p["nodes"], p["elements"], p["material_ids"]
    n = 3 * len(X)
    K, M, f = np.zeros((n, n)), np.zeros((n, n)), np.zeros(n)
    points = [np.array([a, b, c]) for a in (-GAUSS, GAUSS) for b in (-GAUSS, GAUSS)
              for c in (-GAUSS, GAUSS)]
    for e, conn in enumerate(E):
        mat = ref.MATERIALS[int(mids[e])]
        C, rho = elasticity(mat["E"], mat["nu"]), mat["density"]
        dofs = (3 * conn[:, None] + np.arange(3)).ravel()
        Ke, Me, fe = np.zeros((24, 24)), np.zeros((24, 24)), np.zeros(24)
        for xi in points:
            factors = 1 + HEX_REF * xi
            N = factors.prod(axis=1) / 8
            dN = np.stack([HEX_REF[:, d] * np.delete(factors, d, axis=1).prod(axis=1) / 8
                           for d in range(3)], axis=1)
            J = X[conn].T @ dN
            w = np.linalg.det(J)
            G = dN @ np.linalg.inv(J)
            B = np.zeros((6, 24))
            for a in range(8):
                gx, gy, gz = G[a]
                B[:, 3 * a:3 * a + 3] = [[gx, 0, 0], [0, gy, 0], [0, 0, gz],
                                         [gy, gx, 0], [0, gz, gy], [gz, 0, gx]]
            Ke += B.T @ C @ B * w
            Me += rho * np.kron(np.outer(N, N), np.eye(3)) * w
            fe += rho * np.kron(N, ref.GRAVITY) * w
        K[np.ix_(dofs, dofs)] += Ke
        M[np.ix_(dofs, dofs)] += Me
        f[dofs] += fe
    for e, face in p["faces"]:  # traction -p n on the x = 2 faces, 2x2 Gauss
        local = ref.CCX_FACES["hex"][face - 1]
        q = X[E[e][list(local)]]
        for s in (-GAUSS, GAUSS):
            for t in (-GAUSS, GAUSS):
                N = np.array([(1 - s) * (1 - t), (1 + s) * (1 - t), (1 + s) * (1 + t),
                              (1 - s) * (1 + t)]) / 4
                ds = np.array([-(1 - t), 1 - t, 1 + t, -(1 + t)]) / 4
                dt = np.array([-(1 - s), -(1 + s), 1 + s, 1 - s]) / 4
                normal = np.cross(q.T @ ds, q.T @ dt)
                area = np.linalg.norm(normal)
                outward = -normal / area  # ccx faces: the right-hand normal points inward
                for a in range(4):
                    f[3 * E[e][local[a]]:3 * E[e][local[a]] + 3] += (
                        -ref.PRESSURE * outward * N[a] * area)
    return K, M, f


def generalized_eigh(K, M, k):
    try:
        import scipy.linalg
        lam, phi = scipy.linalg.eigh(K, M, subset_by_index=[0, k - 1])
        return lam, phi, "scipy.linalg.eigh"
    except ImportError:
        L = np.linalg.cholesky(M)
        A = np.linalg.solve(L, np.linalg.solve(L, K).T).T
        lam, y = np.linalg.eigh((A + A.T) / 2)
        return lam[:k], np.linalg.solve(L.T, y[:, :k]), "numpy eigh (Cholesky-reduced)"


def newmark(K, M, f, a0, steps=STEPS, dt=DT):
    """Newmark beta = 1/4, gamma = 1/2 from rest with the constant load f and the given a0:
    u_n, v_n for n = 1 .. steps. With M a0 = f it is the midpoint rule of the docstring."""
    A = M + dt * dt / 4 * K
    u, v, a = np.zeros(len(f)), np.zeros(len(f)), a0
    us, vs = [], []
    for _ in range(steps):
        a_new = np.linalg.solve(A, f - K @ (u + dt * v + dt * dt / 4 * a))
        u = u + dt * v + dt * dt / 4 * (a + a_new)
        v = v + dt / 2 * (a + a_new)
        a = a_new
        us.append(u)
        vs.append(v)
    return np.array(us), np.array(vs)


def midpoint(K, M, f, steps=STEPS, dt=DT):
    """The implicit midpoint rule of the docstring, written as such: u_n, v_n, n = 1 .. steps."""
    A = M + dt * dt / 4 * K
    u, v = np.zeros(len(f)), np.zeros(len(f))
    us, vs = [], []
    for _ in range(steps):
        du = np.linalg.solve(A, dt * (M @ v) + dt * dt / 2 * (f - K @ u))
        v = 2 * du / dt - v
        u = u + du
        us.append(u)
        vs.append(v)
    return np.array(us), np.array(vs)


def rel_max(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


def off_printed_digits(x, printed):
    """How many values differ from the printed E13.6 ones by more than half a unit in their last
    digit (plus 1e-12 of the largest)."""
    v = np.abs(printed)
    half_ulp = np.where(v > 0, 5e-7 * 10.0 ** np.floor(np.log10(np.where(v > 0, v, 1))), 0)
    return int(np.sum(np.abs(x - printed) > half_ulp * (1 + 1e-9) + 1e-12 * v.max()))


# ------------------------------------------------------------------------------------------


def record(p, version, solver, probes, eig, table, modes, times, u, v):
    return {
        "name": "hex_dynamics",
        "description": "natural frequencies and the transient under suddenly applied gravity and "
                       "pressure of the hex problem of hex.json (heterogeneous box clamped at "
                       "x = 0), solved by CalculiX; made by "
                       "scripts/calculix/make_dynamics_reference.py",
        "ccx": {"version": version, "element_type": "C3D8", "solver": solver,
                "output": "eigenvalues: full double precision from the .eig file; printed "
                          "eigenvalues, frequencies, mode shapes, u and v: 7 significant digits"},
        "ccx_version": version,
        "element": "hex",
        "grid": {"min": ref.LO, "max": ref.HI, "cells": ref.CELLS},
        "nodes": p["nodes"].tolist(),
        "elements": p["elements"].tolist(),
        "material_ids": p["material_ids"].tolist(),
        "material_field": p["field"],
        "materials": {str(k): val for k, val in ref.MATERIALS.items()},
        "gravity": ref.GRAVITY,
        **ref.conditions_record(p),
        "frequency": {
            "note": "K phi = omega^2 M phi on the free DOFs, consistent mass, no loads; "
                    "eigenvalues omega^2 (1/time^2) to full double precision (ccx .eig file); "
                    "frequencies_hz = sqrt(omega^2) / (2 pi) in cycles per time unit, computed "
                    "from them; *_printed: ccx's .dat table (7 significant digits); modes: "
                    "[mode][probe][x, y, z], ccx's *NODE PRINT U of each eigenmode (7 significant "
                    "digits), normalized to phi^T M phi = 1, sign arbitrary per mode",
            "count": N_MODES,
            "eigenvalues": eig.tolist(),
            "frequencies_hz": (np.sqrt(eig) / (2 * np.pi)).tolist(),
            "eigenvalues_printed": table[:, 0].tolist(),
            "frequencies_hz_printed": table[:, 1].tolist(),
            "probe_nodes": [int(x) for x in probes],
            "modes": modes.tolist(),
        },
        "transient": {
            "note": "loads (gravity and pressure) on at t = 0 and held, from rest, no damping, "
                    "linear geometry; implicit midpoint rule u_{n+1} = u_n + dt/2 (v_n + v_{n+1}), "
                    "M (v_{n+1} - v_n) = dt (f - K (u_n + u_{n+1}) / 2) (= Newmark 1/4, 1/2 with "
                    "M a0 = f); times = n dt, n = 1 .. steps (no entry for t = 0, where "
                    "u = v = 0); "
                    "u, v: [probe][time][x, y, z], ccx's *NODE PRINT U and V (7 significant "
                    "digits)",
            "dt": DT,
            "steps": STEPS,
            "times": times.tolist(),
            "probe_nodes": [int(x) for x in probes],
            "u": u.tolist(),
            "v": v.tolist(),
        },
    }


def main():
    args, version, workdir = ref.prepare(__doc__.split("\n")[0], "ccx_dyn_")
    p = ref.make_problem("hex")
    nodes = p["nodes"]
    probes = [int(np.nonzero(np.all(np.abs(nodes - np.asarray(x)) < ref.EPS, axis=1))[0][0])
              for x in PROBE_POINTS]
    model, dloads = model_and_loads(workdir, p)

    # Frequencies.
    with open(os.path.join(workdir, "hex_frequency.inp"), "w") as f:
        f.write(frequency_deck(model))
    stdout = ref.run_ccx(workdir, "hex_frequency")
    solver = ref.ccx_solver(stdout)
    table = parse_eigenvalue_table(os.path.join(workdir, "hex_frequency.dat"))
    eig = read_eig(os.path.join(workdir, "hex_frequency.eig"))
    mode_blocks = [b for b in parse_blocks(os.path.join(workdir, "hex_frequency.dat"))
                   if b[0] == "displacements"]
    assert table.shape == (N_MODES, 2) and len(mode_blocks) == N_MODES
    modes = np.array([[b[3][v] for v in probes] for b in mode_blocks])
    freq_hz = np.sqrt(eig) / (2 * np.pi)
    if off_printed_digits(eig, table[:, 0]) or off_printed_digits(freq_hz, table[:, 1]):
        sys.exit("error: the .eig eigenvalues do not round to the printed ones")

    # Transients: the midpoint deck (stored) and the amplitude-1 deck (a check of ccx's a0).
    runs = {}
    for name, amplitude in (("hex_transient", midpoint_amplitude()),
                            ("hex_transient_constant", constant_amplitude())):
        with open(os.path.join(workdir, name + ".inp"), "w") as f:
            f.write(transient_deck(model, dloads, probes, amplitude))
        out = ref.run_ccx(workdir, name)
        check_ccx_log(out, name)
        blocks = parse_blocks(os.path.join(workdir, name + ".dat"))
        times, u = transient_history(blocks, "displacements", probes)
        times_v, v = transient_history(blocks, "velocities", probes)
        if not (np.array_equal(times, DT * np.arange(1, STEPS + 1)) and
                np.array_equal(times, times_v)):
            sys.exit(f"error: {name}: output times {times[:3]} ... are not n dt, n = 1 .. {STEPS}")
        runs[name] = (times, u, v)

    # Cross-check.
    K, M, f = assemble(p)
    fixed_dofs = (3 * p["fixed"][:, None] + np.arange(3)).ravel()
    free = np.setdiff1d(np.arange(3 * len(nodes)), fixed_dofs)
    Kf, Mf, ff = K[np.ix_(free, free)], M[np.ix_(free, free)], f[free]
    with open(os.path.join(args.out, "hex.json")) as fh:
        u_static = np.asarray(json.load(fh)["displacements"]).ravel()
    u_mine = np.zeros(3 * len(nodes))
    u_mine[free] = np.linalg.solve(Kf, ff)
    checks = {"statics vs hex.json": rel_max(u_mine, u_static)}

    lam, phi, eigensolver = generalized_eigh(Kf, Mf, N_MODES)
    checks["eigenvalues vs .eig"] = float(np.abs(lam / eig - 1).max())
    checks["eigenvalues vs printed"] = float(np.abs(lam / table[:, 0] - 1).max())
    checks["frequencies vs printed"] = float(np.abs(np.sqrt(lam) / (2 * np.pi) / table[:, 1]
                                                    - 1).max())
    where = {dof: i for i, dof in enumerate(free)}
    probe_rows = np.array([[where[3 * v + d] for d in range(3)] for v in probes])
    mode_err = 0.0
    for k in range(N_MODES):
        mine = phi[probe_rows, k]
        scale = np.abs(modes[k]).max()
        mode_err = max(mode_err, min(np.abs(mine - s * modes[k]).max() for s in (1, -1)) / scale)
    checks["mode shapes at probes"] = mode_err

    u_mid, v_mid = midpoint(Kf, Mf, ff)
    u_mid, v_mid = u_mid[:, probe_rows].transpose(1, 0, 2), v_mid[:, probe_rows].transpose(1, 0, 2)
    _, u_ccx, v_ccx = runs["hex_transient"]
    checks["transient u vs midpoint"] = rel_max(u_mid, u_ccx)
    checks["transient v vs midpoint"] = rel_max(v_mid, v_ccx)
    off_digits = off_printed_digits(u_mid, u_ccx) + off_printed_digits(v_mid, v_ccx)

    _, u_const, _ = runs["hex_transient_constant"]
    eps = 0.25 * (DT / 10) ** 2  # beta (1 + alpha) (dt / 10)^2
    u_doped, _ = newmark(Kf, Mf, ff, np.linalg.solve(Mf + eps * Kf, ff))
    u_doped = u_doped[:, probe_rows].transpose(1, 0, 2)
    const_vs_mid = rel_max(u_mid, u_const)
    const_vs_doped = rel_max(u_doped, u_const)

    print(f"cross-check ({eigensolver}):")
    for key, val in checks.items():
        print(f"  {key:28s} {val:.2e}")
    print(f"  transient u, v components off the printed digits: {off_digits}")
    print(f"  amplitude-1 deck vs midpoint {const_vs_mid:.2e}, vs Newmark with ccx's a0 "
          f"{const_vs_doped:.2e}")
    limits = {"mode shapes at probes": 2e-6}
    bad = [k for k, val in checks.items() if val > limits.get(k, 1e-6)]
    if bad or off_digits or const_vs_doped > 1e-6:
        sys.exit(f"error: the cross-check fails: {bad}, {off_digits} digits off, "
                 f"amplitude-1 deck {const_vs_doped:.2e}")

    times, u, v = runs["hex_transient"]
    path = os.path.join(args.out, "hex_dynamics.json")
    with open(path, "w") as fh:
        json.dump(record(p, version, solver, probes, eig, table, modes, times, u, v), fh,
                  separators=(",", ":"))
        fh.write("\n")
    print(f"{path}: {N_MODES} eigenvalues (first {eig[0]!r}, f = {freq_hz[0]:.7e}), "
          f"{STEPS} steps of {DT} at {len(probes)} probes, max |u| = {np.abs(u).max():.6e}, "
          f"ccx {version} ({solver})")
    if not args.keep:
        shutil.rmtree(workdir)


if __name__ == "__main__":
    main()
