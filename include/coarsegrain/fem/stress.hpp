#pragma once
/// @file Strain, stress and von Mises stress per element (at the element centre).
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem {

struct ElementStress {
    Matrix strain;  ///< #E by mandel_size(dim), Mandel
    Matrix stress;  ///< #E by mandel_size(dim), Mandel
    /// #E von Mises stress of the full 3D stress. In 2D the out-of-plane stress enters:
    /// plane strain sigma_zz = lambda (e11 + e22) (= C_zz11 e11 + C_zz22 e22 of the 3D isotropic
    /// tensor, from the material's E and nu), plane stress sigma_zz = 0. Anisotropic 2D
    /// materials (nu is NaN) carry no out-of-plane coupling, so sigma_zz = 0 is used for them.
    Vector von_mises;
};

/// Strain, stress and von Mises stress at each element centre for displacement u.
/// The same for both formulations (fem::Formulation): the incompatible modes' gradients vanish at
/// the element centre (dP/dxi = 4 (1 - 2 xi) = 0 at xi = 1/2), so the centre strain of the
/// enriched field is exactly that of the nodal Q1 field, whatever the condensed mode amplitudes.
ElementStress element_stress(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                             const Vector& u);

/// Rows of Mandel components (shear scaled by √2) as physical tensor components (shear / √2),
/// as ParaView and users read them.
Matrix mandel_to_physical(const Matrix& m);

/// Strain energy 1/2 u^T K u.
double strain_energy(const SparseMatrix& K, const Vector& u);

}  // namespace coarsegrain::fem
