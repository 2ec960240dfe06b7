#pragma once
/// @file Options of the material-adapted hierarchy (Chen et al. 2019, Algorithm 1), apart from
/// the hierarchy itself so that scene loading can validate them before any work.
#include <limits>
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/mra/refinement.hpp"

namespace coarsegrain::mra {

/// How the Dirichlet conditions enter the hierarchy (Secs. 1, 3.1, 5.4). Errors and condition
/// numbers of each: docs/mra-localization.md, "Dirichlet conditions".
enum class DirichletTreatment {
    /// The fixed DOFs are removed from the fine operator, and coarse nodes on the fixed boundary
    /// lose their DOFs: exact and well conditioned, but the coarsest space is poorer.
    Eliminate,
    /// The fixed DOFs are kept with Options::penalty (1e8, as the authors' code) added to their
    /// diagonal entries. The result depends on the penalty relative to the stiffness (the coarse
    /// solution does not vanish at fixed nodes when E is large), and cond(A^1) grows with it.
    Penalty,
    /// As Penalty with penalty * K_ii, independent of the material scale.
    DiagonalPenalty,
    /// The fixed DOFs are removed as in Eliminate, but coarse nodes on the fixed boundary keep
    /// their canonical measurement functions restricted to the free DOFs (refinement_operators
    /// with keep_boundary_rows): the limit of the penalty as it tends to infinity, the same richer
    /// coarse space, exactly zero at the fixed DOFs, without the penalty's conditioning. With Dirac
    /// refinement the restricted rows vanish and Constrain coincides with Eliminate.
    Constrain,
    /// The boundary-blind construction the paper improves on (Chen et al. 2018; Sec. 1, Fig. 12):
    /// the hierarchy is built on the fine operator without any condition (fixed DOFs kept, no
    /// penalty; B^k stays definite, as rigid motions are not in ker C^k, and every A^k has exactly
    /// the rigid motions in its kernel), and a level is constrained only when it is solved: its
    /// DOFs at the position of a fixed finest DOF (fixed_positions) are held at zero. The basis
    /// functions do not vanish at the other fixed finest DOFs, so the coarse model is wrong near
    /// the fixed boundary: too stiff with linear refinement (Fig. 12's "spurious structural
    /// rigidity"), too soft with Dirac. Single-level solves only (MultilevelSolver::solve_levels
    /// needs m = 1).
    Ignore,
};

/// Grid on which the localization radius rho counts rings (Sec. 3.5).
enum class RadiusGrid {
    Fine,    ///< rings of the finer grid of the step (level k+1): the region spans 2 rho + 1 nodes
    Coarse,  ///< rings of the coarser grid (level k), the paper's wording: 4 rho + 1 fine nodes
};

/// How the solves for Z are localized when the radius is finite (Sec. 3.5).
enum class Localization {
    /// Per coarse node i (the paper): B[S_i, S_i] z_i = -R[S_i, i] on the wavelets S_i near i.
    Node,
    /// Per coarse cell T, as the correctors of Localized Orthogonal Decomposition (Malqvist and
    /// Peterseim): R = sum_T R^T with R^T = W Φ^{k+1} A_T Φ^{k+1,T} C^{†,T}, A_T the fine
    /// stiffness of the fine elements inside T (sum_T A_T = A^q); each R^T is solved on the
    /// wavelets within rho rings of T and Z = sum_T Z^T. Needs the element materials. With the
    /// linear refinement C^† is replaced by a sparse left inverse that reproduces rigid motions
    /// (then the corrections of a rigid motion cancel cell by cell). Measured against Node:
    /// docs/mra-localization.md, "Cell-wise localization".
    Cell,
};

/// Measurement functions of the finest step (the rows of C^{q-1}; Sec. 3.2 with weights).
enum class Measurement {
    Canonical,  ///< the paper's: the canonical refinement itself
    /// Stiffness-weighted (weighted_refinement; no effect on the Dirac refinement, whose
    /// measurements are values at single nodes): each fine node's share
    /// of a coarse measurement is scaled by its local stiffness, so that a coarse node measures
    /// mainly the stiff material around it. Coarser steps compose these measurements with the
    /// canonical C^k, so the hierarchy stays nested. Measured: docs/mra-localization.md,
    /// "Stiffness-weighted measurements".
    Stiffness,
};

/// The fine operator the hierarchy is adapted to (Chen et al. 2019, Secs. 4.1 and 4.2).
enum class Operator {
    /// The stiffness K: the basis of elastostatics (Sec. 4.1), which dynamics then uses with the
    /// Galerkin mass through the same hierarchy.
    Stiffness,
    /// The operator of one implicit step of the scene's dynamics, S = M + c_C C + c_K K
    /// (sim::step_operator: M + dt² K for implicit Euler in velocity form, M + dt²/4 K for
    /// midpoint, C the Rayleigh damping), the "discrete flow" of Sec. 4.2: the basis is adapted
    /// to one time step, and the coarse model is K and M through it (Φ K Φᵀ, Φ M Φᵀ), whose step
    /// operator is exactly the hierarchy's A^1. S depends on dt, the integrator, the damping and
    /// the mass: each of them needs a new build, at the cost of a stiffness build (the same
    /// sparsity). As dt grows the basis tends to the stiffness one; as dt shrinks, to a basis
    /// adapted to the mass alone. Measured: docs/guide.md, "Dynamics".
    Step,
};

/// "dirac", "linear" / "stiffness", "step" / "eliminate", "penalty", "diagonal_penalty",
/// "constrain", "ignore" / "fine", "coarse" / "node", "cell" / "canonical", "stiffness".
std::string refinement_name(Refinement r);
std::string operator_name(Operator o);
std::string dirichlet_name(DirichletTreatment t);
std::string radius_grid_name(RadiusGrid g);
std::string localization_name(Localization l);
std::string measurement_name(Measurement m);

/// Options of the hierarchy (Algorithm 1).
struct Options {
    /// Number of levels q >= 2 (the finest grid counts as one). Cells per axis of the fine grid
    /// must be divisible by 2^(q-1).
    int levels = 3;
    Refinement refinement = Refinement::Linear;
    /// Localization radius rho of step k (building level k from k+1) is radius[k-1], or
    /// radius[0] for every step if radius has one entry; empty (the default): the automatic
    /// construction (automatic_construction). Infinity: global solves (one CHOLMOD
    /// factorization of B^k for all columns of Z). With Localization::Cell a region within
    /// rho / 3 rings of the grid's boundary is extended to it. With relaxation, infinity (or a
    /// radius that spans the level: rho at least the finer level's cells per axis) is the
    /// relaxed step on the whole level, exact: one factorization of A^{k+1} for all its parts,
    /// in the basis of its measurements G (C̃^T = A^{-1} G^T (G A^{-1} G^T)^{-1}, G measuring
    /// the fine functions of the relaxed steps below).
    std::vector<double> radius;
    RadiusGrid radius_grid = RadiusGrid::Fine;
    /// Eq. 12 defect-driven radius (node localization, finite radii; 0: off). The localized
    /// solves make C̃ A^{k+1} W^T = 0 (Eq. 12) hold only on each region's wavelets. With a
    /// tolerance, each region starts at its step's radius and doubles it until the relative
    /// defect of its rows, ||(C̃ A W^T)[r, :]|| / ||(C^† A W^T)[r, :]||, is at most the
    /// tolerance, or the radius reaches max_radius, or the region covers the grid. Measured:
    /// docs/mra-localization.md, "Defect-driven radius".
    double defect_tolerance = 0;
    /// Largest radius of the defect-driven growth (same grid as radius).
    double max_radius = 16;
    /// Patch-wise localization (finite radii only): coarse nodes per axis of a patch. The
    /// nodes of a patch (a block of patch^dim coarse nodes) share one region, the fine nodes
    /// within rho rings of any of them, and one factorization of B^k on it for all their
    /// columns. 1: the paper's per-node regions. A larger patch enlarges every node's region
    /// (at least as accurate as patch 1 with the same rho) and divides the number of
    /// factorizations by patch^dim. With Localization::Cell, a block of patch^dim coarse cells
    /// is one part T: one region (rho rings around the block) and one factorization for the
    /// sum of its cells' right-hand sides.
    int patch = 1;
    /// With patch > 1, each node keeps from its patch's solution only the wavelets within its
    /// own rho rings (zeroes the rest), so its basis function has the support of patch 1: C̃
    /// and A^k as sparse as with patch 1, for patch^dim fewer factorizations. The clipped rows
    /// no longer minimize the energy on their support; what that costs each refinement:
    /// docs/mra-localization.md, "Clipped patches".
    bool patch_clip = false;
    /// Node- or cell-wise localization (finite radii only; Cell needs the Eliminate, Constrain
    /// or Ignore treatment, whose fine operator is the sum of the element matrices, and no
    /// patch_clip).
    Localization localization = Localization::Node;
    /// Relaxed measurements gamma (cell localization; with a finite radius, the linear
    /// refinement; 0: exact).
    /// Each cell's corrector replaces the constraint that its measurements vanish by the penalty
    /// |G w|^2 d / (2 gamma) (G: the measurements of the fine function w stands for, C^k at the
    /// finest step, C^k .. C^{q-1} Φ^{k+1,T} at coarser ones; d: the softest material's
    /// stiffness on the level), and is solved in the level's whole space on the nodes within
    /// `radius` rings of the cell, from the canonical basis (relaxed constraint energy
    /// minimization, Chung, Efendiev and Leung 2018): the coarse coefficients are nodal values,
    /// not measurements, and C̃ reproduces the rigid motions without the invariance correction.
    /// The global space is the same for every gamma; localized, the correctors decay much faster
    /// through soft material around stiff inclusions, where the exact ones lock. 16^3 hexes, 216
    /// stiff spheres, 2 levels, 6 rings, gamma 3: 1.26x the global energy error (exact
    /// constraints at the same storage: 8.6x); with patch 2, 1.20x in 0.4x the build, at 32^3
    /// with 8 rings 1.04x, and with 3 levels 1.01-1.02x at 16^3 and 24^3;
    /// docs/mra-localization.md, "Relaxed measurements in the library".
    double relaxation = 0;
    Measurement measurement = Measurement::Canonical;
    /// coarse.operator: what the fine operator given to build_hierarchy is. Cell localization
    /// with a finite radius needs the stiffness (its parts are element stiffness matrices).
    Operator fine_operator = Operator::Stiffness;
    /// Relative truncation threshold tau >= 0 (0: none). After the solves of step k, the d
    /// entries of a row i of C̃ at the DOFs of one level-(k+1) node j (a row of the paper's d x d
    /// coefficient C̃_ij) are dropped together if all of them are below tau max_l |C̃_il|
    /// (relative to the largest coefficient of the same basis function), so that a node's columns
    /// keep one pattern, which the Galerkin product takes at once. A^k = C̃^k A^{k+1} C̃^{k,T} is
    /// then the exact Galerkin matrix of the truncated basis and is not truncated itself: dropping
    /// its small entries perturbs its near-null space (tau = 1e-4 on A^k made A^1 of the 32x32
    /// hung square indefinite). Default 1e-7: C̃ of global solves 35-63% sparser at an unchanged
    /// error (docs/mra-localization.md).
    double truncation = 1e-7;
    /// Translation and rotation invariance correction of C̃ (Sec. 3.5), applied after truncation
    /// so that it holds exactly.
    bool invariance = true;
    DirichletTreatment dirichlet = DirichletTreatment::Constrain;
    /// Penalty / DiagonalPenalty magnitude (absolute, or relative to K_ii).
    double penalty = 1e8;
    /// Keep Φ^k and Ψ^k (against the finest grid) in every Level. Off by default: they hold
    /// more entries than all C̃^k together (128x128 quads, 3 levels: 12 GB), and basis() and
    /// reconstruct() give Φ^k and Φ^{k,T} u^k on demand from the C̃^k.
    bool store_bases = false;
    /// Keep B^k in every Level (the wavelet solves of the multilevel solver, the diagnostics, the
    /// reports and the Python module read it). The multigrid preconditioner turns it off: after
    /// localized solves B^k is the largest matrix of a step (5.5e7 entries in the fine step of
    /// a 48^3 hex grid at radius 1, twice A^{k+1}) and the cycle does not read it. Neither do the
    /// coarse model and its solves: B^1 of the 64^3 checker with 3 levels, `radius` [3, 4],
    /// holds 3.5e8 entries (4.2 GB; the build peaks at 17.6 GB with it).
    bool store_wavelet_stiffness = true;
    /// The fine element (the scene's "fem" block), for the element matrices the construction
    /// computes itself: the cell-localized solves' A_T and the coarsest cells' own hierarchies.
    /// It must be that of the fine K given to build_hierarchy.
    fem::Formulation formulation = fem::Formulation::Standard;
};

/// Largest Options::levels: a grid of up to 1e5 cells per axis halves at most 16 times.
inline constexpr int kMaxLevels = 17;

/// The automatic construction's localized setting (automatic_construction): fine DOFs above
/// which a 3D grid takes it, its patch, relaxation gamma, the rings of its finest step, and the
/// DOFs of level k+1 up to which a coarser step is taken on its whole level, and the rings of
/// those above.
inline constexpr Index kLocalizedMinDofs = 40000;
inline constexpr int kLocalizedPatch = 2;
inline constexpr double kLocalizedRelaxation = 3;
inline constexpr double kLocalizedFineRings = 6;
inline constexpr Index kWholeLevelMaxDofs = 20000;
inline constexpr double kLocalizedCoarseRings = 3;

/// The options an empty Options::radius (automatic) stands for, on a grid of `cells` cells per
/// axis (the first dim entries; DOFs: dim per node, Dirichlet ones included); `cell_parts`: the
/// model is a grid whose element materials are given (the parts of cell localization; false on
/// level meshes). Options with a radius, or with levels out of range, are returned as they are.
///
/// A 3D grid above kLocalizedMinDofs DOFs whose options leave the localization at its defaults
/// (node-wise, patch 1, no patch_clip, relaxation 0, defect_tolerance 0), with the linear
/// refinement, canonical measurements, the stiffness operator and the eliminate, constrain or
/// ignore treatment, gets the accurate localized construction: cell localization, patch
/// kLocalizedPatch, relaxation kLocalizedRelaxation, kLocalizedFineRings rings at the finest
/// step, and every coarser step on its whole level (infinite radius) up to kWholeLevelMaxDofs
/// DOFs of level k+1, in kLocalizedCoarseRings rings above. Every other model gets global solves
/// (infinite radius at every step).
///
/// Measured against global solves (3 levels; docs/mra-localization.md, "The automatic
/// construction"): 0.40x, 0.63x the coarsest energy error on the accordion beam at 64x16x16 and
/// 80x20x20 hexes, 1.006x on a hung checker slab (48x48x8), 1.0003x on Table 1's box (40x20x20),
/// 1.03x and 1.10x on 216 stiff spheres and touching cubes at 24^3; C̃ 0.32-0.48x as dense, in
/// 0.29-0.61x the build time and 0.30-0.54x the peak memory. Below about 40K DOFs the regions of
/// 6 rings span most of the grid and global solves take seconds; in 2D global solves fill in
/// little; the Dirac refinement's relaxed basis does not localize (validate). A coarser step
/// factorizes A^{k+1} on its whole level, a quarter to half dense, so it grows with the square of
/// the level; in rings its regions' blocks are dense, but their number grows linearly. Hung
/// checker, 3 levels, whole level against 3 rings: at 32^3 (14,739 DOFs on level 2) 104 against
/// 115 s, 0.2597 against 0.2716; at 40^3 (27,783) 305 against 257 s, 0.2355 against 0.2475; at
/// 48^3 (46,875) the whole level's factor does not fit in 24 GB, 3 rings build in 451 s.
Options automatic_construction(Options options, const Eigen::Vector3i& cells, int dim,
                               bool cell_parts);

/// Checks the options' ranges and combinations (the Options fields name the scene's coarse.*
/// keys): levels in 2..kMaxLevels; no radius (automatic), one or levels - 1, each >= 1 (or
/// infinity); patch >= 1; truncation in [0, 1); penalty > 0; defect_tolerance finite and >= 0;
/// max_radius >= 1; for cell localization with a finite radius or relaxation, no patch_clip,
/// the eliminate, constrain or ignore treatment, the stiffness operator and no
/// defect_tolerance; relaxation finite and >= 0, > 0 only with cell localization, and with a
/// finite radius only with the linear refinement.
/// @throws Error naming the option
void validate(const Options& options);

/// Checks that a grid of `cells` cells per axis (first dim entries) has the levels of `options`:
/// cells per axis divisible by 2^(levels - 1).
/// @throws Error naming the axis
void validate_grid(const Options& options, const Eigen::Vector3i& cells, int dim);

/// Options of compare_levels: the scene keys coarse.spectrum_max_dofs and coarse.cell_tensors.
struct CompareOptions {
    /// coarse.spectrum_max_dofs (integer >= 0): levels whose A^k or B^k has more rows get no
    /// condition number. Each spectrum costs a factorization and tens of Lanczos solves:
    /// measured 0.35 s for A of 20200 rows (2D 100x100 grid, 2 shared cores), more in 3D where
    /// factorizations fill in.
    Index max_spectrum_dofs = 20000;
    /// coarse.cell_tensors (true | false): compute the Sec. 5.6 cell tensors. Each coarsest cell
    /// gets its own free-body hierarchy, so a single coarsest cell costs a second full build.
    bool cell_tensors = true;
};

/// Options of the mra-pcg solver backend's multigrid preconditioner (mra/preconditioner.hpp; the
/// scene's solver.levels, solver.radius, solver.smoother_degree).
struct PreconditionerOptions {
    /// Levels q >= 2 of the hierarchy; 0: the fewest levels whose coarsest level has at most
    /// coarsest_dofs DOFs, as far as the cells per axis halve on grids or the automatic level
    /// meshes allow on simplices (preconditioner_levels).
    int levels = 0;
    /// Largest coarsest level of the automatic choice (DOFs, Dirichlet ones included).
    Index coarsest_dofs = 20000;
    /// Localization radius rho of every step (rings of the finer level, Options::radius).
    double radius = 1;
    /// Degree of the Chebyshev smoothing polynomial, before and after the coarse correction.
    int smoother_degree = 3;
    /// Deflate the V-cycle by the rigid motions of the stiff clusters (fem/stiff_clusters.hpp,
    /// elements at least kDeflationContrast times as stiff as the softest material;
    /// solve/deflation.hpp): what a radius-1 basis misses at high contrast. No effect on a model
    /// without such clusters.
    bool deflation = true;
    /// Rings of the fine mesh over which the clusters' rigid motions are extended into the soft
    /// material (fem::cluster_rigid_modes; 0: none).
    int deflation_rings = 2;
};

/// Stiffness ratio to the softest material from which the elements of a material form the
/// stiff clusters that mra-pcg deflates: an order of magnitude. The benchmarks' inclusions
/// (contrast 1e3 and 1e6, docs/fine_pcg_bench.md) all qualify; materials within 10x of the
/// softest are left to the cycle.
inline constexpr double kDeflationContrast = 10;

/// Largest PreconditionerOptions::deflation_rings.
inline constexpr int kMaxDeflationRings = 16;

/// Checks the options' ranges: levels 0 or in 2..kMaxLevels, coarsest_dofs >= 1, radius >= 1
/// (finite), smoother_degree in 1..10, deflation_rings in 0..kMaxDeflationRings.
/// @throws Error naming the option
void validate(const PreconditionerOptions& options);

}  // namespace coarsegrain::mra
