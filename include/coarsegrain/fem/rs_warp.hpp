#pragma once
/// @file Rotation-strain (RS) post-warping of linear displacements (Chen et al. 2019, Sec. 4.3,
/// Eq. 13): a displacement computed by linear elasticity (for example a coarse solution carried
/// to the fine mesh) balloons under large rotations; the warp replaces its gradient by the RS
/// transform, which turns the skew part into a finite rotation, and reconstructs the
/// displacement whose gradient is closest to it (a Poisson problem per component).
#include <memory>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::fem {

/// The Cayley map Cay(A) = (I - A/2)^{-1} (I + A/2) of a skew dim x dim matrix A (dim 2 or 3):
/// the rotation about A's axis by the angle φ = 2 atan(θ/2), where θ is the angle of the
/// infinitesimal rotation A (A x = θ n × x in 3D, A = θ [[0, -1], [1, 0]] in 2D). φ = θ - θ³/12
/// + O(θ⁵): the rotation the exponential map exp(A) would give, a little smaller (73.7° instead
/// of 85.9° at θ = 1.5). Evaluated in closed form, Cay(A) = I + 4 / (4 + θ²) (A + A²/2).
/// @throws Error if A is not square of size 2 or 3, or not skew (|A + Aᵀ| > 1e-12 (1 + |A|),
///         Frobenius norms)
Matrix cayley(const Matrix& A);

/// The rotation-strain transform of a displacement gradient G (dim x dim, dim 2 or 3, entry
/// (i, k) = du_i/dx_k): RS(G) = Cay[(G - Gᵀ)/2] (I + (G + Gᵀ)/2) - I (Chen 2019, Sec. 4.3).
/// The skew part of G becomes the finite rotation Cay, the symmetric part stays the strain.
/// RS(G) = G + O(|G|²): a small gradient is left unchanged to first order; a symmetric G is
/// returned unchanged and a skew G gives Cay(G) - I.
/// @throws Error if G is not square of size 2 or 3
Matrix rs_transform(const Matrix& G);

/// The RS post-warp of displacements on one mesh (Chen 2019, Eq. 13):
///
///     û = argmin_v ∫_Ω |∇v - RS(∇u)|_F²  with v = the prescribed values on the Dirichlet DOFs.
///
/// The integral is evaluated at the quadrature points of the stiffness matrix (2^dim Gauss
/// points per Quad4 / Hex8, the centroid of a Tri3 / Tet4), where ∇u and its RS transform are
/// computed. The objective decouples by displacement component: the normal equations are the
/// scalar Laplacian, L v_i = b_i with L_ab = ∫ ∇N_a · ∇N_b and b_ai = ∫ ∇N_a · (row i of RS),
/// on the nodes whose component i is free.
///
/// Factorization: the components are grouped by their set of prescribed nodes, and each group
/// gets one factorization of the scalar Laplacian restricted to its free nodes, solved with one
/// right-hand side per component of the group. With the usual clamp (every constrained node has
/// all its components prescribed) that is one scalar factorization with dim right-hand sides,
/// about dim² times fewer nonzeros and dim³ times fewer flops than an interleaved dim-block
/// system of the same mesh (64x16x16 hexes clamped at one end: nnz(L) 3.6M against 32.2M for the
/// elasticity stiffness, 1.3 against 35 GFlop; bench/bench_rs_warp.cpp). Rollers or symmetry
/// planes (components prescribed on different nodes) give up to dim factorizations, each still
/// scalar. The prescribed values' contribution -L_fd v_d is computed once at construction.
///
/// Each call then computes ∇u and RS(∇u) at every quadrature point (OpenMP, parallel over the
/// elements), the right-hand sides (gathered per node, race free) and one back-substitution per
/// group. The physical shape gradients and weights of every quadrature point are computed at
/// construction; on a regular grid (mesh.grid set, Quad4 / Hex8) all cells share one set.
///
/// Both u and û are displacements of the rest positions; the Dirichlet values are those the
/// warped field takes (Chen: S û = 0, the fine Dirichlet nodes fixed).
class RsWarp {
  public:
    /// Assembles the Laplacian and factorizes it, one factorization per group of components
    /// with the same prescribed nodes. options chooses the backend; the Laplacian is scalar,
    /// so node_dofs, keep_order and lower_triangle are ignored. Phases "assemble" (quadrature data,
    /// Laplacian, its restrictions to the free nodes), "analyze" (orderings) and "factorize" go
    /// to `timings`.
    /// @throws Error naming the warp (RsWarp) if the mesh's positions or connectivity have the
    ///         wrong number of columns, bc is invalid (unsorted, out of range, or values and dofs
    ///         of different lengths), an element is inverted or degenerate, or a connected part
    ///         of the mesh (a node in no element is a part of its own) has a component
    ///         prescribed at none of its nodes: its Laplacian is singular there
    RsWarp(const mesh::Mesh& mesh, const Dirichlet& bc, const solve::SolverOptions& options = {},
           Timings* timings = nullptr);
    ~RsWarp();
    RsWarp(RsWarp&&) noexcept;
    RsWarp& operator=(RsWarp&&) noexcept;

    /// The warped displacement û (num_dofs, interleaved) of u (num_dofs); û takes bc's values on
    /// its DOFs. Phases "rs" (gradients, RS transforms and right-hand sides) and "solve" (the
    /// back-substitutions) go to `timings`. Not thread-safe (one solve at a time per warp).
    /// @throws Error on a size mismatch or a non-finite u
    Vector operator()(const Vector& u, Timings* timings = nullptr) const;

    /// Number of DOFs of the mesh (dim x nodes).
    Index num_dofs() const;
    /// Number of scalar factorizations: one per distinct set of nodes at which a component is
    /// prescribed (1 for a clamp of whole nodes, at most dim), not counting a component
    /// prescribed at every node (nothing to solve).
    int num_factorizations() const;
    /// Unknowns of each factorization (the free nodes of its group), in component order.
    std::vector<Index> factorization_sizes() const;
    /// Ordering, nnz(L) and flops of each factorization.
    /// @throws Error unless the backend is cholmod
    std::vector<solve::FactorStats> factor_stats() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace coarsegrain::fem
