#pragma once
/// @file Grid problems shared by the material-adapted hierarchy tests.

#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::test {

/// A fine grid problem: mesh, stiffness, load, homogeneous Dirichlet DOFs and the fine solution.
struct GridProblem {
    mesh::Mesh mesh;
    material::ElementMaterials materials;
    SparseMatrix K;
    Vector f;
    fem::Dirichlet bc;
    Vector u;  ///< fine solution (Dirichlet DOFs eliminated)
};

/// Material id 1 (stiff) or 0 (soft) of an element from its centroid.
using MaterialPattern = std::function<int(const Eigen::VectorXd& centroid)>;

/// The problem on `mesh` (covering [0, size] along each axis) with two isotropic materials
/// (E_soft, E_stiff, nu = 0.3) given by `pattern`, fixed on the face y = max (hung from its top),
/// under gravity (0, -1[, 0]) and, if `pull`, a traction (1, 0.5[, 0.25]) on the face y = 0 so
/// that every displacement component is excited.
inline GridProblem hung_problem_on(mesh::Mesh mesh, double E_soft, double E_stiff,
                                   const MaterialPattern& pattern,
                                   const Eigen::Vector3d& size = Eigen::Vector3d::Ones(),
                                   bool pull = true) {
    GridProblem p;
    const int dim = mesh.dim();
    const Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim);
    const Eigen::VectorXd hi = size.head(dim);
    p.mesh = std::move(mesh);
    const Matrix centres = mesh::element_centroids(p.mesh);
    for (Index e = 0; e < p.mesh.num_elements(); ++e)
        p.mesh.material_ids[e] = pattern(centres.row(e).transpose());
    std::map<int, material::Material> by_id;
    by_id[0] = material::isotropic(dim, E_soft, 0.3, 1.0);
    by_id[1] = material::isotropic(dim, E_stiff, 0.3, 1.0);
    bool has0 = false, has1 = false;
    for (Index e = 0; e < p.mesh.num_elements(); ++e)
        (p.mesh.material_ids[e] == 0 ? has0 : has1) = true;
    if (!has0) by_id.erase(0);
    if (!has1) by_id.erase(1);
    p.materials = material::assign(p.mesh, by_id);
    p.K = fem::stiffness_matrix(p.mesh, p.materials);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(dim);
    g[1] = -1.0;
    p.f = fem::gravity_load(p.mesh, p.materials, g);
    const mesh::Boundary b = mesh::boundary(p.mesh);
    Eigen::VectorXd box_lo = lo.array() - 1e-9, box_hi = hi.array() + 1e-9;
    box_hi[1] = 1e-9;
    const std::vector<Index> bottom = mesh::facets_in_box(p.mesh, b, box_lo, box_hi);
    Eigen::VectorXd traction(dim);
    traction << 1.0, 0.5;
    if (dim == 3) traction << 1.0, 0.5, 0.25;
    if (pull) p.f += fem::traction_load(p.mesh, b, bottom, traction);
    box_lo = lo.array() - 1e-9;
    box_hi = hi.array() + 1e-9;
    box_lo[1] = hi[1] - 1e-9;
    p.bc.fix_nodes(mesh::nodes_in_box(p.mesh, box_lo, box_hi), Eigen::VectorXd::Zero(dim));
    const fem::ReducedSystem sys = fem::reduce(p.K, p.f, p.bc);
    solve::SpdSolver solver;
    solver.compute(sys.K);
    p.u = fem::expand(sys, solver.solve(sys.rhs), p.bc, p.mesh.num_dofs());
    return p;
}

/// hung_problem_on a grid over the unit square/cube (or [0, size]) with `cells` per axis: quads
/// or hexes.
inline GridProblem hung_problem(int dim, const Eigen::Vector3i& cells, double E_soft,
                                double E_stiff, const MaterialPattern& pattern,
                                const Eigen::Vector3d& size = Eigen::Vector3d::Ones(),
                                bool pull = true) {
    const Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim);
    const Eigen::VectorXd hi = size.head(dim);
    return hung_problem_on(
        mesh::make_grid(dim == 2 ? mesh::ElementType::Quad4 : mesh::ElementType::Hex8, lo, hi,
                        cells.head(dim)),
        E_soft, E_stiff, pattern, size, pull);
}

/// A homogeneous-free pattern with inclusions: stiff where sin-products are positive.
inline int checker_pattern(const Eigen::VectorXd& x) {
    double s = 1;
    for (int d = 0; d < x.size(); ++d) s *= std::sin(2.3 * M_PI * x[d] + 0.4 * d);
    return s > 0 ? 1 : 0;
}

/// Layers of thickness 0.25 across y, stiff (id 1) first: plates spanning a column's section.
inline int layers_across_y(const Eigen::VectorXd& x) {
    return static_cast<int>(std::floor(x[1] / 0.25)) % 2 == 0 ? 1 : 0;
}

/// Test name of a (dimension, refinement) parameter: "2D_dirac", "3D_linear", ...
inline std::string dim_refinement_label(const std::tuple<int, mra::Refinement>& p) {
    return std::to_string(std::get<0>(p)) + "D_" + mra::refinement_name(std::get<1>(p));
}

/// ||v||_K = sqrt(v^T K v).
inline double energy_norm(const SparseMatrix& K, const Vector& v) {
    return std::sqrt(v.dot(K * v));
}

/// Energy error ||u_c - u||_K / ||u||_K of the baseline the hierarchy improves on (Chen Fig. 2):
/// the Galerkin solution u_c in the canonical basis of level 1, C^1 ... C^{q-1} (Eq. 6; the
/// trilinear FEM on the coarsest grid for the linear refinement), with h's fine operator (and
/// Dirichlet treatment).
inline double canonical_energy_error(const mra::Hierarchy& h, const GridProblem& p) {
    SparseMatrix C = h.level(1).C;
    for (int k = 2; k < h.num_levels(); ++k) C = SparseMatrix(C * h.level(k).C);
    const SparseMatrix Ct = C.transpose();
    Vector f(h.fine_dofs.size());
    for (Index i = 0; i < f.size(); ++i) f[i] = p.f[h.fine_dofs[i]];
    solve::SpdSolver solver;
    solver.compute(SparseMatrix(C * h.A_fine * Ct));
    const Vector u_present = Ct * solver.solve(Vector(C * f));
    Vector u = Vector::Zero(p.u.size());
    for (Index i = 0; i < u_present.size(); ++i) u[h.fine_dofs[i]] = u_present[i];
    return energy_norm(p.K, u - p.u) / energy_norm(p.K, p.u);
}

/// Options for global solves without truncation or correction.
inline mra::Options exact_options(int levels, mra::Refinement r) {
    mra::Options o;
    o.levels = levels;
    o.refinement = r;
    o.invariance = false;
    o.truncation = 0;
    return o;
}

/// Largest absolute entry of M (0 if empty).
inline double max_abs(const Matrix& M) { return M.size() ? M.cwiseAbs().maxCoeff() : 0.0; }

/// exact_options with three levels and the conditions eliminated or the boundary rows kept
/// (constrain): the treatments of the hierarchy on level meshes' exactness tests.
inline std::vector<mra::Options> exact_level_options(mra::Refinement r) {
    mra::Options eliminate = exact_options(3, r), constrain = eliminate;
    eliminate.dirichlet = mra::DirichletTreatment::Eliminate;
    constrain.dirichlet = mra::DirichletTreatment::Constrain;
    return {eliminate, constrain};
}

}  // namespace coarsegrain::test
