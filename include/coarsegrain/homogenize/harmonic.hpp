#pragma once
/// @file Global harmonic displacements and harmonic mollifiers (Kharevych et al. 2009, Sec. 3.2,
/// 3.4, 3.5, 4.2).
///
/// Conventions. The n = mandel_size(dim) harmonic displacements are ordered like Mandel
/// components, pair J = (a, b): (0,0) (1,1) (2,2) (1,2) (0,2) (0,1) in 3D, (0,0) (1,1) (0,1) in
/// 2D. Column J of a harmonic field matrix is h_ab, the response to the uniform stress
/// E^{ab} = (e_a ⊗ e_b + e_b ⊗ e_a) / 2 (names h_xx, h_yy, h_zz, h_yz, h_xz, h_xy). A mollifier
/// is a Mandel matrix (mandel_size(dim) square, top-left block of a Mandel6): column J is the
/// Mandel strain of the response to the J-th Mandel basis tensor, i.e. of h_ab for a normal pair
/// and of √2 h_ab for a shear pair; then ":" is a matrix product and G^{-1} the ordinary inverse.
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::homogenize {

/// The index pair (a, b), a <= b, of Mandel component J in dimension dim.
std::pair<int, int> mandel_pair(int dim, int J);
/// Field name of harmonic displacement J: "h_xx", "h_yy", "h_zz", "h_yz", "h_xz", "h_xy".
std::string harmonic_name(int dim, int J);
/// Mandel scaling of component J: 1 for a normal pair, √2 for a shear pair.
double mandel_weight(int dim, int J);

/// Global harmonic displacements h_ab (Eq. 6): div(C : eps(h_ab)) = 0 inside, traction
/// (C : eps(h_ab)) n = E^{ab} n on the outer boundary (component 0 of `b`), cavities (all other
/// components) traction-free (Sec. 4.2).
///
/// Pure Neumann (fixed_dofs empty): the six (three in 2D) rigid motions are removed by the
/// zeroth and first moments, sum_i w_i h_i = 0 and sum_i w_i (x_i - x̄) × h_i = 0 with w_i the
/// lumped nodal volumes. This equals the Lagrange-multiplier solution of
/// min 1/2 h^T K h - f^T h subject to the moment constraints, computed without an indefinite
/// system: (1) the load is equilibrated, f <- f - W R (R^T W R)^{-1} R^T f (R the rigid modes,
/// W the nodal volumes; a no-op up to round-off for the exact normals, whose tractions are
/// self-equilibrated, and a uniform "inertia relief" body load for the coarse normals, whose
/// tractions need not be); (2) six DOFs are pinned (3-2-1 at three far-apart nodes), which
/// leaves K positive definite and, because the load is equilibrated, adds no reaction;
/// (3) the rigid part is projected out by the moments. One CHOLMOD factorization serves all n
/// right-hand sides.
///
/// Mixed (fixed_dofs given, Sec. 3.8): h = 0 on the fixed DOFs, the same tractions elsewhere on
/// the outer boundary; no moment conditions.
///
/// @param[in] mesh        simplicial mesh (Tri3/Tet4)
/// @param[in] b           mesh::boundary(mesh)
/// @param[in] K           stiffness of mesh with its materials (num_dofs square, both triangles)
/// @param[in] normals     #F by dim unit normals used in the traction: b.normals (exact), or
///                        coarse_boundary_normals (Sec. 4.2)
/// @param[in] fixed_dofs  sorted DOFs held at 0 (mixed); empty for pure Neumann
/// @param[in] factorization  mixed only, optional: a factorization of K without fixed_dofs
///                        (fem::reduce's K_ff), e.g. a static solve's with the same conditions;
///                        K is then not factorized again
/// @return num_dofs by n matrix, column J = h_ab for Mandel pair J (interleaved DOFs)
/// @throws Error if the mesh is not simplicial, sizes disagree, or the problem is singular
///         (disconnected parts in the pure Neumann case, a part without fixed DOFs in the mixed
///         case)
Matrix harmonic_displacements(const mesh::Mesh& mesh, const mesh::Boundary& b,
                              const SparseMatrix& K, const Matrix& normals,
                              const std::vector<Index>& fixed_dofs = {},
                              const solve::SpdSolver* factorization = nullptr);

/// The normals N of Sec. 4.2: for each fine boundary facet of the outer boundary (component 0),
/// the outward unit normal of the coarse boundary facet it faces: the first one the ray from the
/// fine facet's centroid along the fine normal meets (a facet on the coarse boundary meets itself
/// at distance 0). Candidates are the coarse boundary facets that share a node with the coarse
/// element containing (or nearest to) the centroid, or all coarse boundary facets if there are
/// none; if the ray meets no candidate, the nearest candidate is taken. Facets of other
/// components keep their own normals (they carry no traction).
Matrix coarse_boundary_normals(const mesh::Mesh& fine, const mesh::Boundary& fb,
                               const mesh::Mesh& coarse);

/// Harmonic mollifier per element (Sec. 3.5), G_{klab} = (H_{kab,l} + H_{lab,k}) / 2: the strain
/// of the P1 interpolant of the harmonic fields on each simplex, as a Mandel matrix (file
/// comment). On the fine mesh with the fine fields this is G_{T_p}; on the coarse mesh with the
/// coarse-sampled fields (sample_harmonic) it is the coarse mollifier 𝔾_{𝕋_q} of Eq. 8.
/// @param[in] mesh  simplicial mesh
/// @param[in] h     num_dofs by n harmonic fields (harmonic_displacements layout)
/// @return #E Mandel6 matrices, top-left n by n block used, rest zero
std::vector<Mandel6> mollifiers(const mesh::Mesh& mesh, const Matrix& h);

/// Samples the harmonic fields at points (Sec. 3.2, 4.2): barycentric interpolation in the fine
/// element containing the point; for a point outside the fine mesh (or in a cavity), barycentric
/// extrapolation from the nearest fine element, i.e. its affine interpolant evaluated at the
/// point (negative barycentric coordinates). Reproduces fields that are affine on the fine mesh
/// exactly, inside and outside.
/// @param[in] fine     simplicial fine mesh
/// @param[in] locator  PointLocator over fine
/// @param[in] h        fine num_dofs by n fields
/// @param[in] points   #P by dim points
/// @param[out] distance  if non-null: #P distances from the fine mesh (0 inside)
/// @return (dim * #P) by n sampled fields, interleaved like displacements
Matrix sample_harmonic(const mesh::Mesh& fine, const mesh::PointLocator& locator, const Matrix& h,
                       const Matrix& points, Vector* distance = nullptr);

}  // namespace coarsegrain::homogenize
