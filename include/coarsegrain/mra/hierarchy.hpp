#pragma once
/// @file The material-adapted hierarchy of refinable basis functions and wavelets (Chen et al.
/// 2019, Sec. 3, Algorithm 1) on nested regular grids or on given simplicial level meshes, nested
/// or not (level_meshes.hpp).
///
/// Notation (shared/papers/NOTES.md): canonical quantities C^k, W^k, C^{k,†}; material-adapted
/// refinement C̃^k (the paper's outline C^k), stiffness A^k, wavelet stiffness B^k, basis Φ^k and
/// wavelets Ψ^k, expressed against the finest basis (Φ^q = I) and kept only on request
/// (Options::store_bases; basis() and reconstruct() otherwise). Level 1 is the coarsest, level q
/// the finest; step k builds level k from level k+1.
///
/// The Dirichlet conditions enter through the fine operator and are carried to every level
/// (Options::dirichlet; see DirichletTreatment). Only homogeneous conditions are supported (the
/// fixed values must be zero). With DirichletTreatment::Ignore the hierarchy does not see them:
/// a level's DOFs at fixed finest DOFs are held at zero only when it is solved (fixed_positions,
/// free_operator).
///
/// Global solves for Z (Options::radius infinite; what the automatic construction gives in 2D
/// and up to 40K DOFs) followed by truncation at 1e-7 are the accurate construction. Localized
/// solves (node- or cell-wise, patches, clipping, a defect-driven radius) build faster in 3D but
/// are much less accurate on smooth, large deformations: each basis function's small deviation from
/// the global one adds up over the coarse coefficients. Cell-wise localization with relaxed
/// measurements (Options::relaxation) comes within 1.0-1.3x of the global error on isolated stiff
/// inclusions and checkers (blocks of 2^3 cells, 6 rings at 16^3 hexes, 8 at 32^3, C̃ 41% and 15%
/// dense against 99%; with three levels too), but the radius must grow with the grid. On the
/// layered accordion (three levels, the coarse step's regions spanning its level, the fine step's
/// half a length unit each way and across the section) it beats the global error in less time
/// (64x16x16: 0.23x in 0.44x, C̃ 0.6x as dense); with 5 fine rings it is 0.78x at 64x16x16 and 1.48x
/// at 80x20x20 with C̃ 0.28-0.30x as dense, in a quarter of the build and half the memory or less
/// (48x12x12 needs 6 rings). That setting with 6 fine rings, and coarser steps in 3 rings on levels
/// of more than 20K DOFs, is the automatic construction above 40K DOFs in 3D
/// (automatic_construction). docs/mra-localization.md has the measurements behind each
/// option (accuracy, build time, storage) and the commands that regenerate them.
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
    Eigen::Vector3i cells;  ///< grid cells per axis of level k (0 on level meshes)
    /// DOFs of level k present in the hierarchy (indices dim*node + d into the level's grid
    /// DOFs, sorted). Rows of C̃, A, Φ follow this order.
    IndexVector dofs;
    IndexVector dropped_dofs;  ///< grid DOFs of level k without a basis function
    SparseMatrix C;            ///< canonical refinement C^k, #dofs by #dofs(k+1) (Eq. 6)
    /// left inverse C^{k,†} (Eq. 10; the rigid one for Localization::Cell with exact
    /// measurements; unused by relaxed ones, which start from C^k)
    SparseMatrix C_dagger;
    SparseMatrix W;  ///< kernel W^k, #wavelets by #dofs(k+1)
    /// C̃^k = C^{k,†} + Z W^k (Eq. 11), localized/corrected/truncated, #dofs by #dofs(k+1); kept
    /// by runs (RunMatrix: 8.6 bytes per entry at Table 1's setting, CSC 12).
    RunMatrix C_adapted;
    /// A^k = C̃^k A^{k+1} C̃^{k,T} (Alg. 1 line 7), symmetric: its lower triangle, diagonal
    /// included (symmetric_from_lower gives the whole matrix).
    SparseMatrix A;
    /// B^k = W^k A^{k+1} W^{k,T} (Alg. 1 line 2), symmetric: its lower triangle, diagonal
    /// included (0 x 0 without Options::store_wavelet_stiffness).
    SparseMatrix B;
    SparseMatrix Phi;  ///< Φ^k = C̃^k Φ^{k+1}: #dofs by fine grid DOFs (if store_bases, else 0x0)
    SparseMatrix Psi;   ///< Ψ^k = W^k Φ^{k+1}: #wavelets by fine grid DOFs (if store_bases)
    double radius = 0;  ///< rho used for this step (the starting one with defect_tolerance)
    /// Per node of level k: the rings of level k+1 of its region's final localized solve (the
    /// radius on the fine grid; grown with defect_tolerance); 0 for global solves, cell
    /// localization and nodes without DOFs.
    std::vector<int> region_rings;
    /// Per node of level k+1: 1 if the invariance correction made its columns of C̃ reproduce
    /// the rigid motions (to 1e-10); 0 where it was skipped (near a Dirichlet node) or where a
    /// column has too few entries to meet the conditions (e.g. one fine ring on level meshes).
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
    Eigen::Vector3i fine_cells;  ///< cells per axis of level q (grids; 0 on level meshes)
    Eigen::Vector3d spacing;     ///< cell size of level q (grids)
    Eigen::Vector3d origin;      ///< position of node 0 (grids)
    /// Level meshes only (empty on grids): the meshes of levels 1..q-1, coarsest first; level k's
    /// nodes are those of level_meshes[k-1].
    std::vector<mesh::Mesh> level_meshes;
    Matrix fine_positions;             ///< level meshes only: the fine mesh's node positions
    std::vector<double> edge_lengths;  ///< level meshes only: mean edge length of levels 1..q
    IndexVector fine_dofs;  ///< present DOFs of level q (all but the eliminated fixed ones)
    /// A^q: the fine stiffness on fine_dofs (+ penalty); empty (0 x 0) after
    /// build_hierarchy_free, whose caller keeps it.
    SparseMatrix A_fine;
    /// DirichletTreatment::Ignore only: positions in fine_dofs of the fixed DOFs (A_fine is then
    /// the unconstrained stiffness on every grid DOF).
    IndexVector fine_fixed;
    std::vector<Level> levels;  ///< levels[k-1] is level k, k = 1..q-1
    Timings timings;            ///< phases "level k: <phase>"

    int num_levels() const { return static_cast<int>(levels.size()) + 1; }
    /// True for a hierarchy of nested grids, false for one on level meshes.
    bool on_grid() const { return level_meshes.empty(); }
    /// Level meshes only: node positions of level k = 1..q (#nodes by dim).
    const Matrix& mesh_positions(int k) const;
    Index fine_grid_dofs() const;
    /// Level k, 1 <= k < q. @throws Error otherwise
    const Level& level(int k) const;
    /// Cells per axis of level k (1..q) of a grid hierarchy (0 on level meshes).
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

/// build_hierarchy on a fine operator already restricted to the DOFs free of the Dirichlet
/// conditions (all DOFs of `mesh` but `fixed_dofs`, ascending, as fem::reduce makes it), for the
/// Eliminate and Constrain treatments and canonical measurements (the others need the DOFs the
/// conditions remove). A_free is read by the build but neither copied nor kept: the result's
/// A_fine is empty (0 x 0), A^q stays the caller's (the multigrid preconditioner's use).
/// @throws Error as build_hierarchy, or if A_free is not #free DOFs square or the options need
///         the operator over all DOFs
Hierarchy build_hierarchy_free(const mesh::Mesh& mesh, const SparseMatrix& A_free,
                               const std::vector<Index>& fixed_dofs, const Options& options,
                               const material::ElementMaterials* materials = nullptr);

/// Builds the material-adapted hierarchy on simplicial level meshes (Algorithm 1), nested or not:
/// the canonical operators of level_meshes.hpp (linear_refinement or, for Dirac refinement, the
/// selection of pivot_nodes; local_refinement_operators), then the steps of the grid
/// construction: global solves, or node-wise localized ones whose regions are rings of the
/// finer level's node graph around each coarse node's pivot. The nodes of level k < q are those
/// of coarser_levels[k-1], those of level q the fine mesh's; a node of a coarser level lies on
/// the Dirichlet boundary when its chain of pivots ends on a fixed fine node.
///
/// @param[in] coarser_levels  levels 1..q-1, coarsest first, simplicial (triangles or
///                            tetrahedra), with no more nodes than the next finer level
/// @param[in] fine_mesh       level q: any element type (only its nodes are used)
/// @param[in] K, fixed_dofs   as build_hierarchy on a grid, over the fine mesh's DOFs
/// @param[in] options         levels = coarser_levels.size() + 1; validate_level_mesh_options
/// @throws Error if the meshes or options do not meet the above, local_refinement_operators
///         fails, or a wavelet stiffness B^k is not positive definite
Hierarchy build_hierarchy(const std::vector<mesh::Mesh>& coarser_levels,
                          const mesh::Mesh& fine_mesh, const SparseMatrix& K,
                          const std::vector<Index>& fixed_dofs, const Options& options);

/// build_hierarchy on level meshes with the fine operator already restricted to the DOFs free of
/// the Dirichlet conditions, as build_hierarchy_free on a grid (read in place, A_fine left
/// empty; the Eliminate and Constrain treatments).
/// @throws Error as build_hierarchy on level meshes, or if A_free is not #free DOFs square
Hierarchy build_hierarchy_free(const std::vector<mesh::Mesh>& coarser_levels,
                               const mesh::Mesh& fine_mesh, const SparseMatrix& A_free,
                               const std::vector<Index>& fixed_dofs, const Options& options);

/// The checks build_hierarchy makes on the options of a hierarchy on level meshes: those of
/// validate(options); localized solves (finite radius) node-wise with patch 1; canonical
/// measurements.
/// @throws Error saying what was expected
void validate_level_mesh_options(const Options& options);

/// The checks build_hierarchy makes on level meshes and their options, for a scene to make them
/// before any work.
/// @throws Error naming the level and what was expected
void validate_level_meshes(const std::vector<mesh::Mesh>& coarser_levels,
                           const mesh::Mesh& fine_mesh, const Options& options);

/// Restricts a fine vector (fine grid DOFs) to the hierarchy's fine DOFs and coarse-grains it to
/// level k (Sec. 3.6): g^k = C̃^k ... C̃^{q-1} g^q.
Vector coarse_grain(const Hierarchy& h, const Vector& g_fine, int k);

/// Φ^k = C̃^k ... C̃^{q-1} Φ^q (#dofs of level k by fine grid DOFs; k = q: the selection of the
/// present fine DOFs): the stored one if Options::store_bases, else computed.
/// @throws Error if k is not in 1..q
SparseMatrix basis(const Hierarchy& h, int k);

/// The Galerkin image on level k of an operator over the fine grid DOFs (the mass, Chen 2019
/// Sec. 4.2): X^q = X restricted to the hierarchy's fine DOFs, X^l = C̃^l X^{l+1} C̃^{l,T} for
/// l = q-1..k, i.e. Φ^k X Φ^{k,T}. Both triangles stored.
/// @throws Error if k is not in 1..q or X is not fine grid DOFs square
SparseMatrix galerkin_operator(const Hierarchy& h, const SparseMatrix& X, int k);
/// galerkin_operator's lower triangle, as Level::A keeps A^k, without the whole matrix.
/// @throws Error as galerkin_operator
SparseMatrix galerkin_operator_lower(const Hierarchy& h, const SparseMatrix& X, int k);

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
/// instead of 611 MB.
SparseMatrix symmetric_from_lower(const SparseMatrix& lower);

/// Nonzeros of the symmetric matrix whose lower triangle `lower` holds (stored zeros excluded).
Index symmetric_nonzeros(const SparseMatrix& lower);

}  // namespace coarsegrain::mra
