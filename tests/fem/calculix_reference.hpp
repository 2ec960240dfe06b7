#pragma once
/// @file The problems stored in tests/data/calculix/*.json (scripts/calculix/make_reference.py
/// and the scripts beside it say how CalculiX solved them), rebuilt with the library: the mesh,
/// the materials, the loads (gravity and a pressure) and the clamp.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::test {

inline nlohmann::json read_reference(const std::string& name) {
    const std::string path = std::string(COARSEGRAIN_TEST_DATA) + "/calculix/" + name + ".json";
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << "cannot open " << path;
    return nlohmann::json::parse(in);
}

inline Eigen::VectorXd vec(const nlohmann::json& a) {
    Eigen::VectorXd v(static_cast<Index>(a.size()));
    for (Index i = 0; i < v.size(); ++i) v[i] = a[static_cast<std::size_t>(i)].get<double>();
    return v;
}

/// Mesh stored in the reference: nodes, 0-based connectivity (VTK order), material ids.
/// Elements "hex", "tet" or "quad" (the plane-strain layer's quads, 2D nodes).
inline mesh::Mesh reference_mesh(const nlohmann::json& ref) {
    mesh::Mesh m;
    m.type = ref["element"] == "hex"    ? mesh::ElementType::Hex8
             : ref["element"] == "quad" ? mesh::ElementType::Quad4
                                        : mesh::ElementType::Tet4;
    const int dim = mesh::element_dim(m.type);
    const auto& nodes = ref["nodes"];
    const auto& elements = ref["elements"];
    const auto& ids = ref["material_ids"];
    m.rest_positions.resize(static_cast<Index>(nodes.size()), dim);
    for (std::size_t v = 0; v < nodes.size(); ++v)
        for (int d = 0; d < dim; ++d)
            m.rest_positions(static_cast<Index>(v), d) = nodes[v][static_cast<std::size_t>(d)];
    const int npe = mesh::nodes_per_element(m.type);
    m.elements.resize(static_cast<Index>(elements.size()), npe);
    m.material_ids.resize(static_cast<Index>(elements.size()));
    for (std::size_t e = 0; e < elements.size(); ++e) {
        for (int a = 0; a < npe; ++a)
            m.elements(static_cast<Index>(e), a) = elements[e][static_cast<std::size_t>(a)];
        m.material_ids[static_cast<Index>(e)] = ids[e];
    }
    mesh::validate(m, "calculix/" + ref["name"].get<std::string>() + ".json");
    return m;
}

/// The reference's isotropic materials on mesh m (2D: plane strain, the default).
inline material::ElementMaterials reference_materials(const nlohmann::json& ref,
                                                      const mesh::Mesh& m) {
    std::map<int, material::Material> by_id;
    for (const auto& [id, mat] : ref["materials"].items())
        by_id[std::stoi(id)] = material::isotropic(m.dim(), mat["E"], mat["nu"], mat["density"]);
    return material::assign(m, by_id);
}

/// The reference's load and clamp on mesh m.
struct ReferenceConditions {
    Vector f;  ///< gravity + pressure p on the faces in the load box (traction -p n)
    fem::Dirichlet bc;
};

/// Builds the load and the clamp, checking that they select exactly what ccx loaded / held.
inline ReferenceConditions reference_conditions(const nlohmann::json& ref, const mesh::Mesh& m,
                                                const material::ElementMaterials& mats) {
    const mesh::Boundary b = mesh::boundary(m);
    const auto& pressure = ref["pressure"];
    const std::vector<Index> facets =
        mesh::facets_in_box(m, b, vec(pressure["box"]["min"]), vec(pressure["box"]["max"]));
    EXPECT_EQ(facets.size(), pressure["faces"].size());  // the faces ccx loaded, one for one
    const Eigen::VectorXd normal = b.normals.row(facets.front()).transpose();
    for (const Index f : facets)
        EXPECT_LT((b.normals.row(f).transpose() - normal).norm(), 1e-12);  // a flat face
    const double p = pressure["value"];
    ReferenceConditions c;
    c.f = fem::gravity_load(m, mats, vec(ref["gravity"])) +
          fem::traction_load(m, b, facets, -p * normal);
    const auto& dirichlet = ref["dirichlet"];
    const std::vector<Index> fixed =
        mesh::nodes_in_box(m, vec(dirichlet["box"]["min"]), vec(dirichlet["box"]["max"]));
    EXPECT_EQ(fixed, dirichlet["nodes"].get<std::vector<Index>>());
    c.bc.fix_nodes(fixed, vec(dirichlet["value"]));
    return c;
}

/// Solves the reference problem (gravity, pressure, clamp) with stiffness K on mesh m.
inline Vector solve_reference(const nlohmann::json& ref, const mesh::Mesh& m,
                              const material::ElementMaterials& mats, const SparseMatrix& K) {
    const auto [f, bc] = reference_conditions(ref, m, mats);
    const fem::ReducedSystem sys = fem::reduce(K, f, bc);
    solve::SpdSolver solver;
    solver.compute(sys.K);
    return fem::expand(sys, solver.solve(sys.rhs), bc, m.num_dofs());
}

/// The displacements a static reference stores, interleaved (dim per node).
inline Vector ccx_displacements(const nlohmann::json& ref, int dim) {
    const auto& disp = ref["displacements"];
    Vector u(dim * static_cast<Index>(disp.size()));
    for (std::size_t v = 0; v < disp.size(); ++v)
        for (int d = 0; d < dim; ++d)
            u[dim * static_cast<Index>(v) + d] = disp[v][static_cast<std::size_t>(d)];
    return u;
}

/// Whether x matches a value ccx printed as d.dddddd E+xx: within half a unit in its last digit
/// (5e-7 * 10^floor(log10|printed|)) plus `round_off` for values that are round-off themselves.
inline bool matches_printed(double x, double printed, double round_off) {
    const double v = std::abs(printed);
    const double half_ulp = v > 0 ? 5e-7 * std::pow(10.0, std::floor(std::log10(v))) : 0.0;
    return std::abs(x - printed) <= half_ulp * (1 + 1e-9) + round_off;
}

/// max|u - u_ccx| / max|u_ccx|, and (in `off`) the components that differ from ccx's printed
/// value by more than half a unit in its last digit (plus 1e-12 max|u_ccx| of round-off).
inline double ccx_difference(const Vector& u, const Vector& u_ccx, Index* off) {
    const double scale = u_ccx.lpNorm<Eigen::Infinity>();
    *off = 0;
    for (Index i = 0; i < u.size(); ++i)
        if (!matches_printed(u[i], u_ccx[i], 1e-12 * scale)) ++*off;
    return (u - u_ccx).lpNorm<Eigen::Infinity>() / scale;
}

}  // namespace coarsegrain::test
