#pragma once
/// @file Linear-elastic materials: isotropic and general anisotropic tensors in Mandel form.
#include <map>
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::material {

/// How a 2D problem relates to 3D: plane strain (default, eps_zz = 0) or plane stress
/// (sigma_zz = 0).
enum class PlaneMode { Strain, Stress };

/// A linear-elastic material.
struct Material {
    /// Elasticity tensor, Mandel form; in 2D the top-left 3x3 block (e11 e22 √2e12) is used.
    Mandel6 C = Mandel6::Zero();
    double density = 1.0;  ///< mass per unit volume (per unit area in 2D)
    /// Young's modulus and Poisson ratio for isotropic materials; for anisotropic ones E is the
    /// mean directional Young's modulus along the axes and nu is NaN.
    double E = 0.0;
    double nu = 0.0;
    /// For 2D isotropic materials: whether C is the plane-strain or the plane-stress tensor
    /// (element_stress uses it for sigma_zz); meaningless in 3D and for anisotropic materials.
    PlaneMode mode = PlaneMode::Strain;
};

/// Isotropic material from Young's modulus and Poisson's ratio.
///
/// 3D: C = lambda 1⊗1 + 2 mu I (Mandel), lambda = E nu / ((1+nu)(1-2nu)), mu = E / (2(1+nu)).
/// 2D plane strain: the (11, 22, 12) block of the 3D tensor. 2D plane stress: the tensor with
/// sigma_zz = 0 condensed out, E/(1-nu^2) [1 nu 0; nu 1 0; 0 0 1-nu].
/// @param[in] dim   2 or 3
/// @param[in] mode  for dim = 2: plane strain (default) or plane stress; ignored in 3D
/// @throws Error unless E > 0, -1 < nu < 0.5, density > 0 (the message names the value)
Material isotropic(int dim, double E, double nu, double density,
                   PlaneMode mode = PlaneMode::Strain);

/// General anisotropic material from a Mandel tensor (mandel_size(dim) square).
/// E is set to the mean of directional_young along the coordinate axes, nu to NaN.
/// @throws Error unless C is finite, symmetric (1e-10 relative) and positive definite (smallest
///         eigenvalue > 1e-12 times the largest) and density > 0
Material anisotropic(int dim, const Matrix& C_mandel, double density);

/// Converts a Voigt-notation stiffness (engineering shear strains; 21 / 6 independent entries,
/// ordering 11 22 33 23 13 12 in 3D, 11 22 12 in 2D) to Mandel form.
Matrix voigt_to_mandel(const Matrix& C_voigt);
/// Inverse of voigt_to_mandel.
Matrix mandel_to_voigt(const Matrix& C_mandel);

/// The mandel_size(dim) square block of m.C that is used in dimension dim.
inline Eigen::Block<const Mandel6> tensor(const Material& m, int dim) {
    const int n = mandel_size(dim);
    return m.C.topLeftCorner(n, n);
}

/// Directional Young's modulus 1 / (d⊗d : S : d⊗d) with S = C^{-1}, along direction d (size
/// dim, normalized here). In 2D this is the modulus of the 2D tensor: E for plane stress,
/// E / (1 - nu^2) for a plane-strain isotropic tensor.
/// @throws Error if the sizes do not match or d is zero
double directional_young(const Matrix& C_mandel, const Eigen::VectorXd& d);

/// Materials of the elements of one mesh: element e uses table[index[e]].
struct ElementMaterials {
    int dim = 3;
    std::vector<Material> table;
    IndexVector index;  ///< #E index into table

    const Material& of(Index e) const { return table[static_cast<std::size_t>(index[e])]; }
    Index size() const { return static_cast<Index>(index.size()); }
};

/// Looks up each element's material id in `by_id`. The table holds the materials of the ids
/// that occur, in increasing id order.
/// @throws Error naming the first material id that has no material and how many elements use it
ElementMaterials assign(const mesh::Mesh& mesh, const std::map<int, Material>& by_id);

/// One material for every element.
ElementMaterials uniform(const mesh::Mesh& mesh, const Material& m);

}  // namespace coarsegrain::material
