#pragma once
/// @file Effective elasticity tensors per coarse element (Kharevych et al. 2009, Eq. 8), the
/// averaging baselines (naive / Voigt / Reuss) and the coarse lumped mass, all weighted by the
/// exact intersection measures |T_p ∩ 𝕋_q| of mesh::intersect.
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/intersection.hpp"

namespace coarsegrain::homogenize {

/// Energy averages <G^T C G>_{𝕋_q} of Eq. 8 (before the coarse mollifier is applied):
/// A_q = sum over overlaps (p, q) of |T_p ∩ 𝕋_q| / |𝕋_q| G_p^T C_p G_p.
/// @param[in] dim             2 or 3
/// @param[in] G_fine          fine mollifiers, one per fine element (homogenize::mollifiers)
/// @param[in] fine_materials  fine element materials (C_p)
/// @param[in] overlaps        mesh::intersect(fine, coarse): sorted by coarse element
/// @param[in] coarse_measures #Ec measures |𝕋_q|
/// @return #Ec Mandel6 (top-left n by n block used), symmetric positive semi-definite
std::vector<Mandel6> energy_averages(int dim, const std::vector<Mandel6>& G_fine,
                                     const material::ElementMaterials& fine_materials,
                                     const std::vector<mesh::Overlap>& overlaps,
                                     const Vector& coarse_measures);

/// Eq. 8: ℂ_q = 𝔾_q^{-T} A_q 𝔾_q^{-1}, symmetrized (A_q from energy_averages, 𝔾_q the coarse
/// mollifiers). Then |𝕋_q| 𝔾_q^T ℂ_q 𝔾_q = |𝕋_q| A_q, which is Eq. 5 for every pair of harmonic
/// displacements.
/// @throws Error naming the coarse element if 𝔾_q is near-singular (see mollifier_singular)
std::vector<Mandel6> effective_tensors(int dim, const std::vector<Mandel6>& A,
                                       const std::vector<Mandel6>& G_coarse);

/// Mean Frobenius norm of the fine mollifiers, weighted by the fine element measures: the scale
/// against which a coarse mollifier counts as singular.
double mollifier_scale(int dim, const std::vector<Mandel6>& G_fine, const Vector& fine_measures);

/// True if the smallest singular value of the coarse mollifier is below 1e-10 times `scale`:
/// its inverse in Eq. 8 would amplify round-off. Coarse mollifiers of a mixed problem vanish
/// (to round-off) in the directions the fixed nodes pin; physical ones are larger than
/// scale / (material contrast x anisotropy), far above 1e-10 scale.
bool mollifier_singular(int dim, const Mandel6& G, double scale);

/// Condition number sigma_max / sigma_min of the n by n block.
double condition_number(int dim, const Mandel6& G);

/// The averaging baselines: per coarse element, the average of a fine property weighted by
/// |T_p ∩ 𝕋_q| over the material inside the element (cavities carry no tensor to average).
enum class Average {
    Naive,  ///< Lamé parameters λ, μ averaged, isotropic tensor rebuilt (needs isotropic fine
            ///< materials; in 3D and 2D plane strain the tensor is linear in λ, μ, so this
            ///< equals Voigt; it differs in 2D plane stress)
    Voigt,  ///< tensors averaged
    Reuss,  ///< compliances averaged, then inverted
};

/// Baseline tensors (Mandel6, top-left block used), one per coarse element.
/// @throws Error if a naive average meets an anisotropic fine material, or a coarse element
///         holds no fine material
std::vector<Mandel6> average_tensors(Average kind, const material::ElementMaterials& fine_materials,
                                     const std::vector<mesh::Overlap>& overlaps, Index num_coarse);

/// Mass of fine material inside each coarse element, sum over overlaps of rho_p |T_p ∩ 𝕋_q|
/// (cavities weigh nothing). Lumping it equally on the element's nodes gives the coarse lumped
/// mass (Sec. 3.3).
Vector coarse_element_masses(const material::ElementMaterials& fine_materials,
                             const std::vector<mesh::Overlap>& overlaps, Index num_coarse);

}  // namespace coarsegrain::homogenize
