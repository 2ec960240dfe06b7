#pragma once
/// @file The bar the corotated dynamics tests swing: clamped, layered, under gravity.
#include <vector>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/material/material_field.hpp"
#include "coarsegrain/mesh/grid.hpp"

namespace coarsegrain::test {

/// A bar [0, 3] x [0, 1] (x [0, 1]) of `type` elements (12x4 cells in 2D, 6x2x2 in 3D), clamped
/// at x = 0, of stiff dense (E = 50, density 4) and soft light (E = 2, density 0.5) layers across
/// its axis, under gravity (0, -g): g = 1 swings its tip down by about a third of its length
/// within t = 1.
struct SwingingBar {
    mesh::Mesh mesh;
    material::ElementMaterials mats;
    SparseMatrix K, M;  ///< stiffness and consistent mass
    Vector f;
    fem::Dirichlet bc;
};

inline SwingingBar make_swinging_bar(mesh::ElementType type, double g = 1) {
    const int dim = mesh::element_dim(type);
    SwingingBar b;
    b.mesh = dim == 2 ? mesh::make_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(3, 1),
                                        Eigen::Vector2i(12, 4))
                      : mesh::make_grid(type, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 1, 1),
                                        Eigen::Vector3i(6, 2, 2));
    material::layers(b.mesh, 0, 0.0, 0.5, {1, 2});
    b.mats = material::assign(b.mesh, {{1, material::isotropic(dim, 50.0, 0.3, 4.0)},
                                       {2, material::isotropic(dim, 2.0, 0.4, 0.5)}});
    b.K = fem::stiffness_matrix(b.mesh, b.mats);
    b.M = fem::mass_matrix(b.mesh, b.mats, fem::MassType::Consistent);
    Eigen::VectorXd gravity = Eigen::VectorXd::Zero(dim);
    gravity[1] = -g;
    b.f = fem::gravity_load(b.mesh, b.mats, gravity);
    std::vector<Index> clamped;
    for (Index v = 0; v < b.mesh.num_nodes(); ++v)
        if (b.mesh.rest_positions(v, 0) < 1e-9) clamped.push_back(v);
    b.bc.fix_nodes(clamped, Eigen::VectorXd::Zero(dim));
    return b;
}

}  // namespace coarsegrain::test
