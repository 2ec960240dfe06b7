#pragma once
/// @file Per-element elasticity tensors as VTU cell fields, so a coarse model written by
/// `coarsegrain coarsen` (coarse_model.vtu) can be read back and simulated without the fine
/// mesh.
///
/// Storage: one scalar cell field per independent entry of the Voigt stiffness (engineering
/// shear strains; ordering 11 22 33 23 13 12 in 3D, 11 22 12 in 2D, 1-based): "C_voigt_IJ" for
/// I <= J (21 fields in 3D, 6 in 2D), plus "density". Voigt, not Mandel, because it is the
/// notation of the scene files' "C_voigt" and of most engineering references.
#include <map>
#include <string>

#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/material/material.hpp"

namespace coarsegrain::io {

/// Name of the Voigt entry (I, J), 0-based indices: "C_voigt_<I+1><J+1>" with I <= J.
std::string voigt_field_name(int I, int J);

/// Appends the C_voigt_IJ and density cell fields of one material per element (write_vtu checks
/// that their length matches the mesh's elements).
void add_element_material_fields(VtuFields& fields, const material::ElementMaterials& mats);

/// True if the cell fields hold every C_voigt_IJ of dimension dim (and then density must be
/// there too; element_materials_from_fields checks).
bool has_element_material_fields(const VtuFields& fields, int dim);

/// One anisotropic material per element from the cell fields; sets mesh.material_ids to the
/// element index, which is each material's key.
/// @param[in] source  file name for messages
/// @throws Error naming the source, field and element if a field is missing or has the wrong
///         size, or an element's tensor is not symmetric positive definite
std::map<int, material::Material> element_materials_from_fields(const VtuFields& fields,
                                                                mesh::Mesh& mesh,
                                                                const std::string& source);

}  // namespace coarsegrain::io
