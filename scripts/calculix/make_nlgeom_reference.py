#!/usr/bin/env python3
"""Reference large-deflection cantilever from CalculiX's (ccx) geometrically nonlinear statics.

What this produces
------------------
tests/data/calculix/cantilever_nlgeom.json: a slender homogeneous cantilever bent far beyond the
range of linear theory by its own weight, solved by CalculiX both geometrically nonlinearly
(NLGEOM, at ten load levels) and linearly, as an independent reference for large-deflection
solvers (e.g. corotational linear elasticity, which agrees with the model below to first order
in the strain).

  mesh      box [0,10] x [0,0.5] x [0,0.5] (length L = 10 along x, square section h = 0.5),
            regular 40 x 4 x 4 grid of C3D8 bricks (trilinear, full 2x2x2 Gauss: not C3D8R or
            C3D8I), 1025 nodes, 640 elements, numbered as mesh::make_grid does
            (make_reference.make_grid; Hex8 corners in VTK order).
  material  one isotropic material E = 1e5, nu = 0.3, density 1.
  clamp     every node on x = 0 (25 nodes), all three components zero.
  load      gravity g = (0, 0, -6) as a dead body load (density g per unit reference volume),
            scaled by the load factor lambda = 0.1, 0.2, ..., 1.
Beam numbers: A = h^2 = 0.25, I = h^4 / 12 = 5.2083e-3, q = density |g| A = 1.5, EI = 520.83;
Euler-Bernoulli tip deflection q L^4 / (8 EI) = 3.6 = 0.36 L and tip rotation
q L^3 / (6 EI) = 0.48 rad at lambda = 1. |g| = 6 was chosen so that ccx's linear tip deflection
is about L / 3 (it is 3.234 = 0.32 L: the Q1 mesh is stiffer than the beam, see below).

How CalculiX is driven
----------------------
- The model part of both decks (nodes, C3D8 elements in ELSET M1, *MATERIAL with *ELASTIC and
  *DENSITY, the clamped node set) and the gravity load (*DLOAD with M1, GRAV, 6.0, 0.0, 0.0,
  -1.0) are those make_reference.write_inp writes; ccx ids are our 0-based indices + 1.
- linear.inp: write_inp's step (*STATIC without NLGEOM, so geometrically linear) with
  *EL PRINT E added.
- nlgeom.inp: *STEP, NLGEOM, INC=100 with *STATIC, DIRECT and "0.1, 1.0": fixed increments of
  0.1 of the step time 1 (no automatic incrementation; a static load ramps linearly over the
  step, so the time is the load factor). All ten increments converged at the first attempt, so
  0.05 was not needed. *NODE PRINT, NSET=NALL, FREQUENCY=1 with U and *EL PRINT, ELSET=M1,
  FREQUENCY=1 with E print every increment (times 0.1 .. 1, checked against LOAD_FACTORS).
- *CONTROLS, PARAMETERS=FIELD with R_n = C_n = R_p = 1e-8 (largest residual force relative to the
  average force, largest displacement correction relative to the increment's displacement, and
  R_n's replacement after 9 iterations; the defaults are 0.005, 0.01 and 0.02). With the
  defaults ccx accepted the increments ending at 0.2, 0.3 and 0.4 after two Newton iterations,
  2.3e-5 .. 5.0e-5 of max|u| away from the converged solution (measured when this was
  written); with the tight criteria every increment takes three iterations and ends within
  about a unit of the 7th digit of the converged solution (cross-check 1).
- What ccx solves with NLGEOM and a linear *ELASTIC material: a total-Lagrangian St. Venant-
  Kirchhoff model (CalculiX source and manual, read in the current repository; cross-check 1
  confirms it for ccx 2.20 to about the 7th digit). calctotstrain.f adds the quadratic terms to the
  strain when NLGEOM is on, giving the Green-Lagrange strain E = (F^T F - I) / 2 from the gradient
  with respect to the reference coordinates; linel.f returns S = C : E with C the isotropic
  Hooke tensor, S the second Piola-Kirchhoff stress (manual, "Linear elastic materials": "a
  linear elastic relationship between the Lagrange strain and the Piola-Kirchhoff stress of the
  second kind"; "Static analysis": total Lagrangian, all variables in the material frame).
  GRAV is integrated over the reference volume with the reference density in e_c3d.f (only
  centrifugal loads use the current coordinates), so it is a dead load (a pressure *DLOAD P
  would follow the deformed surface). *EL PRINT E prints the Lagrange strain with NLGEOM, the
  small strain without, as exx, eyy, ezz, exy, exz, eyz with tensor shears.
- Output: U printed as E13.6 (7 significant digits), stored as printed. ccx's linear solver on
  Debian 12 (calculix-ccx 2.20) is SPOOLES. Run times when this was written (2 cores): linear
  0.2 s, NLGEOM 3.4 .. 3.7 s; the whole script about 20 s (mostly the numpy cross-check).

Results at the tip centre node (10, 0.25, 0.25) (node 532), linear uz = lambda uz_lin(1);
rotation of the tip section from the tip's top and bottom centre nodes (atan of the deformed
x over z difference; linear: the x difference over h):

    lambda  linear uz  NLGEOM ux  NLGEOM uz  uz NL/lin  ux / L    rotation lin  NLGEOM
     0.1    -0.323441  -0.005974  -0.323172   0.9992   -0.0006       0.0431    0.0431
     0.2    -0.646881  -0.023803  -0.644743   0.9967   -0.0024       0.0862    0.0860
     0.3    -0.970322  -0.053204  -0.963157   0.9926   -0.0053       0.1294    0.1286
     0.4    -1.293762  -0.093727  -1.276950   0.9870   -0.0094       0.1725    0.1708
     0.5    -1.617203  -0.144768  -1.584784   0.9800   -0.0145       0.2156    0.2123
     0.6    -1.940643  -0.205603  -1.885474   0.9716   -0.0206       0.2587    0.2531
     0.7    -2.264083  -0.275411  -2.178012   0.9620   -0.0275       0.3019    0.2931
     0.8    -2.587524  -0.353313  -2.461572   0.9513   -0.0353       0.3450    0.3321
     0.9    -2.910965  -0.438395  -2.735510   0.9397   -0.0438       0.3881    0.3701
     1.0    -3.234405  -0.529737  -2.999363   0.9273   -0.0530       0.4312    0.4071

The linear tip ux is -2.2e-14 (zero up to round-off: the tip centre lies on the neutral axis),
its uy 4.8e-11. Mid-span centre (5, 0.25, 0.25) (node 512) at lambda = 1: linear uz = -1.14435,
NLGEOM (ux, uz) = (-0.1446693, -1.075795).
Strains at lambda = 1 over all 2x2x2 Gauss points (ccx's *EL PRINT E): NLGEOM Green-Lagrange
principal strains in [-0.0270, 0.0267] (largest in element 521, near the root on the top face),
max |E_ij| = 0.0265; linear small strain principal values in [-0.0279, 0.0279], max |eps_ij|
0.0274.

Cross-checks (on every run; the script fails if check 1 gets worse than 1e-6)
---------------------------------------------------------------------------
1. The same discrete problems solved here: a vectorized numpy total-Lagrangian St. Venant-
   Kirchhoff Q1 FEM (ccx's 2x2x2 Gauss points, C from make_dynamics_reference.elasticity,
   internal forces int dE : S dV0 and the consistent tangent, material + geometric, assembled
   with scipy.sparse if available, else dense; the dead load rho g N_a on the reference
   volume), solved by Newton to |du| <= 1e-12 |u| at each load factor, and its tangent at
   u = 0 for the linear problem.
   Measured when this was written, max |difference| / max |ccx u|:
       linear 1.5e-7;  NLGEOM 4.3e-7 (lambda = 0.1), 0.6e-7 .. 4.0e-7 (lambda = 0.2 .. 1),
   i.e. 1.0 (linear) and 1.0 .. 1.3 (lambda >= 0.2) half units of the last printed digit of
   max |u|, 2.8 at lambda = 0.1: ccx stops when its estimate of the next correction is small,
   so its last Newton iterate can still differ from the converged one in the 7th digit.
   ccx's printed strains against the strains of these solutions: Green-Lagrange at lambda = 1
   2.2e-7, linear 1.8e-7 of the largest (this also pins ccx's component order, tensor shears
   and integration point order: xi fastest, then eta, then zeta).
2. Beam theory (informative): ccx's linear tip deflection is 0.8984 of Euler-Bernoulli's; the
   Q1 bricks with full integration lock in bending (shear deformation, which would make the
   beam softer, adds only about 0.3 %: q L^2 / (2 kappa G A) = 0.0094). The inextensible
   elastica (shear-rigid beam under a dead vertical load q per unit length: theta' = M / EI,
   M' = -q (L - s) cos theta, theta(0) = 0, M(L) = 0; RK4 + shooting) with the bending stiffness
   calibrated to ccx's linear tip, EI / 0.8984 = 579.70, gives at lambda = 1 the tip
   (ux, uz) = (-0.52893, -2.99801) against ccx's NLGEOM (-0.52974, -2.99936): 0.15 % and
   0.05 %, and the same NL / linear ratio 0.927 of the tip deflection. So both ccx results are
   stiffer than beam theory by the same factor, and the geometric nonlinearity is that of the
   elastica.

The json file
-------------
The problem in the format of hex.json (name "cantilever_nlgeom", description, ccx {version,
element_type, solver, output, nlgeom, newton_iterations}, ccx_version, element "hex", grid,
nodes, 0-based elements, material_ids, materials, gravity, pressure (value 0: none; the free
end's faces are listed only so that the conditions read as hex.json's), dirichlet), and:
    displacements          [node][x, y, z]  ccx's linear solution at lambda = 1 (linear in
                                             lambda)
    load_factors           [10]              0.1, 0.2, ..., 1
    nlgeom_displacements   [10][node][x, y, z]  ccx's NLGEOM solution at each load factor
    probes                 {name: {point, node}}  tip_centre, tip_top_centre,
                           tip_bottom_centre, three_quarter_span_centre, mid_span_centre,
                           quarter_span_centre (0-based node ids)
    strain                 the strain extremes above
    beam_theory            A, I, q, the Euler-Bernoulli tip deflection and rotation, ccx's
                           linear / Euler-Bernoulli ratio, the calibrated elastica's tips.

Rerun
-----
    python3 scripts/calculix/make_nlgeom_reference.py            # writes cantilever_nlgeom.json
    python3 scripts/calculix/make_nlgeom_reference.py --keep DIR # also keeps the .inp/.dat
Needs ccx and numpy like make_reference.py (/usr/bin/python3 on Debian); scipy's sparse solver
is used when available (python3-scipy), else numpy's dense one (3000 free DOFs, slower).
"""

import json
import os
import re
import shutil
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_dynamics_reference as dyn  # noqa: E402
import make_reference as ref  # noqa: E402

LENGTH, SIDE = 10.0, 0.5
LO, HI, CELLS = [0.0, 0.0, 0.0], [LENGTH, SIDE, SIDE], [40, 4, 4]
MATERIAL = {"E": 1.0e5, "nu": 0.3, "density": 1.0}
G = 6.0
GRAVITY = [0.0, 0.0, -G]
LOAD_FACTORS = [k / 10 for k in range(1, 11)]  # the ends of ccx's fixed increments 0.1
# ccx's field convergence criteria R_n, C_n, (q_0, q_u: defaults), R_p (see the docstring).
CONTROLS = "1e-8, 1e-8, , , 1e-8"
PROBES = {
    "tip_centre": (LENGTH, SIDE / 2, SIDE / 2),
    "tip_top_centre": (LENGTH, SIDE / 2, SIDE),
    "tip_bottom_centre": (LENGTH, SIDE / 2, 0.0),
    "three_quarter_span_centre": (0.75 * LENGTH, SIDE / 2, SIDE / 2),
    "mid_span_centre": (LENGTH / 2, SIDE / 2, SIDE / 2),
    "quarter_span_centre": (0.25 * LENGTH, SIDE / 2, SIDE / 2),
}
# ccx's 2x2x2 Gauss points (gauss3d2): xi fastest, then eta, then zeta.
GAUSS_POINTS = [np.array([a, b, c]) * dyn.GAUSS for c in (-1, 1) for b in (-1, 1)
                for a in (-1, 1)]
VOIGT = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0)]  # dyn.elasticity's order


def make_problem():
    nodes, elements = ref.make_grid("hex", LO, HI, CELLS)
    e = ref.EPS
    fixed_box = ([LO[0] - e, LO[1] - e, LO[2] - e], [LO[0] + e, HI[1] + e, HI[2] + e])
    tip_box = ([HI[0] - e, LO[1] - e, LO[2] - e], [HI[0] + e, HI[1] + e, HI[2] + e])
    probes = {name: int(np.nonzero(np.all(np.abs(nodes - np.asarray(x)) < e, axis=1))[0][0])
              for name, x in PROBES.items()}
    return dict(nodes=nodes, elements=elements, material_ids=np.ones(len(elements), int),
                fixed=np.nonzero(ref.in_box(nodes, *fixed_box))[0], fixed_box=fixed_box,
                tip_faces=ref.faces_in_box("hex", nodes, elements, *tip_box), tip_box=tip_box,
                probes=probes)


# ------------------------------------------------------------------------------------------
# Decks and ccx output


def write_decks(workdir, p):
    """linear.inp: make_reference's deck (one linear *STATIC step) with *EL PRINT E added;
    nlgeom.inp: the same model with a *STEP, NLGEOM of fixed increments 0.1."""
    linear = os.path.join(workdir, "linear.inp")
    ref.write_inp(linear, "hex", p["nodes"], p["elements"], p["material_ids"], {1: MATERIAL},
                  GRAVITY, [], 0.0, p["fixed"])
    with open(linear) as f:
        text = f.read()
    model, step = text.split("*STEP\n")
    m = re.search(r"\*DLOAD\n(.*?)\*NODE PRINT", step, re.S)
    assert m and "*BOUNDARY\nFIXED, 1, 3, 0.0\n" in step and step.endswith("*END STEP\n")
    with open(linear, "w") as f:
        f.write(text[:-len("*END STEP\n")] + "*EL PRINT, ELSET=M1\nE\n*END STEP\n")
    with open(os.path.join(workdir, "nlgeom.inp"), "w") as f:
        f.write(model + "*STEP, NLGEOM, INC=100\n*STATIC, DIRECT, SOLVER=SPOOLES\n0.1, 1.0\n"
                "*CONTROLS, PARAMETERS=FIELD\n" + CONTROLS + "\n"
                "*BOUNDARY\nFIXED, 1, 3, 0.0\n*DLOAD\n" + m.group(1) +
                "*NODE PRINT, NSET=NALL, FREQUENCY=1\nU\n"
                "*EL PRINT, ELSET=M1, FREQUENCY=1\nE\n*END STEP\n")


def parse_strains(dat_path, n_elements):
    """Every *EL PRINT E block of a .dat file: [(time, n_elements x 8 x 6)], the components
    exx, eyy, ezz, exy, exz, eyz (tensor shears) at ccx's integration points, as printed."""
    blocks = []
    with open(dat_path) as f:
        for line in f:
            m = re.match(r"\s*strains \(elem, integ\.pnt\.,exx,eyy,ezz,exy,exz,eyz\) for set "
                         r"\S+ and time\s+(\S+)", line)
            if m:
                blocks.append((float(m.group(1)), np.full((n_elements, 8, 6), np.nan)))
                continue
            parts = line.split()
            if blocks and len(parts) == 8 and parts[0].isdigit():
                blocks[-1][1][int(parts[0]) - 1, int(parts[1]) - 1] = [float(v) for v in parts[2:]]
    for t, e in blocks:
        if np.isnan(e).any():
            raise RuntimeError(f"{dat_path}: strains missing at time {t}")
    return blocks


def increment_log(stdout):
    """[(attempts, Newton iterations of the accepted attempt)] per increment of ccx's log."""
    out = []
    for chunk in re.split(r"\n increment \d+ attempt ", stdout)[1:]:
        attempt = int(chunk.split()[0])
        iterations = len(re.findall(r"\n iteration \d+", chunk))
        if attempt > 1:
            out[-1] = (attempt, iterations)
        else:
            out.append((attempt, iterations))
    return out


# ------------------------------------------------------------------------------------------
# Cross-check 1: a vectorized total-Lagrangian St. Venant-Kirchhoff Q1 FEM (2x2x2 Gauss)


def geometry(nodes, elements):
    """Shape values N (8 points x 8 nodes), reference gradients G (E x 8 x 8 x 3) and
    weights det J (E x 8) at ccx's Gauss points."""
    X = nodes[elements]
    N, dN = [], []
    for xi in GAUSS_POINTS:
        factors = 1 + dyn.HEX_REF * xi
        N.append(factors.prod(axis=1) / 8)
        dN.append(np.stack([dyn.HEX_REF[:, d] * np.delete(factors, d, axis=1).prod(axis=1) / 8
                            for d in range(3)], axis=1))
    N, dN = np.array(N), np.array(dN)
    J = np.einsum("eai,qaj->eqij", X, dN)
    G = np.einsum("qaj,eqji->eqai", dN, np.linalg.inv(J))
    return N, G, np.linalg.det(J)


class SvkModel:
    """Internal forces and tangent of S = C : E, E = (F^T F - I) / 2 (C from dyn.elasticity,
    Voigt with engineering shears), assembled with scipy.sparse (dense without scipy); dead
    gravity load."""

    def __init__(self, p):
        try:
            import scipy.sparse
            import scipy.sparse.linalg
            self.sparse, self.solve = scipy.sparse, scipy.sparse.linalg.spsolve
        except ImportError:
            self.sparse, self.solve = None, np.linalg.solve
        self.elements = p["elements"]
        self.N, self.G, self.w = geometry(p["nodes"], self.elements)
        self.C = dyn.elasticity(MATERIAL["E"], MATERIAL["nu"])
        self.n = 3 * len(p["nodes"])
        dofs = (3 * self.elements[:, :, None] + np.arange(3)).reshape(len(self.elements), 24)
        self.dofs = dofs
        self.rows = np.repeat(dofs, 24, axis=1).ravel()
        self.cols = np.tile(dofs, (1, 24)).ravel()
        fixed = (3 * p["fixed"][:, None] + np.arange(3)).ravel()
        self.free = np.setdiff1d(np.arange(self.n), fixed)
        body = MATERIAL["density"] * np.einsum("eq,qa->ea", self.w, self.N)
        self.f_ext = np.zeros(self.n)
        np.add.at(self.f_ext, dofs, np.einsum("ea,k->eak", body, GRAVITY).reshape(-1, 24))

    def strains(self, u):
        """Deformation gradients and Green strains (E x 8 x 3 x 3) at the Gauss points."""
        F = np.eye(3) + np.einsum("eak,eqaj->eqkj", u.reshape(-1, 3)[self.elements], self.G)
        return F, 0.5 * (np.einsum("eqki,eqkj->eqij", F, F) - np.eye(3))

    def forces_and_tangent(self, u):
        F, E = self.strains(u)
        ev = np.stack([E[..., i, j] * (1 if i == j else 2) for i, j in VOIGT], axis=-1)
        sv = ev @ self.C.T
        S = np.zeros_like(E)
        for v, (i, j) in enumerate(VOIGT):
            S[..., i, j] = S[..., j, i] = sv[..., v]
        B = np.empty(F.shape[:2] + (6, 8, 3))
        for v, (i, j) in enumerate(VOIGT):
            B[:, :, v] = np.einsum("eqk,eqa->eqak", F[..., :, i], self.G[..., j])
            if i != j:
                B[:, :, v] += np.einsum("eqk,eqa->eqak", F[..., :, j], self.G[..., i])
        f = np.einsum("eq,eqvak,eqv->eak", self.w, B, sv).reshape(-1, 24)
        CB = np.einsum("vw,eqwbl->eqvbl", self.C, B)
        K = np.einsum("eq,eqvak,eqvbl->eakbl", self.w, B, CB, optimize=True)
        K += np.einsum("eq,eqai,eqij,eqbj,kl->eakbl", self.w, self.G, S, self.G, np.eye(3),
                       optimize=True)
        f_int = np.zeros(self.n)
        np.add.at(f_int, self.dofs, f)
        if self.sparse is None:
            Kg = np.zeros((self.n, self.n))
            np.add.at(Kg, (self.rows, self.cols), K.reshape(len(K), -1).ravel())
            return f_int, Kg[np.ix_(self.free, self.free)]
        Kg = self.sparse.coo_matrix((K.reshape(len(K), -1).ravel(), (self.rows, self.cols)),
                                    shape=(self.n, self.n)).tocsc()
        return f_int, Kg[self.free][:, self.free]

    def linear(self):
        """The geometrically linear solution (tangent at u = 0) at load factor 1."""
        _, K = self.forces_and_tangent(np.zeros(self.n))
        u = np.zeros(self.n)
        u[self.free] = self.solve(K, self.f_ext[self.free])
        return u

    def newton(self, load_factors, tol=1e-12):
        """Equilibrium f_int(u) = lambda f_ext at each load factor, each started from the last;
        returns the displacements (per factor) and the iterations taken."""
        u, out, iterations = np.zeros(self.n), [], []
        for lam in load_factors:
            for it in range(1, 31):
                f_int, K = self.forces_and_tangent(u)
                du = self.solve(K, (lam * self.f_ext - f_int)[self.free])
                u[self.free] += du
                if np.abs(du).max() <= tol * np.abs(u).max():
                    break
            else:
                raise RuntimeError(f"numpy Newton: no convergence at load factor {lam}")
            out.append(u.copy())
            iterations.append(it)
        return np.array(out), iterations


# ------------------------------------------------------------------------------------------
# Cross-check 2: beam theory


def beam_constants():
    area, inertia = SIDE ** 2, SIDE ** 4 / 12
    q = MATERIAL["density"] * G * area
    return dict(area=area, I=inertia, q=q, EI=MATERIAL["E"] * inertia,
                tip_deflection=q * LENGTH ** 4 / (8 * MATERIAL["E"] * inertia),
                tip_rotation=q * LENGTH ** 3 / (6 * MATERIAL["E"] * inertia))


def elastica(q, EI, L=LENGTH, n=4000):
    """Tip (u_x, u_z) of the inextensible, shear-rigid cantilever (elastica) clamped at s = 0
    under the dead vertical load q per unit length (along -z): theta' = M / EI with
    M' = -q (L - s) cos theta, theta(0) = 0, M(L) = 0; RK4 in s and secant shooting on M(0)."""
    def shoot(m0):
        def rhs(s, y):  # theta, M, x, z
            return np.array([y[1] / EI, -q * (L - s) * np.cos(y[0]), np.cos(y[0]),
                             -np.sin(y[0])])
        y, h = np.array([0.0, m0, 0.0, 0.0]), L / n
        for i in range(n):
            s = i * h
            k1 = rhs(s, y)
            k2 = rhs(s + h / 2, y + h / 2 * k1)
            k3 = rhs(s + h / 2, y + h / 2 * k2)
            k4 = rhs(s + h, y + h * k3)
            y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return y
    a, b = q * L ** 2 / 2, 0.9 * q * L ** 2 / 2  # M(0) linear, and a guess below it
    ya, yb = shoot(a), shoot(b)
    for _ in range(50):
        if abs(yb[1]) < 1e-12 * q * L ** 2:
            return yb[2] - L, yb[3]
        a, b, ya = b, b - yb[1] * (b - a) / (yb[1] - ya[1]), yb
        yb = shoot(b)
    raise RuntimeError(f"elastica: no convergence for q = {q}")


# ------------------------------------------------------------------------------------------


def principal_strains(E):
    """Principal values (ascending) of strains stored as [..., (xx, yy, zz, xy, xz, yz)]."""
    T = np.stack([E[..., [0, 3, 4]], E[..., [3, 1, 5]], E[..., [4, 5, 2]]], axis=-2)
    return np.linalg.eigvalsh(T)


def ccx_voigt(E):
    """Green strains E (... x 3 x 3) in ccx's print order xx, yy, zz, xy, xz, yz."""
    return np.stack([E[..., 0, 0], E[..., 1, 1], E[..., 2, 2], E[..., 0, 1], E[..., 0, 2],
                     E[..., 1, 2]], axis=-1)


def main():
    args, version, workdir = ref.prepare(__doc__.split("\n")[0], "ccx_nlgeom_")
    p = make_problem()
    nodes, elements = p["nodes"], p["elements"]
    all_nodes = range(len(nodes))
    write_decks(workdir, p)

    seconds, logs = {}, {}
    for job in ("linear", "nlgeom"):
        start = time.perf_counter()
        logs[job] = ref.run_ccx(workdir, job)
        seconds[job] = time.perf_counter() - start
    solver = ref.ccx_solver(logs["nlgeom"])
    u_lin = ref.parse_displacements(os.path.join(workdir, "linear.dat"), all_nodes)
    e_lin = parse_strains(os.path.join(workdir, "linear.dat"), len(elements))
    blocks = [b for b in dyn.parse_blocks(os.path.join(workdir, "nlgeom.dat"))
              if b[0] == "displacements"]
    times = np.array([b[2] for b in blocks])
    if len(times) != len(LOAD_FACTORS) or not np.allclose(times, LOAD_FACTORS, rtol=0,
                                                          atol=1e-7):
        sys.exit(f"error: ccx's increments end at {times.tolist()}, not {LOAD_FACTORS}")
    u_nl = np.array([[b[3][v] for v in all_nodes] for b in blocks])
    e_nl = parse_strains(os.path.join(workdir, "nlgeom.dat"), len(elements))
    if [t for t, _ in e_nl] != times.tolist() or len(e_lin) != 1:
        sys.exit("error: the strain blocks do not match the displacement blocks")
    increments = increment_log(logs["nlgeom"])
    if len(increments) != len(LOAD_FACTORS) or any(a != 1 for a, _ in increments):
        sys.exit(f"error: ccx's increments (attempt, iterations): {increments}")

    # Cross-check 1: the same discrete problems solved here.
    model = SvkModel(p)
    mine_lin = model.linear().reshape(-1, 3)
    mine_nl, my_iterations = model.newton(LOAD_FACTORS)
    mine_nl = mine_nl.reshape(len(LOAD_FACTORS), -1, 3)
    checks = {"linear u": dyn.rel_max(mine_lin, u_lin)}
    checks.update({f"nlgeom u at {lam}": dyn.rel_max(mine_nl[k], u_nl[k])
                   for k, lam in enumerate(LOAD_FACTORS)})
    # ccx's printed strains against the strains of the solutions above (not of ccx's printed
    # displacements: differencing their 7 digits over a cell loses about 3 of them).
    _, E_nl = model.strains(mine_nl[-1].ravel())
    F_lin, _ = model.strains(mine_lin.ravel())
    eps_lin = 0.5 * (F_lin + F_lin.transpose(0, 1, 3, 2)) - np.eye(3)
    checks["nlgeom E (Green) at 1.0"] = dyn.rel_max(ccx_voigt(E_nl), e_nl[-1][1])
    checks["linear E (small strain)"] = dyn.rel_max(ccx_voigt(eps_lin), e_lin[0][1])
    print(f"ccx {version} ({solver}): linear {seconds['linear']:.2f} s, nlgeom "
          f"{seconds['nlgeom']:.2f} s, Newton iterations per increment "
          f"{[i for _, i in increments]} (numpy: {my_iterations})")
    print("cross-check, numpy total-Lagrangian St. Venant-Kirchhoff FEM, max |diff| / max |ccx|:")
    for key, val in checks.items():
        print(f"  {key:28s} {val:.2e}")
    if max(checks.values()) > 1e-6:
        sys.exit("error: the cross-check fails")

    # Cross-check 2: beam theory.
    beam = beam_constants()
    tip = p["probes"]["tip_centre"]
    ratio = -u_lin[tip, 2] / beam["tip_deflection"]
    stiff_EI = beam["EI"] / ratio
    print(f"beam: q = {beam['q']}, EI = {beam['EI']:.6g}, Euler-Bernoulli tip deflection "
          f"{beam['tip_deflection']:.6g} (rotation {beam['tip_rotation']:.6g} rad); "
          f"ccx linear / Euler-Bernoulli = {ratio:.6f}")
    top, bottom = p["probes"]["tip_top_centre"], p["probes"]["tip_bottom_centre"]
    elastica_tip = []
    print("  lambda  linear uz  nlgeom ux  nlgeom uz  uz nl/lin  rotation lin, nl | elastica "
          "(EI / ratio) ux, uz")
    for k, lam in enumerate(LOAD_FACTORS):
        lin_uz, ux, uz = lam * u_lin[tip, 2], u_nl[k, tip, 0], u_nl[k, tip, 2]
        d_nl = u_nl[k, top] - u_nl[k, bottom] + nodes[top] - nodes[bottom]
        ex, ez = elastica(lam * beam["q"], stiff_EI)
        elastica_tip.append([ex, ez])
        rot_lin = lam * (u_lin[top, 0] - u_lin[bottom, 0]) / SIDE
        print(f"  {lam:4.1f}  {lin_uz:9.6f}  {ux:9.6f}  {uz:9.6f}  {uz / lin_uz:.4f}     "
              f"{rot_lin:.4f}  {np.arctan2(d_nl[0], d_nl[2]):.4f}   | {ex:9.6f}  {ez:9.6f}")

    # Strains.
    p_lin = principal_strains(e_lin[0][1])
    p_nl = principal_strains(e_nl[-1][1])
    where = np.unravel_index(np.argmax(p_nl[..., 2]), p_nl.shape[:2])
    strain = {
        "note": "from ccx's *EL PRINT E at the 2x2x2 Gauss points of all elements at load "
                "factor 1: Green-Lagrange strain (nlgeom) and small strain (linear); principal "
                "values of the strain tensor (tensor shears exy = E_xy)",
        "nlgeom_max_principal": float(p_nl[..., 2].max()),
        "nlgeom_min_principal": float(p_nl[..., 0].min()),
        "nlgeom_max_abs_component": float(np.abs(e_nl[-1][1]).max()),
        "nlgeom_max_principal_at": {"element": int(where[0]), "ccx_integration_point":
                                    int(where[1]) + 1},
        "linear_max_principal": float(p_lin[..., 2].max()),
        "linear_min_principal": float(p_lin[..., 0].min()),
        "linear_max_abs_component": float(np.abs(e_lin[0][1]).max()),
    }
    print(f"strain: nlgeom Green principal in [{strain['nlgeom_min_principal']:.5f}, "
          f"{strain['nlgeom_max_principal']:.5f}] (max at element {where[0]}, point "
          f"{where[1] + 1}), max |E_ij| {strain['nlgeom_max_abs_component']:.5f}; linear "
          f"[{strain['linear_min_principal']:.5f}, {strain['linear_max_principal']:.5f}]")

    record = {
        "name": "cantilever_nlgeom",
        "description": "homogeneous cantilever [0,10]x[0,0.5]x[0,0.5] clamped at x = 0 under "
                       "dead gravity along -z, large deflection: CalculiX's geometrically "
                       "nonlinear (NLGEOM, total Lagrangian St. Venant-Kirchhoff) static "
                       "solution at load factors 0.1 .. 1 and its linear solution; made by "
                       "scripts/calculix/make_nlgeom_reference.py",
        "ccx": {"version": version, "element_type": "C3D8", "solver": solver,
                "output": "*NODE PRINT U, E13.6 (7 significant digits)",
                "nlgeom": "*STEP, NLGEOM; *STATIC, DIRECT with increments 0.1 of the load "
                          "(time = load factor); *CONTROLS, PARAMETERS=FIELD " + CONTROLS +
                          "; S (2nd Piola-Kirchhoff) = C : E (Green-Lagrange), dead body load "
                          "on the reference volume",
                "newton_iterations": [i for _, i in increments]},
        "ccx_version": version,
        "element": "hex",
        "grid": {"min": LO, "max": HI, "cells": CELLS},
        "nodes": nodes.tolist(),
        "elements": elements.tolist(),
        "material_ids": p["material_ids"].tolist(),
        "materials": {"1": MATERIAL},
        "gravity": GRAVITY,
        "pressure": {"value": 0.0, "traction": "-p n, n the outward normal",
                     "note": "no pressure: p = 0 on the free end x = 10, given only so that "
                             "the conditions have the format of hex.json",
                     "box": {"min": p["tip_box"][0], "max": p["tip_box"][1]},
                     "faces": [[e, f] for e, f in p["tip_faces"]],
                     "faces_note": "[element (0-based), ccx face number]"},
        "dirichlet": {"box": {"min": p["fixed_box"][0], "max": p["fixed_box"][1]},
                      "nodes": p["fixed"].tolist(), "value": [0.0, 0.0, 0.0],
                      "note": "clamp: every node on x = 0, all three components zero"},
        "displacements": u_lin.tolist(),
        "displacements_note": "geometrically linear solution at load factor 1 (ccx *STATIC "
                              "without NLGEOM); at load factor lambda it is lambda times this",
        "load_factors": LOAD_FACTORS,
        "nlgeom_displacements": u_nl.tolist(),
        "nlgeom_displacements_note": "[load factor][node][x, y, z]: the NLGEOM solution under "
                                     "lambda times gravity, lambda = load_factors",
        "probes": {name: {"point": list(PROBES[name]), "node": v}
                   for name, v in p["probes"].items()},
        "strain": strain,
        "beam_theory": {
            "note": "Euler-Bernoulli cantilever under q = density |g| A: tip deflection "
                    "q L^4 / (8 E I), tip rotation q L^3 / (6 E I), I = h^4 / 12; "
                    "ccx_linear_over_euler_bernoulli = -u_z(tip_centre) / tip deflection",
            "length": LENGTH, "side": SIDE, "area": beam["area"], "I": beam["I"],
            "q": beam["q"], "tip_deflection": beam["tip_deflection"],
            "tip_rotation": beam["tip_rotation"],
            "ccx_linear_over_euler_bernoulli": float(ratio),
            "elastica_note": "tip [u_x, u_z] per load factor of the inextensible elastica under "
                             "lambda q with the bending stiffness EI / "
                             "ccx_linear_over_euler_bernoulli (= elastica_EI), i.e. calibrated "
                             "to ccx's linear tip deflection",
            "elastica_EI": float(stiff_EI),
            "elastica_tip": elastica_tip,
        },
    }
    path = os.path.join(args.out, "cantilever_nlgeom.json")
    with open(path, "w") as fh:
        json.dump(record, fh, separators=(",", ":"))
        fh.write("\n")
    print(f"{path}: {len(nodes)} nodes, {len(elements)} C3D8, {len(LOAD_FACTORS)} load factors, "
          f"{os.path.getsize(path) / 1e6:.2f} MB")
    if not args.keep:
        shutil.rmtree(workdir)


if __name__ == "__main__":
    main()
