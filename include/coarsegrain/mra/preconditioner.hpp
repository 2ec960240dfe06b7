#pragma once
/// @file The material-adapted hierarchy as a multigrid preconditioner for conjugate gradients on
/// the fine model (Chen et al. 2019, Sec. 6: "as a multigrid preconditioner"): the adapted
/// refinements C̃^k of a cheap localized build restrict residuals and their transposes prolong
/// corrections, the Galerkin operators A^k = C̃^k A^{k+1} C̃^{k,T} (Alg. 1 line 7) are the level
/// operators, Chebyshev smoothing on every level but the coarsest, whose A^1 is factorized.
/// The fine solve is then exact to the solver's tolerance, whatever the accuracy of the
/// hierarchy as a coarse model.
#include <memory>
#include <vector>

#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/solve/pcg.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::mra {

/// The levels the preconditioner uses on a grid of `cells` cells per axis (first dim entries):
/// options.levels if set, else the fewest q >= 2 such that the grid of level 1 has at most
/// options.coarsest_dofs DOFs or its cells no longer halve along every axis.
/// @throws Error if the cells do not halve once (some axis has an odd count), or options.levels
///         is set and the cells are not divisible by 2^(levels - 1)
int preconditioner_levels(const Eigen::Vector3i& cells, int dim,
                          const PreconditionerOptions& options);

/// The levels the preconditioner uses on a fine mesh: on a grid, preconditioner_levels of its
/// cells; on triangles or tetrahedra (automatic level meshes, automatic_levels.hpp) with N
/// nodes in dimension d, options.levels if set, else the fewest q >= 2 whose coarsest level is
/// expected to have at most options.coarsest_dofs DOFs (d N / 2^{d(q-1)}), at most
/// max_automatic_levels(fine).
/// @throws Error if the mesh is neither a grid nor simplicial, or as the grid version, or if
///         options.levels is set above max_automatic_levels(fine)
int preconditioner_levels(const mesh::Mesh& fine, const PreconditionerOptions& options);

/// One V-cycle over a hierarchy as a preconditioner, M^{-1} r = V(q, r) with
/// V(1, b) = A^{1,-1} b and, for k > 1, x = S_k b, x += C̃^{k-1,T} V(k-1, C̃^{k-1} (b - A^k x)),
/// x += S_k (b - A^k x): S_k the Chebyshev polynomial of degree d in D_k^{-1} A^k on
/// [λ/10, 1.1 λ] (λ: the largest eigenvalue of D_k^{-1} A^k, estimated by 20 power iterations,
/// D_k = diag A^k). The same polynomial before and after makes M symmetric; it is positive
/// definite when the smoothing converges in the A^k norm (the λ estimate within 10%).
class MultigridPreconditioner : public solve::Preconditioner {
  public:
    /// @param h  a hierarchy built with DirichletTreatment::Eliminate or Constrain on the fine
    ///           operator A (build_hierarchy_free; an A_fine is released: the cycle uses A,
    ///           which must outlive this)
    /// @param A  the fine operator on the hierarchy's fine DOFs, both triangles stored
    /// @throws Error if A is not the hierarchy's fine operator size, or on a boundary-blind or
    ///         penalized hierarchy; NotPositiveDefinite if A^1 is not positive definite
    MultigridPreconditioner(Hierarchy h, const SparseMatrix& A, int smoother_degree);
    ~MultigridPreconditioner() override;

    /// z = M^{-1} r over the hierarchy's fine DOFs.
    Vector apply(const Vector& r) const override;

    const Hierarchy& hierarchy() const { return m_h; }
    /// Per level k = 1..q: its DOFs and the stored entries of its operator.
    std::vector<std::pair<Index, Index>> level_sizes() const;

  private:
    struct Level;
    /// V(k, b) for level index i = k - 1.
    Vector cycle(std::size_t i, const Vector& b) const;
    void smooth(const Level& L, const Vector& b, Vector& x) const;

    Hierarchy m_h;
    std::vector<Level> m_levels;  ///< index k - 1
    solve::SpdSolver m_coarsest;
    int m_degree;
};

/// The factory of mra-pcg's preconditioner for the fine model of a scene: given the stiffness
/// (or a step operator) restricted to the free DOFs (all DOFs of `fine` but `fixed_dofs`, in
/// order, as fem::reduce makes it), builds the hierarchy on it (linear refinement, node
/// localization at options.radius, Dirichlet DOFs eliminated, truncation 1e-7, invariance
/// correction; B^k dropped once used, Options::store_wavelet_stiffness) and the V-cycle. On a
/// grid the levels are its nested grids; on triangles or tetrahedra they are the automatic
/// level meshes (made at each call, phase "mra-pcg: levels"), the localized regions rings of
/// the finer level's node graph. With options.deflation and stiff clusters in `materials`
/// (found once, here), the cycle is deflated by their rigid motions extended over
/// options.deflation_rings rings (solve::DeflatedPreconditioner around the cycle). Phases
/// "mra-pcg: hierarchy", "mra-pcg: cycle" and "mra-pcg: deflation".
/// @param fine        the fine mesh, a grid (mesh::make_grid) or simplicial; copied
/// @param materials   the fine model's element materials (read here only)
/// @param fixed_dofs  the Dirichlet DOFs, sorted
/// @throws Error if preconditioner_levels or fem::stiff_clusters does; (when called) if the
///         matrix is not #free DOFs square, or as automatic_level_meshes and build_hierarchy
solve::PreconditionerFactory hierarchy_preconditioner(const mesh::Mesh& fine,
                                                      const material::ElementMaterials& materials,
                                                      std::vector<Index> fixed_dofs,
                                                      const PreconditionerOptions& options);

/// The V-cycle inside a preconditioner made by hierarchy_preconditioner (itself, or the base of
/// its deflation).
/// @throws Error if M is neither
const MultigridPreconditioner& multigrid_cycle(const solve::Preconditioner& M);

}  // namespace coarsegrain::mra
