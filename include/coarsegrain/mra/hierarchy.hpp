#pragma once
/// @file The material-adapted hierarchy of refinable basis functions and wavelets (Chen et al.
/// 2019, Sec. 3, Algorithm 1) on nested regular grids.
///
/// Notation (shared/papers/NOTES.md): canonical quantities C^k, W^k, C^{k,†}; material-adapted
/// refinement C̃^k (the paper's outline C^k), stiffness A^k, wavelet stiffness B^k, basis Φ^k and
/// wavelets Ψ^k, expressed against the finest basis (Φ^q = I) and kept only on request
/// (Options::store_bases; basis() and reconstruct() otherwise). Level 1 is the coarsest, level q
/// the finest; step k builds level k from level k+1.
///
/// ## Dirichlet conditions (DirichletTreatment)
/// The fixed DOFs enter through the fine operator and are carried to every level. Measured on
/// the 32x32 bimaterial square hung from its top edge (contrast 2000, bilinear refinement, 5
/// levels, global solves; tests/mra/test_dirichlet.cpp prints the table), energy error of the
/// coarsest level ||u^1 - u||_A / ||u||_A and condition number of A^1:
///
/// | treatment       | linear: error | cond(A^1) | Dirac: error | cond(A^1)          |
/// |-----------------|---------------|-----------|--------------|--------------------|
/// | Eliminate       | 0.0713        | 839       | 0.4371       | 2.85e3             |
/// | Penalty (1e8)   | 0.0239/0.0240 | 1.52e3    | 0.4371       | 4.96e8 / 5.47e4    |
/// | DiagonalPenalty | 0.0239        | 1.52e3    | 0.4371       | 5.72e11            |
/// | Constrain       | 0.0239        | 1.52e3    | 0.4371       | 2.85e3             |
///
/// (x / y: material scale E x 1 / E x 1e4; the other rows do not depend on it.) Largest |u^1|
/// at fixed DOFs over max |u^1|: 0 for Eliminate and Constrain, 2e-10 for DiagonalPenalty,
/// 8e-9 / 8e-5 for Penalty.
///
/// - Eliminate: the fixed DOFs are removed from the fine operator, and coarse nodes lying on the
///   fixed boundary lose their DOFs. Exact, well conditioned, but the coarsest space is poorer.
/// - Penalty: the fixed DOFs are kept with `penalty` (1e8, as the authors' code) added to their
///   diagonal entries. The coarse nodes on the boundary keep basis functions, but the result
///   depends on the penalty relative to the stiffness (the coarse solution does not vanish at
///   fixed nodes when E is large) and cond(A^1) grows with the penalty.
/// - DiagonalPenalty: as Penalty with penalty * K_ii, independent of the material scale.
/// - Constrain (default): the fixed DOFs are removed from the fine operator as in Eliminate, but
///   coarse nodes on the fixed boundary keep their canonical measurement functions restricted to
///   the free DOFs (refinement_operators with keep_boundary_rows). This is the limit of the
///   penalty as it tends to infinity: the same richer coarse space, exactly zero at fixed DOFs,
///   without the penalty's conditioning. With Dirac refinement the restricted rows vanish and
///   Constrain coincides with Eliminate.
/// - Ignore: the boundary-blind construction the paper improves on (Chen et al. 2018; Sec. 1 and
///   Fig. 12): the hierarchy is built on the fine operator without any condition (fixed DOFs
///   kept, no penalty; B^k stays definite, as rigid motions are not in ker C^k), and a level is
///   constrained only when it is solved: its DOFs at the position of a fixed finest DOF
///   (fixed_positions) are held at zero. The basis functions do not vanish at the other fixed
///   finest DOFs, so reconstructions violate the conditions there, and the coarse model is
///   wrong near the fixed boundary: too stiff with linear refinement (Fig. 12's "spurious
///   structural rigidity"), too soft with Dirac: see "Boundary-blind construction" below.
///   Single-level solves only (MultilevelSolver::solve_levels needs m = 1).
///
/// ## Boundary-blind construction (DirichletTreatment::Ignore)
/// Chen et al. 2018 build their coarse shape functions without the Dirichlet conditions and fix
/// coarse nodes afterwards; Ignore reproduces that treatment of the conditions on this
/// hierarchy (not their discontinuous shape functions), as the baseline of Fig. 12. Nothing is
/// skipped by the invariance correction, so every A^k has exactly the rigid motions in its
/// kernel (tests/mra/test_boundary_blind.cpp: below 1e-14 relative); solves factorize A^k without
/// its fixed DOFs (free_operator). Measured on examples/pinned_beam (a homogeneous 4x1x1 beam
/// clamped at both ends, 32x8x8 hexes, 3 levels to 8x2x2, global solves; coarsest level
/// against the fine solve; tests/examples/test_pinned_beam.cpp):
///
/// | refinement | dirichlet | energy error | compliance ratio |
/// |------------|-----------|--------------|------------------|
/// | linear     | constrain | 0.0094       | 0.9999           |
/// | linear     | ignore    | 0.367        | 0.659            |
/// | Dirac      | constrain | 0.255        | 0.935            |
/// | Dirac      | ignore    | 1.22         | 2.47             |
///
/// With linear refinement the blind model is too stiff, the spurious rigidity of Fig. 12: the
/// free-body basis functions cannot form the clamped boundary layer. With Dirac refinement it
/// fails the other way: the interior basis functions do not vanish on the clamped faces between
/// the coarse nodes, so the beam is held at 9 points per end instead of whole faces, and sags
/// 2.5 times too much.
/// Only homogeneous conditions are supported (the fixed values must be zero).
///
/// ## Localization and truncation (Options::radius, radius_grid, truncation, invariance)
/// bench/bench_mra_localization tabulates the coarsest-level energy error ||u^1 - u||_A / ||u||_A
/// against the radius, on 32x32 grids hung from the top under gravity, 3 levels, bilinear
/// refinement (notes of issue 5 for all rows). "square": checker inclusions, contrast 2000;
/// "layered": vertical layers of width 1/8, E 100 vs 5e6. rho in rings of the fine (f) or
/// coarse (c) grid of each step; density = nonzero fraction of C̃ of the finest step; defect =
/// ||C̃ A W^T||_F / ||C^† A W^T||_F, the Eq. 12 defect of that step.
///
/// | construction                 | square err | layered err | density     | defect      |
/// |------------------------------|------------|-------------|-------------|-------------|
/// | global, tau = 0              | 0.0116     | 0.0349      | 1.00        | 0           |
/// | global, tau = 1e-7 (default) | 0.0116     | 0.0349      | 0.65 / 0.37 | 4e-7 / 3e-7 |
/// | global, tau = 1e-4           | 0.26       | 0.20        | 0.26 / 0.11 | 3e-4 / 2e-4 |
/// | rho = 2c (= 4f), corrected   | 0.98       | 0.998       | 0.11        | 0.02        |
/// | rho = 4c, corrected          | 0.78       | 0.996       | 0.26        | 1e-3 / 2e-3 |
/// | rho = 4c, no correction      | 0.85       | 0.055       | 0.26        | 1e-3 / 2e-3 |
/// | rho = 6c, corrected          | 0.16       | 0.997       | 0.44        | 5e-5 / 3e-4 |
/// | rho = 6c, no correction      | 0.27       | 0.036       | 0.44        | 5e-5 / 3e-4 |
/// | rho = 8c, corrected          | 0.013      | 0.038       | 0.62        | 4e-6 / 3e-5 |
///
/// Small radii fail on these problems because the coarsest error is the Eq. 12 defect amplified
/// many times: each localized basis function is close to the global one (defect 1e-3 at rho =
/// 4c), but a smooth displacement has large coefficients whose small per-function errors add up
/// (on the homogeneous square, contrast 1, two levels, rho = 2c gives 0.24 against 0.003
/// globally). About 1e-5 is needed to stay within 1.5x of the global error, which takes regions
/// as wide as the grid here. The invariance correction (minimum-norm change of C̃'s columns)
/// helps the inclusions but ruins the layered composite: the stiff layers, held at the top,
/// carry the Dirichlet condition down the whole height, where forcing exact rigid motions costs
/// stiff strain energy. Rings: with the linear refinement, an odd radius on the fine grid
/// selects the same wavelets as the even radius below it; the coarse count is twice the fine
/// count. Hence the defaults: global solves (one CHOLMOD factorization of B^k per step)
/// followed by truncation at 1e-7, which leaves the error unchanged and C̃ 35-63% sparser
/// (0.25 / 0.15 dense on 64x64, measured when the truncation still dropped entries one by one;
/// the two global rows above are by nodes, session 18: by entries they read 0.61 / 0.33 and
/// 0.34 / 0.21 error at 0.23 / 0.10 density for tau = 1e-4). A^k is not truncated (see
/// Options::truncation). The price is paid in 3D: on a 24x12x12 hex grid C̃ stays 63% dense and A^1
/// dense (bench/bench_mra), so localized radii (with per-step values, e.g. global for the coarse
/// steps) remain the option for large 3D models, at a much larger error.
///
/// Three experiments (session 19, not kept; 2D, node-wise, rho in coarse rings) on what the
/// correction should reproduce. (1) The global construction's combination of the rigid motions,
/// Ĉ^T (C r) with Ĉ from one factorization of B^k and 3 solves, applied at every node (none
/// skipped near the Dirichlet boundary), instead of exact rigid motions: 32x32, 3 levels, rho =
/// 6c: square 0.133 (the paper's rule 0.161), layered 0.193 (0.997; 0.036 without correction),
/// across 0.56 (0.93); with the affine fields too (6 modes) 0.110 / 0.178 / 0.246. (2)
/// Energy-minimizing bases (Xu and Zikatanov; Mandel, Brezina and Vaněk): the localized rows
/// that minimize the total energy sum_i ||φ_i||_A^2 subject to reproducing (1)'s targets, by
/// conjugate gradients on the Lagrange multipliers preconditioned with B^k (85-1800 iterations):
/// 16x16, 2 levels, rho = 4c / 6c: square 0.155 / 0.019 (no correction 0.238 / 0.025, global
/// 0.0128), layered 0.94 / 0.83 (0.51 / 0.14), across 0.84 / 0.84 (1.00 / 0.96). Neither is
/// within 1.5x of the global error on all three problems. (1) on the 3D checker of bench_mra
/// (40x20x20, rho 5 fine rings, patch 2 clipped): Dirac 0.778 (affine 0.757; the paper's rule
/// 0.790, no correction 0.702), linear 0.682 (0.682; 0.708, 0.500). (3) Correcting only the
/// columns whose rigid-motion residual is below tau of the target (a localization error rather
/// than a boundary effect), 32x32, rho = 4c / 6c: tau = 0.1: square 0.85 / 0.19, layered 0.78 /
/// 0.16; tau = 1e-3: square 0.85 / 0.27, layered 0.067 / 0.090 (all columns: 0.78 / 0.16 and
/// 0.996 / 0.997); the across case stays at 0.94-0.99. No threshold serves both.
///
/// ## Cell-wise localization (Options::localization)
/// Localization::Cell splits R by coarse cells, as the element correctors of Localized
/// Orthogonal Decomposition, with a left inverse that reproduces rigid motions (the library's
/// injection C^† does not; detail::rigid_left_inverse, linear refinement only). Same problems
/// and columns as the table above (bench_mra_localization 32 3 l, no truncation; err = coarsest
/// energy error with / without the invariance correction; dens = C̃ of the finest step; build
/// seconds, 1 thread, loaded machine):
///
/// | rho | square node  | square cell     | layered node  | layered cell | density   | build s   |
/// |-----|--------------|-----------------|---------------|--------------|-----------|-----------|
/// | 1c  | 0.99 / 0.96  | 0.72 / 0.80     | 0.998 / 0.73  | 0.96 / 0.96  | 0.05/0.18 | 0.06/0.4  |
/// | 2c  | 0.98 / 0.91  | 0.40 / 0.47     | 0.998 / 0.30  | 0.85 / 0.85  | 0.11/0.26 | 0.2/0.7   |
/// | 4c  | 0.78 / 0.85  | 0.071 / 0.073   | 0.996 / 0.055 | 0.65 / 0.65  | 0.26/0.44 | 0.6/1.5   |
/// | 6c  | 0.16 / 0.27  | 0.0117 / 0.0117 | 0.997 / 0.036 | 0.41 / 0.41  | 0.44/0.62 | 0.7/2.1   |
///
/// (density and build: node / cell, square; global: 0.0116 / 0.0349.) On the inclusions cell-wise
/// localization reaches the global error at 6c and is 10x more accurate than node-wise at 4c, and
/// the invariance correction no longer matters (the construction reproduces rigid motions by itself
/// away from the boundary). On the layered composite it behaves like the invariance correction
/// (same explanation) and is far worse than node-wise without correction. The accordion scene at
/// 32x8x8 (E 1e7 / 1e4, 3 levels, rho in fine rings, invariance on, truncation 1e-7, coarsest
/// error node / cell): linear rho = 1: 0.9999 / 0.992, 2: 0.999 / 0.992, 3: 0.999 / 0.992 (level 2:
/// 0.997 / 0.63), build 3 s / 25 s at rho = 2; Dirac (injection C^†) rho = 1: 0.81 / 0.99, 2: 0.98
/// / 0.93. With global solves at the coarse step and cell / node at the fine one: rho = 2: 0.63 /
/// 0.997, rho = 4: 0.72 / 0.999 (not monotonic; builds 26 s / 3 s and 70 s / 21 s). So it does not
/// cure the 3D locking. Costs: C̃ 2x denser and builds 2-8x longer than node-wise at the same rho
/// (one factorization per cell, regions one cell wider, right-hand sides through Φ^{k+1} at coarser
/// steps). With the dense Moore-Penrose C^† (an experiment) the square gave 0.83 / 0.45 / 0.095 /
/// 0.012 at 1c / 2c / 4c / 6c, at C̃ density 1.
///
/// In 3D (session 20: bench_mra N N N 2 rho 1e-7 fine linear 1 SCENE 1 node|cell, scenes in
/// bench/scenes, hung under gravity; checker = bench_mra's own problem; coarsest energy error;
/// trilinear = bench_mra's baseline, the trilinear FEM on the coarse grid; 2 threads, idle):
///
/// | problem          | global | node 2 / 5    | cell 2 / 3 / 5           | trilinear |
/// |------------------|--------|---------------|--------------------------|-----------|
/// | homogeneous 16^3 | 0.0112 | 0.694 / 0.475 | 0.0217 / 0.0213 / 0.0127 | 0.0759    |
/// | homogeneous 24^3 | 0.0061 | 0.626 / 0.459 | 0.0171 / 0.0168 / 0.0086 | 0.0574    |
/// | particles 16^3   | 0.0119 | 0.955 / 0.884 | 0.266 / 0.250 / 0.0946   | 0.968     |
/// | particles 24^3   | 0.0070 | 0.913 / 0.861 | 0.274 / 0.275 / 0.120    | 0.969     |
/// | checker 24x12x12 | 0.217  | - / 0.361     | 0.361 / 0.361 / 0.227    | 0.755     |
///
/// Builds in the same order (s): homogeneous 16^3 6.4; 0.9 / 4.7; 6.4 / 6.4 / 18.6. 24^3 113;
/// 3.2 / 16; 27 / 26 / 83. Particles 16^3 8.6; 1.0 / 4.6; 6.5 / 6.3 / 18. 24^3 135; 3.2 / 16;
/// 26 / 26 / 82. Checker 4.4; 3.3 (rho 5); 4.6 / 4.7 / 12.6.
///
/// The accordion beam at 64x16x16 (examples/accordion with 3 levels to 16x4x4: the fine step's
/// coarse cells are half a layer wide; session 21, `coarsen --method mra-linear`, coarsest
/// energy error): global solves 0.0111 (build 127 s, idle: the fine step's solves 53 s and its
/// A^2 61 s; session 22, A^2 by columns of M X: 44.5 s, with the solves at 74 s that day, build
/// 134 s); cell-wise rho = 2 fine rings with patch 2 at the fine step and global solves at the
/// coarse one 0.159 (build 124 s on a loaded machine: cell solves 37 s, C̃ 12 s, A^2 16 s, and
/// A^1 44 s, before the dense Galerkin product for a half-dense A^{k+1}). As in 2D, where two
/// coarse cells per layer need rho = 8 to 16 fine rings (0.21 at rho = 2: "Why the accordion
/// locks" below), rho = 2 is far from the global error.
///
/// The paper's node-wise localization loses to the trilinear FEM even on a homogeneous block, at
/// every radius that builds faster than global solves: each localized function has less energy
/// than the trilinear one (which is admissible), but each carries its own truncation error and a
/// smooth displacement adds them up (the amplification above); the invariance correction
/// removes only the rigid part of that sum. Cell-wise localization corrects a coarse field by the
/// sum of its cells' correctors, each driven by the field on one cell (Henning and Peterseim's
/// element correctors): 1.9-2.8x the global error from rho = 2 and 1.1-1.4x at rho = 5 on the
/// homogeneous block, 1.05x on the checker at rho = 5, but 8-17x on the isolated stiff
/// inclusions of contrast 1000 (particles.json), whose correctors decay slowly. It builds 4-8x
/// slower than node-wise at the same radius (one factorization per coarse cell with the
/// right-hand sides of ~27 coarse nodes, regions one coarse cell wider) and stores 2-3.8x more;
/// it is cheaper than global solves from ~24^3 cells on. Until session 20 its Z was summed from
/// triplets, ~10 per entry of Z (peaks of 4.4 / 11.0 GB at 16^3, rho = 3 / 5; now 0.67 / 1.57
/// GB).
///
/// Patches of cells (Options::patch with Localization::Cell: a block of patch^dim cells is one
/// part, with one region of rho rings around the block and one factorization for the sum of
/// its cells' right-hand sides) on Table 1's box (bench_mra 40 20 20 2 rho 1e-7 fine linear P
/// checker 1 cell; global solves 0.1716 in 137.8 s with 1.97 GB, node-wise rho = 5 0.58 in
/// 20-23 s with 361 MB; coarsest error, build s, storage MB, build peak GB):
///
/// | rho, patch | error  | x global | build s | localized solves s | A^1 s | storage | peak |
/// |------------|--------|----------|---------|--------------------|-------|---------|------|
/// | 3, 1       | 0.333  | 1.94     | 28.6    | 20.6               | 5.5   | 615     | 2.8  |
/// | 5, 1       | 0.1998 | 1.16     | 90.1    | 73.3               | 12.7  | 911     | 4.9  |
/// | 2 (= 3), 2 | 0.257  | 1.50     | 23.2-24.1 | 11.5-11.9        | 8.6-8.9 | 755-762 | 3.8-3.9 |
/// | 5, 2       | 0.1793 | 1.04     | 52.0    | 27.0               | 18.1  | 1042    | 5.4  |
/// | 2, 3       | 0.224  | 1.31     | 30.8    | 13.5               | 12.5  | 891     | 4.7  |
/// | 5, 3       | 0.1779 | 1.04     | 59.8    | 24.7               | 22.7  | 1185    | 7.3  |
/// | 1, 4       | 0.438  | 2.55     | 36.6    | 25.2               | 7.9   | 695     | 3.8  |
///
/// So cell-wise rho = 5 with patch 2 is as accurate as global solves here (1.04x) in 38% of
/// their time and 53% of their storage (58% and 63% of the global build with the dense Galerkin
/// product of session 21, 89.1 s and 1.64 GB), and rho = 2 with patch 2 meets the 1.5x
/// in 24 s; both are far from the paper's 15 s, and the Galerkin product A^1 with the wider C̃ is now a
/// third of the build. A patch 2 on the homogeneous block at 16^3, rho = 3: error 0.0180
/// against 0.0213 with patch 1, localized solves 2.4 s against 4.8 s, storage 143 against 124 MB.
///
/// Why the accordion locks: there every coarse cell of a step is exactly one layer, so each
/// coarse node sits on a stiff/soft interface and each stiff layer spans the cross-section. The
/// same happens in 2D (the accordion as a 4x1 quad beam, one step, cell-wise, coarsest error
/// against rho in fine rings): at 32x8 quads (one layer per coarse cell) rho = 2 / 4 / 8 / 16 /
/// 24 give 0.61 / 0.51 / 0.46 / 0.42 / 0.57, and only regions spanning the whole beam (32) give
/// the global 0.0005; at 64x16 (two coarse cells per layer) 0.21 / 0.072 / 0.014 / 0.0015 against
/// the global 0.0014. Node-wise without the correction at 64x16: 1.00 / 1.00 / 0.99 / 0.034 at
/// rho = 2 / 4 / 8 / 16.
///
/// How far the accordion's basis functions reach (session 22; the demo beam at 48x12x12 hexes, 3
/// levels, linear, node-wise at the fine step and global solves at the coarse one, invariance
/// on, truncation 1e-7; coarsest energy error, global 0.0027 in a 16-18 s build): rho = 6 / 12
/// fine rings 0.61 / 0.0031 (12.6 s for the fine step's solves, global 9 s). With regions
/// spanning the whole cross-section and rho rings along the axis only (an experiment, not kept):
/// rho = 2 / 4 / 8 / 12 give 0.92 / 0.44 / 0.039 / 0.0031 (`patch` 2 at rho = 8: 0.042). So the
/// regions must span the cross-section (the stiff layers move as plates) and about one length
/// unit along the axis, a quarter of this beam: at 80x20x20 hexes (107K DOFs) that is 20 fine
/// rings, regions nearly as large as the grid. A beam four times as long (16x1x1 at 192x12x12,
/// 98K DOFs, rho = 12) reached 0.0092 but built in 99 s (fine step's solves 41 s, A^2 19 s,
/// the coarse step's global solves 20 s, A^1 11 s), and `patch` 2 with `patch_clip` at rho = 5
/// on the 4x1x1 beam at 80x20x20 gave 0.99 (Dirac 0.85; naive averaging 0.92) in 40 / 24 s.
///
/// ## Stiffness-weighted measurements (Options::measurement)
/// Measurement::Stiffness weights the measurements of the finest step by the local stiffness
/// (weighted_refinement), as the contrast-robust quasi-interpolation of Peterseim and Scheichl
/// (2016). It makes the accordion case localize: the 2D accordion at 32x8, one step, cell-wise:
/// rho = 4 / 8 fine rings 0.11 / 0.012, equal to its global 0.012 at 8 (canonical: 0.51 / 0.46,
/// global 0.0005). The price is the coarse space: weighted measurements leave the soft layers'
/// deformation to the wavelets, and the global construction is less accurate. The 3D accordion
/// 32x8x8, one step, cell-wise: rho = 2 / 4 fine rings 0.41 / 0.145 (canonical 0.72 at 4, 0.74 at
/// 8), global 0.0118 (canonical 0.0017); three levels, rho = 4: 0.51 (level 2: 0.145), as the
/// coarser steps measure canonically again. On the localization study (bench_mra_localization
/// 32 3 m, 32x32, 3 levels, no truncation, coarsest error, canonical / stiffness):
///
/// | problem               | global          | cell 4c       | cell 6c        | node 6c, no corr. |
/// |-----------------------|-----------------|---------------|----------------|-------------------|
/// | checker square        | 0.0116 / 0.0267 | 0.071 / 0.042 | 0.0117 / 0.027 | 0.27 / 0.089      |
/// | layered along hanging | 0.035 / 0.107   | 0.65 / 0.62   | 0.41 / 0.26    | 0.036 / 0.29      |
/// | layered across        | 0.0041 / 0.0086 | 0.083 / 0.21  | 0.064 / 0.12   | 0.94 / 0.98       |
///
/// So it is an option for layers as thick as the coarse cells of the finest step (measured 0.006
/// against 0.60 in MraMeasurementLocalized), not a default. Weighting every step with the
/// diagonal of A^{k+1} (an experiment) fixed the 2D accordion's middle step at 64x16 (level 2:
/// 0.016 against 0.77) but not its coarsest step (0.80, global 0.021), and made A^1 of the 3D
/// accordion singular at rho = 2.
///
/// ## Defect-driven radius (Options::defect_tolerance, max_radius)
/// Each region starts at the step's radius and doubles it until its rows meet Eq. 12 to the
/// tolerance: ||(C̃ A W^T)[r, :]|| <= tol ||(C^† A W^T)[r, :]|| (the local solve zeroes the
/// defect on the region's wavelets; what remains is B's coupling across the region's border).
/// Measured (bench_mra_localization 64 3 d: 64x64 hung squares, 3 levels, bilinear, no
/// truncation, invariance correction, start 2 fine rings, max 128; err = coarsest
/// ||u^1 - u||_A / ||u||_A, rings = mean over the finest step's nodes, build s; 2 threads):
///
/// | problem        | global | fixed 8 / 16 rings | tol 1e-2 | 1e-3     | 1e-4     | 1e-5     |
/// |----------------|--------|--------------------|----------|----------|----------|----------|
/// | square, err    | 0.0047 | 0.76 / 0.039       | 0.90     | 0.83     | 0.78     | 0.041    |
/// | rings, build s | -, 8.2 | 8, 2.1 / 16, 12.5  | 10, 6.5  | 15, 13.3 | 22, 28.1 | 28, 38.4 |
/// | layered, err   | 0.016  | 0.97 / 0.087       | 0.97     | 0.83     | 0.78     | 0.025    |
/// | rings, build s | -, 8.4 | 8, 2.5 / 16, 10.9  | 10, 7.7  | 13, 12.3 | 16, 30.9 | 27, 42.8 |
/// | across, err    | 0.0018 | 0.94 / 0.31        | 0.97     | 0.94     | 0.95     | 0.033    |
/// | rings, build s | -, 7.2 | 8, 2.3 / 16, 11.1  | 10, 8.4  | 13, 16.3 | 16, 28.4 | 27, 39.3 |
///
/// The criterion works as specified, but on these problems it does not pay: the coarsest error
/// stays near 1 until the defect is ~1e-5 (tol 1e-4 still leaves 0.78 at a global defect of
/// 2e-5), and reaching it grows the regions to 27-28 rings, nearly the grid, for 5x the
/// global build (1.6x / 9x / 18x the global error). A fixed radius of 16 is as accurate on the
/// square for a third of that, but not on the layers (0.087 and 0.31). The reason is the
/// amplification described above: a small defect in every basis function adds up over the
/// smooth, large deformation. Off by default.
///
/// ## Clipped patches (Options::patch_clip)
/// A patch of 2^dim coarse nodes solves one system on the union of their regions (one
/// factorization instead of 2^dim), but each node's basis function then spreads over that
/// union: C̃ and A^k grow. Clipping keeps from the patch's solution only each node's own
/// wavelets (those of patch 1 at the same rho), so C̃ has patch 1's support, and the kept
/// coefficients are the patch's, not the minimizers on the smaller support. Measured
/// (bench_mra 40 20 20 2 5 1e-7 fine R P, Table 1's setting, 2 threads, idle; storage with W and
/// C^†; coarsest energy error with / without the invariance correction):
///
/// | refinement | patch      | build s | solves s | A^1 s | storage MB | error         |
/// |------------|------------|---------|----------|-------|------------|---------------|
/// | Dirac      | 1          | 13.1    | 11.0     | 1.5   | 235.5      | 0.790 / 0.704 |
/// | Dirac      | 2          | 7.1     | 4.2      | 2.2   | 355.5      | 0.762 / -     |
/// | Dirac      | 2, clipped | 5.2-6.1 | 3.4-3.9  | 1.3-1.6 | 235.5    | 0.790 / 0.702 |
/// | linear     | 1          | 23.1    | 19.4     | 2.8   | 360.5      | 0.582 / 0.444 |
/// | linear     | 2          | 12.9    | 7.6      | 4.1   | 465.5      | 0.492 / 0.412 |
/// | linear     | 2, clipped | 8.8-10.8 | 5.8-7.1 | 2.2-2.8 | 360.6    | 0.708 / 0.500 |
///
/// (This session's machine ran patch 1 15% slower than session 18's, 11.5 and 20.3 s.)
/// With the Dirac refinement clipping costs nothing in accuracy: patch 1's error and storage for
/// patch 2's factorizations, and A^1 nearly as fast as patch 1's. At 64^3 (bench_mra 64 64 64
/// 2 5 1e-7 fine dirac 2c): builds of 163.5 s (solves 113.3 s, A^1 36.5 s, invariance 4.3 s, B
/// 2.2 s; the full bench, after its fine reference's factorize 208.4 s + solve 2.8 s) and 175.7 s
/// (a build-only variant) with the first version (below), 145.6 s with the committed one (build
/// only; solves 95.1 s, A^1 35.1 s), 4.90 GB with W and C^† (C̃ 3.26e8 entries, as with patch
/// 1), build peak 15.7-16.6 GB, against 279.5-307.0 s for patch 1 and 252.5 s / 8.29 GB for
/// patch 2. The linear refinement at 64^3, patch 2 clipped (build only): 253.4 s (solves 147.5 s,
/// A^1 65.3 s, B 21.2 s, invariance 5.7 s), 7.43 GB (C̃ 4.23e8 entries, A^1's lower
/// triangle 2.61e8), build peak 22.8 GB, against 516.7 s and 7.41 GB with patch 1 (session 16).
/// Clipping also keeps the transient rows small: each node's rows are formed on its own wavelets
/// only (a first version formed them over the patch's and dropped the zeros afterwards, and was
/// killed by the kernel at 24.4 GB here). With the linear refinement the clipped functions lose
/// more (0.71 against 0.58), but it is the only setting measured here that builds Table 1's box
/// within both 15 s and 390 MB. A ring more (clipping at rho + 1) keeps nearly the whole patch
/// region with the linear refinement (460.2 MB, error 0.49). Other patch sizes, clipped (same
/// session): patch 3 Dirac 5.05 s (error 0.785), linear 8.0 s (0.708); patch 4 Dirac 9.25 s: beyond
/// 3 the regions' factorizations grow faster than their number falls. Smoothing the clipped rows by
/// symmetric Gauss-Seidel sweeps on each node's own system (an experiment) took the linear error
/// from 0.71 to 0.62 (2 sweeps) and 0.59 (10), but 2 sweeps cost as much as the factorizations they
/// save (solves 6.2 -> 14.6 s). Note the invariance correction's cost on this 3D checker: it raises
/// the coarsest error by 12% (Dirac) to 40% (linear clipped).
///
/// ## Cost in 3D (bench/bench_mra)
/// The accordion beam of examples/accordion (4x1x1, layers of E 1e5 / 1e2 across the axis,
/// clamped at x = 0, gravity), hex grids, 3 levels (coarsest = grid / 4), truncation 1e-7,
/// invariance correction, rho in fine rings, patch 1, OMP_NUM_THREADS=2 on a 2-core machine
/// loaded by 2-3 other jobs (times vary by 1.5x between runs). build = build_hierarchy; peak =
/// process high-water mark (includes the fine problem and its CHOLMOD solve, ~500 MB at
/// 64x16x16); speedup = fine factorize + solve over coarsest factorize + solve.
///
/// | grid     | refinement, rho | build s | peak MB | coarsest error | speedup |
/// |----------|-----------------|---------|---------|----------------|---------|
/// | 32x8x8   | linear, global  | 16.0    | 612     | 0.0029         | 37x     |
/// | 32x8x8   | Dirac, global   | 7.9     | 350     | 0.0156         | 121x    |
/// | 32x8x8   | linear, 2       | 5.0     | 136     | 0.999          | 40x     |
/// | 32x8x8   | Dirac, 2        | 0.8     | 80      | 0.977          | 77x     |
/// | 32x8x8   | Dirac, 1        | 0.7     | 69      | 0.81           | 254x    |
/// | 48x12x12 | linear, 2       | 27.5    | 514     | 0.994          | 22x     |
/// | 48x12x12 | Dirac, 2        | 2.7     | 278     | 0.978          | 69x     |
/// | 48x12x12 | Dirac, 1        | 2.6     | 231     | 0.984          | 102x    |
/// | 64x16x16 | linear, 2       | 78.6    | 1156    | 0.990          | 15x     |
/// | 64x16x16 | linear, 1       | 6.2     | 811     | 1.000          | 73x     |
/// | 64x16x16 | Dirac, 2        | 12.3    | 696     | 0.987          | 28x     |
/// | 64x16x16 | Dirac, 1        | 2.3     | 619     | 0.61           | 196x    |
///
/// (The speedups of this table predate session 13, when dense coarse operators still went
/// through CHOLMOD; LAPACK now factorizes them 2-6x faster: see "Table 1's setting" below.)
/// Builds are fast now, but on this cantilever every small radius fails: a coarsest error of
/// 0.6-1.0 means the coarse model hardly moves (locking), against 0.003 for global solves.
/// Larger regions do not help either within 20 s: on 32x8x8 with Dirac refinement, global solves
/// at the coarse step and rho = 2 / 4 / 6 at the fine step gave 0.92 / 0.81 / 0.39 (2 s, 19 s,
/// 21 s), and rho = 1 with patch 2 0.87. The errors do not even decrease monotonically with
/// the grid or the radius. It is the amplification described above: the beam's large, smooth
/// bending displacement needs basis functions exact to ~1e-5, which only regions spanning the
/// beam give. Against the previous implementation (Galerkin products dense above 5% density,
/// simplicial local solves, Φ^k and Ψ^k kept), same C̃ and errors, checker bench problem:
/// 24x8x8, 2 levels, rho = 3: 30 s -> 3.2 s (180 MB); 16x8x8, 3 levels, rho = 5:
/// 30 s / 171 MB -> 9.0 s / 132 MB. Large regions stay expensive: 40x20x20, 3 levels, rho = 5
/// (regions of ~4000 wavelets per coarse node at the fine step, ~6000 and 54% dense at the
/// coarse one) was 359 s / 880 MB and took 409 s / 2.07 GB here (error 0.690; the local
/// factorizations are 85% of the time; where the peak memory goes was not analysed).
///
/// Where the time went (perf, 24x8x8 checker, rho = 3): dense Galerkin products and their page
/// faults (55%), then the sparse local factorizations (18%). Now the products pick sparse or
/// dense by their multiply-add count (sparse Gustavson, parallel, lower triangle only for
/// A^k), and localized solves dominate: the sparse factorizations of the fine step's regions
/// (64x16x16, linear, rho = 2: 39 s of 67 s) and the products with the dense A^2 of the coarse
/// step. Patches (Options::patch) trade fewer factorizations for larger regions and a denser C̃:
/// patch 2 on that case cut the fine step's solves from 39 s to 27 s but doubled C̃ and raised
/// the time of A^2 from 4 s to 22 s, for the same error (0.988).
///
/// Table 1's setting (bench_mra 40 20 20 2 5: 18,081 nodes, checker contrast 1000, two levels,
/// rho = 5 fine rings, truncation 1e-7; idle machine, 2 threads; the paper's desktop: 15.1 s,
/// 390 MB). Rows: (a) before session 11; (b) one BLAS thread per OpenMP thread, CHOLMOD (AMD)
/// from 1000 unknowns, the O(nnz) symmetry check; (c) now: the Galerkin product by blocks of
/// 2x2x2 coarse nodes (detail::congruence), symbolic analyses reused across regions of the
/// same shape (regions sorted by shape; B keeps its structural pattern, or cancellations that
/// depend on the material would give regions of one shape different patterns), B[S, S] built
/// in place, Z built row by row instead of from triplets, A^k assembled symmetric in place.
/// (d) session 13: local systems built in their AMD order and factorized in place (no
/// permuted transposes inside CHOLMOD), no per-system symmetry check, CHOLMOD with symbolic
/// reuse from 100 unknowns instead of Eigen's simplicial LLT below 1000, dense ones by LAPACK.
/// (e) session 14: A^k and B^k kept as their lower triangles, the Galerkin product assembling
/// only that one (storage: C̃ 22.2M entries, A^1 10.6M, B 3.8M at patch 1).
/// (f) session 15: C̃^k kept as a RunMatrix (8.6 bytes per entry instead of 12); (g) C̃'s rows
/// formed from each region's solution, without assembling Z ("solves" then includes C̃ = C^† +
/// Z W, which took ~1 s), and B symmetrized in place.
/// Peak = the bench's high-water mark (fine problem and its solve included; (c) patch 2 was
/// measured before the last two changes, which took patch 1 from 1393 to 1261 MB).
/// (h) session 17: the regions ordered on their node graph (the dim wavelets of a node
/// together) by AMD or METIS, whichever fills less (solve::fill_reducing_order), instead of
/// AMD on the scalar graph: an interior Dirac region (3,345 unknowns) needs 1.1e8 flops
/// instead of 1.9e8, and ordering the node graph costs about half the scalar METIS.
/// (i) session 18: the truncation drops a row's d entries at a finer node together
/// (Options::truncation), so that a node's columns of C̃ keep one pattern, and the Galerkin
/// product takes them at once (detail::congruence); the bench calls retain_freed_memory, whose
/// retained heap the peak now includes.
///
/// | patch | row | build s | solves s | A^1 s | storage MB | peak MB | coarsest error |
/// |-------|-----|---------|----------|-------|------------|---------|----------------|
/// | 1     | (a) | 182     | 158      | 20.4  | 610        | 2023    | 0.58           |
/// | 1     | (b) | 68.7    | 49.3     | 15.5  | 610        | 2117    | 0.58           |
/// | 1     | (c) | 39.1    | 30.0     | 5.9   | 611        | 1261    | 0.58           |
/// | 2     | (b) | 52.6    | 17.0     | 30.5  | 769        | 2820    | 0.48           |
/// | 2     | (c) | 22.0    | 10.2     | 7.7   | 771        | 1848    | 0.48           |
/// | 1     | (d) | 29.1-30.1 | 22.0-22.3 | 4.2  | 611        | 1272    | 0.58           |
/// | 2     | (d) | 22.6    | 10.9     | 7.0   | 771        | 1848    | 0.48           |
/// | 1     | (e) | 28.7-33.7 | 21.4-25.2 | 4.0-4.7 | 439      | 1225-1272 | 0.58         |
/// | 2     | (e) | 20.6    | 9.3      | 6.5   | 580        | 1848    | 0.48           |
/// | 1     | (f) | 34.2    | 25.1     | 5.6   | 363        | 1271    | 0.58           |
/// | 2     | (f) | 20.7    | 9.6      | 6.6   | 470        | 1848    | 0.48           |
/// | 1     | (g) | 29.6-31.0 | 23.0-24.0 | 4.6-4.7 | 363    | 1139-1153 | 0.58         |
/// | 2     | (g) | 17.3    | 9.1      | 5.9   | 470        | 1450    | 0.48           |
/// | 1     | (h) | 22.8    | 17.6     | 3.7   | 363        | 1129    | 0.58           |
/// | 2     | (h) | 14.1    | 7.0      | 4.9   | 470        | 1446    | 0.48           |
/// | 1     | (i) | 20.3    | 17.2     | 2.2   | 358        | 1267    | 0.58           |
/// | 2     | (i) | 10.2    | 6.2      | 3.1   | 463        | 1489    | 0.49           |
///
/// The Dirac refinement in the same setting (its B^1 is 99.86% sparse, the shark's figure in
/// Table 1): (h) patch 1 build 13.4 s (solves 10.2 s, 14.7-15.9 s with the scalar AMD order of (g);
/// A^1 2.1 s), storage 239 MB, peak 820 MB, coarsest error 0.79; patch 2 10.0 s (solves 5.1 s,
/// A^1 3.2 s), 361 MB, peak 1151 MB, error 0.76. (i) patch 1 11.5 s (solves 9.7 s, A^1 1.4 s),
/// 234.5 MB, peak 900 MB, error 0.79; patch 2 6.1 s (solves 3.6 s, A^1 1.8 s), 354.5 MB, peak
/// 1214 MB, error 0.76. Both meet the 15 s and 390 MB; the linear refinement meets one
/// or the other (patch 2 / patch 1). Global solves with the Dirac
/// refinement: build 108 s (solves 43 s, A^1 63 s), 1.47 GB, coarsest error 0.596; so rho = 5
/// costs the Dirac construction 1.32x its global error here (patch 2: 1.27x), against 3.4x for
/// the linear one (0.58 against 0.17), whose global construction is 3.5x more accurate.
///
/// The paper's 18K-node hex model is not a solid box: the shark has 18,234 nodes for ~10K
/// hexes and 3,317 coarse nodes, i.e. it is mostly 1-2 elements thick, and its C^1 is 2.2%
/// dense against 5.4% for our 40x20x20 box, whose rho = 5 regions (11^3 fine nodes) are about
/// 3x larger and cost ~10x more to factorize. A plate of the shark's statistics (bench_mra 78
/// 78 2 2 5: 18,723 nodes, 12,168 hexes, 3,200 coarse nodes; C^1 1.9% dense, A^1 8.9%, B^1
/// 0.23%, against the shark's 2.2%, 13.8%, 0.14%) builds in 4.5-5.2 s with 169 MB of storage
/// (the paper: 15.1 s, 390.5 MB); local solves 1.7-2.1 s, A^1 1.1 s, coarsest error 0.76.
///
/// Global solves (the accurate default, radius inf) in the same setting: build 137.8 s
/// (factorization of B and solves 55.7 s, A^1 80.6 s; 156.3 s with A^1 97.7 s before the
/// product read dense-ish C̃ by rows), storage 1.97 GB (C̃ 132M entries, 32% dense; A^1 98%
/// dense), peak 5.8 GB, coarsest error 0.1716 against 0.58 at rho = 5. The grouped product
/// streams C̃ once per group of 24 rows: ~7 GFlop/s per core, bound by memory. Session 21: the
/// dense product by BLAS (detail::congruence from 30% density) builds it in 89.1 s (solves 50.2
/// s, A^1 36.8 s), storage 1.64 GB (A^1's lower triangle with its exact zeros dropped), peak 7.0
/// GB, same error.
/// Growth with the grid (same setting, patch 1; nodes: build s, storage MB): (c) 1,377: 1.9,
/// 22; 4,225: 9.6, 101; 9,537: 19.7, 284; 18,081: 39.7, 611; (d) 1.3, 5.9, 14.1, 29.1 s. From
/// 4,225 to 18,081 nodes (4.3x) the build grows 4.9x, close to linear (small grids clip most
/// regions at the boundary, so their systems are smaller).
/// 64^3 cells (274,625 nodes), two levels, rho = 2 fine rings: build 129.8 s in (e) (local
/// solves 62.1 s, B 25.5 s, A^1 17.8 s, C̃ = C^† + Z W 10.6 s, invariance 6.7 s; (d): 146.5 s
/// with A^1 30.2 s; (c): 298.6 s, local solves 207 s), storage 3.3 GB in (e) (C̃ 1.1e8 entries,
/// lower triangles of A^1 9.6e7 and B 6.6e7), 5.2 GB in (d), 2.97 GB in (f, g); peak 9.9 GB
/// from the start of the build in (e) (10.6 GB in (d)), ~4.6 GB of it the bench's fine problem.
/// In (g): build 119.7 s (B 15.7 s, localized solves with C̃ 64.7 s, invariance 6.6 s, A^1
/// 26.1 s), peak 9.0 GB; the bench's own fine reference solve peaks at 19.2 GB before. Coarsest
/// factorize + solve 192 s + 0.67 s against 218 s + 1.0 s for the fine one (1.1x; A^1 is
/// 107,811 DOFs with 1.9e8 nonzeros); coarsest error 0.72. At rho = 5 (measured in (g), 2
/// threads, idle): build 516.7 s (localized solves 387.5 s, A^1 94.5 s, invariance 16.1 s, B
/// 10.1 s), storage 7.41 GB (C̃ 3.97e8 entries, 99.55% sparse; lower triangles of A^1 2.61e8,
/// 95.52% sparse, and B 6.6e7), build peak 20.1 GB with the bench's fine problem. The bench's
/// fine reference factorization after the build (811,200 DOFs, 19.4 GB predicted, beside the
/// 7.4 GB hierarchy) was then killed by the kernel at 24.3 GB (twice: 516.7 s and 507.5 s
/// builds); SpdSolver now refuses it at the analysis (SolverOptions::max_factor_bytes; third
/// run, 513.7 s: "19.4 GB, more than the 9.02 GB available", exit code 1). A^1
/// (107,811 DOFs, 5.2e8 entries) was not factorized: at that size the coarsest level wants more
/// steps.
/// Growth with the Dirac refinement in (h) (rho = 5, patch 1, 2 threads; nodes: build s
/// (localized solves, A^1), storage, coarsest error; the same run repeated varies by up to 25%
/// here): 15,625 (24^3): 13.0 s (10.1, 1.8), 211 MB, 0.75; 18,081 (40x20x20): 13.4 s, 239 MB,
/// 0.79; 35,937 (32^3): 30.0-37.8 s (22.6-28.2, 4.9-6.4), 542 MB, 0.70; 117,649 (48^3): 123.9 s
/// (92.8, 21.5), 1.99 GB, build peak 6.1 GB, 0.63; 274,625 (64^3): 352.9 s (274.0, 54.8;
/// invariance 13.7), 4.90 GB (C̃ 3.07e8 entries, 99.64% sparse; A^1's lower triangle 1.6e8,
/// 97.06% sparse; B's 2.4e7), build peak 14.8 GB; a second run 334.3 s (solves 246.8 s, A^1
/// 60.6 s, invariance 16.5 s); after the invariance correction lost its per-entry heap
/// allocations (session 17), 305.6 s (solves 237.6 s, A^1 52.6 s, invariance 5.1 s); before
/// that, with glibc's malloc thresholds raised (GLIBC_TUNABLES mmap_threshold and
/// trim_threshold, now retain_freed_memory) 302.3 s, B 1.7 s instead of 4.0-4.6 s. In (i):
/// 279.5 s (solves 231.8 s, A^1 34.5 s, invariance 4.2 s, B 2.5 s), 4.89 GB (C̃ 3.26e8 entries,
/// 6% more than truncated by entries, in less storage), build peak 15.2 GB; the same run again
/// (idle machine) 307.0 s (solves 245.7 s, A^1 46.0 s), its fine factorization 186 s against
/// 200 s: the 300 s is met on average (293 s), not in every run. Build-only runs in one
/// session (the bench without its fine reference, a local variant): before (i) 315.2 s, and 301.8 s
/// with retain_freed_memory's settings (through GLIBC_TUNABLES); with the rest of (i) 299.0 s, and
/// 277.2 s with them. Patch 2 (in (h)): 252.5 s (solves 138.0 s, A^1 92.4 s), but 8.29 GB of
/// storage and a build peak of 23.3 GB. From 32^3 to 64^3 (7.6x the nodes) the build
/// grows 8.8-11.8x: a region's factorization and solve take 9-15 ms per thread, longer on the
/// larger grids. The series in (i): 24^3 11.0 s (solves 9.3 s, A^1 1.2 s), 207 MB, 0.75;
/// 40x20x20 11.5 s, 235 MB, 0.79; 32^3 26.9 s (22.7, 3.0), 536 MB, 0.70; 48^3 106.5 s
/// (87.3, 13.5), 1.97 GB, 0.63; 64^3 279.5-307.0 s (231.8-245.7, 34.5-46.0), 4.89 GB. The 64^3
/// coarsest operator (104,544 DOFs) would need an 18.6 GB factor, which the memory guard refused
/// next to the hierarchy (13.8 GB available); bench_mra now runs its fine reference (factorize 315
/// s + solve 5.2 s at 64^3) before the build and frees it. The regions' order: METIS on the scalar
/// graph took the solves of (d) at 40x20x20 from 22.0 to 20.7 s but those of 24^3, rho = 2 from 2.9
/// to 3.9 s (its ordering time); on the node graph (h) ordering costs about half (40x20x20: 0.95
/// against 1.69 CPU-s with Dirac, 1.58 against 4.17 with linear refinement), and 24^3, rho = 2 went
/// from 3.0-3.4 s to 2.6-2.9 s.
///
/// Where the time goes at patch 1 (perf, (d)): the 2,541 local CHOLMOD factorizations (~3,500
/// unknowns, 2e8 flops each) are mostly BLAS (dgemm and its copies: ~35% of the build's CPU time);
/// CHOLMOD's permuted transposes of the input, 25% of the solves in (c), are gone, and ~21% of the
/// regions (the clipped ones at the boundary) have a new pattern and pay an order and a symbolic
/// analysis. The Galerkin product A^1 takes ~11%, building B[S, S] 3%. A^1 is 36% dense: its
/// factorization (2.7 s) is slower than the fine one (1.6 s) at this radius.
/// Three levels (bench_mra NX NY NZ 3 ...), coarsest factorize + solve against the fine one in
/// the same run (medians of up to 5 timings each): the paper's beam (32x8x8, 2,673 nodes -> 81,
/// rho = 5) 148-297x over 12 runs, median about 200x (coarsest 0.29-0.45 ms + 0.04-0.06 ms
/// against 75-110 ms; sub-millisecond times make the ratio jittery here; the paper: 0.87 s +
/// 0.008 s -> 0.003 s + 0.00023 s); 40x20x20 with global solves at the coarse step (1188
/// coarse DOFs, dense) 105x. Both were 35-50x and 26.5x while the dense coarse operators went
/// through CHOLMOD (solve::SpdSolver now hands them to LAPACK, on one BLAS thread below 800
/// unknowns). The beam in (i): 251x, 277x and 312x in three runs.
#include <limits>
#include <string>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "coarsegrain/mra/options.hpp"
#include "coarsegrain/mra/refinement.hpp"
#include "coarsegrain/mra/run_matrix.hpp"

namespace coarsegrain::mra {

/// One level k < q of the hierarchy, built from level k+1 (Algorithm 1, lines 2-7).
struct Level {
    int k = 0;              ///< paper index, 1 = coarsest
    Eigen::Vector3i cells;  ///< grid cells per axis of level k
    /// DOFs of level k present in the hierarchy (indices dim*node + d into the level's grid
    /// DOFs, sorted). Rows of C̃, A, Φ follow this order.
    IndexVector dofs;
    IndexVector dropped_dofs;  ///< grid DOFs of level k without a basis function
    SparseMatrix C;            ///< canonical refinement C^k, #dofs by #dofs(k+1) (Eq. 6)
    SparseMatrix C_dagger;  ///< left inverse C^{k,†} (Eq. 10; rigid one for Localization::Cell)
    SparseMatrix W;         ///< kernel W^k, #wavelets by #dofs(k+1)
    /// C̃^k = C^{k,†} + Z W^k (Eq. 11), localized/corrected/truncated, #dofs by #dofs(k+1); kept
    /// by runs (RunMatrix: 8.6 bytes per entry at Table 1's setting, CSC 12).
    RunMatrix C_adapted;
    /// A^k = C̃^k A^{k+1} C̃^{k,T} (Alg. 1 line 7), symmetric: its lower triangle, diagonal
    /// included (symmetric_from_lower gives the whole matrix).
    SparseMatrix A;
    /// B^k = W^k A^{k+1} W^{k,T} (Alg. 1 line 2), symmetric: its lower triangle, diagonal
    /// included.
    SparseMatrix B;
    SparseMatrix Phi;  ///< Φ^k = C̃^k Φ^{k+1}: #dofs by fine grid DOFs (if store_bases, else 0x0)
    SparseMatrix Psi;   ///< Ψ^k = W^k Φ^{k+1}: #wavelets by fine grid DOFs (if store_bases)
    double radius = 0;  ///< rho used for this step (the starting one with defect_tolerance)
    /// Per node of level k: the rings of level k+1 of its region's final localized solve (the
    /// radius on the fine grid; grown with defect_tolerance); 0 for global solves, cell
    /// localization and nodes without DOFs.
    std::vector<int> region_rings;
    /// Per node of level k+1: 1 if the invariance correction was applied to its columns of C̃.
    std::vector<char> invariance_applied;
    /// Per node of level k: 1 if it lies on a fixed node of the finest grid. The invariance
    /// correction skips the fine nodes whose columns of C̃ reach one of these (Sec. 3.5). All 0
    /// with DirichletTreatment::Ignore, whose construction does not see the conditions.
    std::vector<char> dirichlet_nodes;
    /// DirichletTreatment::Ignore only: positions in `dofs` (sorted) of the DOFs at the position
    /// of a fixed finest DOF (same node position and component), held at zero when level k is
    /// solved. Empty with the other treatments, whose A^k carries the conditions.
    IndexVector fixed;
    double build_seconds = 0;
};

/// The whole hierarchy.
struct Hierarchy {
    int dim = 3;
    Options options;
    Eigen::Vector3i fine_cells;  ///< cells per axis of level q
    Eigen::Vector3d spacing;     ///< cell size of level q
    Eigen::Vector3d origin;      ///< position of node 0
    IndexVector fine_dofs;       ///< present DOFs of level q (all but the eliminated fixed ones)
    SparseMatrix A_fine;         ///< A^q: the fine stiffness on fine_dofs (+ penalty)
    /// DirichletTreatment::Ignore only: positions in fine_dofs of the fixed DOFs (A_fine is then
    /// the unconstrained stiffness on every grid DOF).
    IndexVector fine_fixed;
    std::vector<Level> levels;  ///< levels[k-1] is level k, k = 1..q-1
    Timings timings;            ///< phases "level k: <phase>"

    int num_levels() const { return static_cast<int>(levels.size()) + 1; }
    Index fine_grid_dofs() const;
    /// Level k, 1 <= k < q. @throws Error otherwise
    const Level& level(int k) const;
    /// Cells per axis of level k (1..q).
    Eigen::Vector3i cells(int k) const;
    /// Rest position of node v of level k (size dim).
    Eigen::VectorXd node_position(int k, Index v) const;
};

/// Builds the material-adapted hierarchy of a regular grid (Algorithm 1).
///
/// @param[in] mesh        a grid made by mesh::make_grid (GridInfo set); any element type, the
///                        hierarchy only uses its nodes
/// @param[in] K           fine stiffness (num_dofs square, both triangles)
/// @param[in] fixed_dofs  sorted Dirichlet DOFs (homogeneous)
/// @param[in] options     see Options
/// @param[in] materials   element materials of `mesh` (K must be their stiffness); needed only
///                        by Localization::Cell with a finite radius
/// @throws Error if the mesh is not a grid, the cells are not divisible by 2^(levels-1), an
///         option is out of range, cell localization lacks the materials, or a wavelet
///         stiffness B^k is not positive definite
Hierarchy build_hierarchy(const mesh::Mesh& mesh, const SparseMatrix& K,
                          const std::vector<Index>& fixed_dofs, const Options& options,
                          const material::ElementMaterials* materials = nullptr);

/// Restricts a fine vector (fine grid DOFs) to the hierarchy's fine DOFs and coarse-grains it to
/// level k (Sec. 3.6): g^k = C̃^k ... C̃^{q-1} g^q.
Vector coarse_grain(const Hierarchy& h, const Vector& g_fine, int k);

/// Φ^k = C̃^k ... C̃^{q-1} Φ^q (#dofs of level k by fine grid DOFs; k = q: the selection of the
/// present fine DOFs): the stored one if Options::store_bases, else computed.
/// @throws Error if k is not in 1..q
SparseMatrix basis(const Hierarchy& h, int k);

/// Φ^{k,T} u^k over all fine grid DOFs, computed level by level as
/// u^{l+1} = C̃^{l,T} u^l for l = k..q-1 (zeros at eliminated DOFs), without Φ^k.
/// @throws Error if k is not in 1..q or u_k has the wrong size
Vector reconstruct(const Hierarchy& h, const Vector& u_k, int k);

/// Positions of the DOFs of level k (1..q; rows of Level::A, or of A_fine for k = q) that a
/// solve at level k holds at zero: Level::fixed or Hierarchy::fine_fixed (empty unless
/// DirichletTreatment::Ignore).
/// @throws Error if k is not in 1..q
const IndexVector& fixed_positions(const Hierarchy& h, int k);

/// The other positions of level k's DOFs, sorted: those a solve at level k computes.
/// @throws Error if k is not in 1..q
IndexVector free_positions(const Hierarchy& h, int k);

/// The operator a solve at level k factorizes: Level::A (lower triangle) or A_fine (k = q,
/// both triangles) without the rows and columns of fixed_positions(h, k).
/// @throws Error if k is not in 1..q
SparseMatrix free_operator(const Hierarchy& h, int k);

/// Bytes of a compressed sparse matrix (values, inner and outer indices).
std::size_t storage_bytes(const SparseMatrix& M);
/// Bytes of a RunMatrix (RunMatrix::bytes).
inline std::size_t storage_bytes(const RunMatrix& M) { return M.bytes(); }

/// The symmetric matrix whose lower triangle (diagonal included) `lower` holds, both triangles
/// stored (as SpdSolver and the products take it). Level::A and Level::B are stored as their
/// lower triangles: at 40x20x20 hexes, rho = 5, the two-level hierarchy's storage is 439 MB
/// instead of 611 MB (363 MB with C̃ kept as a RunMatrix).
SparseMatrix symmetric_from_lower(const SparseMatrix& lower);

/// Nonzeros of the symmetric matrix whose lower triangle `lower` holds (stored zeros excluded).
Index symmetric_nonzeros(const SparseMatrix& lower);

}  // namespace coarsegrain::mra
