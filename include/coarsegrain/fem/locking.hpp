#pragma once
/// @file Warnings for materials on which the fine element locks (near-incompressible materials).
#include <string>
#include <vector>

#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem {

/// One warning per isotropic material of the mesh whose Poisson ratio makes the element type
/// and formulation lock (volumetric locking): "material 2: nu = 0.499: standard hex elements
/// lock (...)", with the tip-deflection error measured on a cantilever (bench/bench_locking.cpp,
/// docs/guide.md "Near-incompressible materials") and what to do instead. None for plane stress
/// (no incompressibility constraint in the plane), for anisotropic materials (nu is NaN), and
/// for elements and formulations that do not lock at that nu.
/// Material ids come from mesh.material_ids (the table index if the mesh has none).
std::vector<std::string> locking_warnings(const mesh::Mesh& mesh,
                                          const material::ElementMaterials& mats,
                                          Formulation formulation);

}  // namespace coarsegrain::fem
