#pragma once
/// @file Strain, stress and von Mises stress per element (at the element centre).
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem {

struct ElementStress {
    Matrix strain;     ///< #E by mandel_size(dim), Mandel
    Matrix stress;     ///< #E by mandel_size(dim), Mandel
    Vector von_mises;  ///< #E; in 2D plane strain sigma_zz = C_zz,ij eps_ij enters, plane stress 0
};

/// Strain, stress and von Mises stress at each element centre for displacement u.
ElementStress element_stress(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                             const Vector& u);

/// Strain energy 1/2 u^T K u.
double strain_energy(const SparseMatrix& K, const Vector& u);

}  // namespace coarsegrain::fem
