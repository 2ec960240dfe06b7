#pragma once
/// @file Coarse-to-fine maps: the barycentric embedding and the quasi-static harmonic map of
/// Kharevych et al. 2009, Sec. 4.3 (Eq. 9-10).
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mesh/point_locator.hpp"

namespace coarsegrain::homogenize {

/// The coarse element that carries each point: the one containing it, or the nearest one for a
/// point outside the coarse mesh (mesh::PointLocator::locate_nearest).
/// @param[in] points  #P by dim
/// @return #P locations in the coarse mesh (weights clamped for points outside)
std::vector<mesh::Location> locate_points(const mesh::PointLocator& coarse_locator,
                                          const Matrix& points);

/// Barycentric embedding: u(x) = sum_a w_a(x) U_a with the coarse element's interpolation
/// weights at each point (clamped for points outside the coarse mesh, so a point within round-off
/// of the boundary takes its nearest boundary value).
/// @param[in] coarse     the coarse mesh (any element type)
/// @param[in] locations  locate_points(...) of the points
/// @return (dim * #P) by coarse num_dofs sparse matrix, u_points = E * u_coarse (interleaved)
SparseMatrix barycentric_embedding(const mesh::Mesh& coarse,
                                   const std::vector<mesh::Location>& locations);

/// Fine Dirichlet conditions carried to a coarse model: its DOFs become w with u_coarse = T w.
struct CarriedConditions {
    SparseMatrix T;     ///< coarse DOFs by reduced DOFs (the identity where no constraint couples)
    fem::Dirichlet bc;  ///< conditions on the reduced DOFs
    Index fixed = 0;    ///< coarse DOFs held at a value
    Index constrained = 0;   ///< coarse DOFs held only in combination (multi-point constraints)
    Index combinations = 0;  ///< the free combinations of those (reduced DOFs that replace them)
};

/// The fine Dirichlet conditions carried to the coarse DOFs through a coarse-to-fine map E
/// (u_fine = E u_coarse, e.g. barycentric_embedding): E u_coarse must take the prescribed fine
/// values g on the fixed fine DOFs F. The coarse DOFs that touch them (an entry of E above 1e-10
/// in their rows: smaller weights are round-off of a fine node on a coarse facet) fall into
/// blocks coupled by common fixed fine DOFs. A block whose columns of E_F are independent is
/// fixed: each DOF at its least-squares value (E_FD^T E_FD)^-1 E_FD^T g, zero for zero values
/// (a coarse mesh whose nodes lie on the clamped face). Otherwise (a coarse mesh sticking out
/// beyond the clamped face, a clamp inside coarse elements) only the combinations in the null
/// space of E_FD stay free: the block's DOFs are replaced by coordinates in that null space plus
/// the minimum-norm least-squares values (carried by one extra DOF held at 1), so that the fine
/// nodes are held without fixing whole coarse elements.
/// @throws Error if a fine Dirichlet DOF is out of E's rows
CarriedConditions carry_dirichlet(const fem::Dirichlet& fine, const SparseMatrix& E);

/// The quasi-static harmonic map (Sec. 4.3). For each coarse simplex 𝕋_q with rest corners X^i
/// and deformed corners x^i, a rotation R and a combination S of the harmonic displacements
/// match the deformed edges (Eq. 9),
///     R (x^i - x^0) = X^i - X^0 + (H^i - H^0) : S,   i = 1..dim,
/// (dim^2 equations for the dim(dim-1)/2 rotation and mandel_size(dim) coefficients of S), and
/// every fine point x0 carried by 𝕋_q is placed by the same R and S (Eq. 10),
///     x = x^0 + R^T (x0 - X^0 + (H(x0) - H^0) : S).
/// H(x0) is the fine harmonic field at x0 and H^i the coarse-sampled one (sample_harmonic).
/// Coarse deformations that are themselves combinations of harmonic displacements are thus
/// carried to the fine mesh exactly, with their fine-scale detail, where the barycentric
/// embedding only interpolates them linearly.
class HarmonicMap {
  public:
    /// @param[in] coarse     simplicial coarse mesh (copied)
    /// @param[in] H_coarse   (dim * coarse #V) by n harmonic fields at the coarse nodes
    /// @param[in] points     #P by dim fine rest positions
    /// @param[in] H_points   (dim * #P) by n harmonic fields at the fine points
    /// @param[in] carrier    #P coarse element carrying each point (locate_points)
    /// @throws Error if sizes disagree, or the harmonic edge map of a coarse element is singular
    ///         (its coarse mollifier is)
    HarmonicMap(const mesh::Mesh& coarse, const Matrix& H_coarse, const Matrix& points,
                const Matrix& H_points, std::vector<Index> carrier);

    /// Eq. 9-10 for a deformed coarse mesh: solves each element's R and S by Newton's method
    /// from the polar rotation of the element's deformation gradient.
    /// @param[in] coarse_deformed  coarse #V by dim deformed positions
    /// @return #P by dim deformed fine positions
    /// @throws Error naming the coarse element if no rotation matches (no convergence)
    Matrix deformed_positions(const Matrix& coarse_deformed) const;

    /// The map linearized about the rest state (R = I + [ω]×, small displacements): a sparse
    /// (dim * #P) by coarse num_dofs matrix with u_points = L * u_coarse. Fine displacements
    /// that are combinations of harmonic displacements plus rigid motions are reproduced
    /// exactly from their coarse samples.
    const SparseMatrix& linearized() const { return m_linear; }

  private:
    int m_dim;
    mesh::Mesh m_coarse;
    Matrix m_H_coarse;
    Matrix m_points;
    Matrix m_H_points;
    std::vector<Index> m_carrier;
    /// Per coarse element: the d^2 square matrix of Eq. 9 linearized at R = I, columns
    /// [ΔH_J (coarse edge differences of field J) | W_r (X^i - X^0)], rows (i, k).
    std::vector<Matrix> m_edge_maps;
    SparseMatrix m_linear;
};

}  // namespace coarsegrain::homogenize
