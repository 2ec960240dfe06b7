// Volumetric and shear locking of the fine elements: the tip deflection of a cantilever under
// gravity for every element type and formulation, against the converged answer. Prints the
// tables of docs/guide.md ("Near-incompressible materials") and the errors behind the warnings of
// fem::locking_warnings (src/fem/locking.cpp).
//
//   build/release/bench/bench_locking            # 3D and 2D tables (a few minutes on 2 cores)
//   build/release/bench/bench_locking --2d       # 2D only (seconds)
//
// The problem: a 4 x 1 x 1 beam (4 x 1 in 2D, plane strain), E = 1000, density 1, gravity 1
// along -z (-y), clamped at x = 0; the deflection is -u_z (-u_y) at the centre of the free end,
// (4, 0.5, 0.5). Grids 16x1x1 (one element through the depth: bending alone, where shear locking
// shows) and 8x2x2 .. 64x16x16 (8x2 .. 64x16 in 2D), through the scene pipeline
// (scene::parse_scene, build_fine_model, solve_static, probe_displacements).
//
// Formulations: "standard" and "incompatible" (fem::Formulation), and, for comparison only,
// "sri": selective reduced integration, the Lame lambda term at the centre point alone and the
// mu term with 2^dim Gauss points (isotropic materials; on these parallelepipeds it is the
// B-bar element of Hughes, the mean dilatation being the centre one). SRI is assembled here, not
// in the library.
//
// The converged answer per nu: Richardson extrapolation of the SRI element on the three finest
// grids, u* = u3 + (u3 - u2) / (2^p - 1) with the observed order p = log2((u2 - u1) / (u3 - u2))
// (2D: 64x16, 128x32, 256x64), printed with the same extrapolation of the incompatible element,
// which agrees within 0.2% up to nu = 0.4999 and fails beyond (it locks mildly there, 3D).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace cg = coarsegrain;
using nlohmann::json;

namespace {

constexpr double kE = 1000.0;

struct Variant {
    std::string element;      ///< hex, tet, quad, tri
    std::string formulation;  ///< standard, incompatible, sri
};

/// The cantilever as a scene.
json cantilever(int dim, const std::string& element, const std::vector<int>& cells, double nu,
                const std::string& formulation) {
    json j = {
        {"dimension", dim},
        {"materials", {{"0", {{"E", kE}, {"nu", nu}, {"density", 1.0}}}}},
    };
    if (dim == 3) {
        j["mesh"] = {{"grid",
                      {{"min", {0, 0, 0}}, {"max", {4, 1, 1}}, {"cells", cells}, {"element", element}}}};
        j["dirichlet"] = json::array({{{"box", {{"min", {-1e-9, -1, -1}}, {"max", {1e-9, 2, 2}}}}}});
        j["loads"] = {{"gravity", {0, 0, -1}}};
        j["probes"] = json::array({{4, 0.5, 0.5}});
    } else {
        j["mesh"] = {
            {"grid", {{"min", {0, 0}}, {"max", {4, 1}}, {"cells", cells}, {"element", element}}}};
        j["dirichlet"] = json::array({{{"box", {{"min", {-1e-9, -1}}, {"max", {1e-9, 2}}}}}});
        j["loads"] = {{"gravity", {0, -1}}};
        j["probes"] = json::array({{4, 0.5}});
    }
    if (formulation == "incompatible") j["fem"] = {{"formulation", "incompatible"}};
    return j;
}

/// Selective reduced integration (isotropic, one material): the mu part of the tensor with the
/// full Gauss rule, the lambda part at the centre.
cg::SparseMatrix sri_stiffness(const cg::mesh::Mesh& m, double nu) {
    const int dim = m.dim(), n = cg::mandel_size(dim);
    const double lambda = kE * nu / ((1 + nu) * (1 - 2 * nu)), mu = kE / (2 * (1 + nu));
    cg::Matrix C_mu = cg::Matrix::Zero(n, n), C_lambda = cg::Matrix::Zero(n, n);
    C_mu.diagonal().setConstant(2 * mu);
    C_lambda.topLeftCorner(dim, dim).setConstant(lambda);
    const int npe = static_cast<int>(m.elements.cols()), ndof = dim * npe;
    std::vector<Eigen::Triplet<double, cg::Index>> entries;
    entries.reserve(static_cast<std::size_t>(m.num_elements()) * ndof * ndof);
    const double g = 0.5 / std::sqrt(3.0);
    for (cg::Index e = 0; e < m.num_elements(); ++e) {
        const cg::Matrix X = m.element_positions(e);
        cg::Matrix Ke = cg::Matrix::Zero(ndof, ndof);
        const int points = 1 << dim;
        for (int q = 0; q < points; ++q) {
            Eigen::VectorXd xi(dim);
            for (int d = 0; d < dim; ++d) xi[d] = 0.5 + ((q >> d) & 1 ? g : -g);
            double detJ = 0;
            const cg::Matrix B = cg::fem::strain_displacement(m.type, X, xi, &detJ);
            Ke += (detJ / points) * B.transpose() * C_mu * B;
        }
        double detJ = 0;
        const cg::Matrix B =
            cg::fem::strain_displacement(m.type, X, Eigen::VectorXd::Constant(dim, 0.5), &detJ);
        Ke += detJ * B.transpose() * C_lambda * B;
        for (int a = 0; a < npe; ++a)
            for (int b = 0; b < npe; ++b)
                for (int i = 0; i < dim; ++i)
                    for (int j = 0; j < dim; ++j)
                        entries.emplace_back(dim * m.elements(e, a) + i, dim * m.elements(e, b) + j,
                                             Ke(dim * a + i, dim * b + j));
    }
    cg::SparseMatrix K(m.num_dofs(), m.num_dofs());
    K.setFromTriplets(entries.begin(), entries.end());
    return K;
}

double tip_deflection(int dim, const Variant& v, const std::vector<int>& cells, double nu) {
    const cg::scene::Scene sc =
        cg::scene::parse_scene(cantilever(dim, v.element, cells, nu, v.formulation), "cantilever", "");
    cg::scene::FineModel model = cg::scene::build_fine_model(sc);
    if (v.formulation == "sri") model.K = sri_stiffness(model.mesh, nu);
    const cg::scene::StaticSolution sol = cg::scene::solve_static(model, sc.solver);
    return -cg::scene::probe_displacements(sc, model.mesh, sol.u).front()[dim - 1];
}

std::string grid_name(const std::vector<int>& c) { return fmt::format("{}", fmt::join(c, "x")); }

void table(int dim) {
    const std::vector<double> nus = {0.3, 0.45, 0.49, 0.499, 0.4999, 0.49999};
    std::vector<std::vector<int>> grids, reference_grids;
    std::vector<Variant> variants;
    if (dim == 3) {
        grids = {{16, 1, 1}, {8, 2, 2}, {16, 4, 4}, {32, 8, 8}, {64, 16, 16}};
        reference_grids = {{16, 4, 4}, {32, 8, 8}, {64, 16, 16}};
        variants = {{"hex", "standard"}, {"hex", "sri"}, {"hex", "incompatible"}, {"tet", "standard"}};
    } else {
        grids = {{16, 1}, {8, 2}, {16, 4}, {32, 8}, {64, 16}};
        reference_grids = {{64, 16}, {128, 32}, {256, 64}};
        variants = {{"quad", "standard"}, {"quad", "sri"}, {"quad", "incompatible"}, {"tri", "standard"}};
    }
    // Converged answers: Richardson extrapolation of the SRI element, which does not lock
    // once there are two elements through the depth and shares nothing with the incompatible
    // modes; the incompatible element's extrapolation is printed beside it as a cross-check.
    std::map<double, double> converged;
    std::map<std::pair<std::string, double>, std::vector<double>> results;
    fmt::print("\n{}D cantilever 4 x 1{}, E = {}, tip deflection; converged answer by Richardson "
               "extrapolation of the SRI element on {}, {}, {} (incompatible element beside it):\n",
               dim, dim == 3 ? " x 1" : " (plane strain)", kE, grid_name(reference_grids[0]),
               grid_name(reference_grids[1]), grid_name(reference_grids[2]));
    const auto extrapolate = [&](const std::string& formulation, double nu, double* order) {
        std::vector<double> u;
        for (const auto& g : reference_grids)
            u.push_back(tip_deflection(dim, {dim == 3 ? "hex" : "quad", formulation}, g, nu));
        *order = std::log2((u[1] - u[0]) / (u[2] - u[1]));
        const double p = std::isfinite(*order) && *order > 0.5 ? *order : 2.0;
        return u[2] + (u[2] - u[1]) / (std::pow(2.0, p) - 1);
    };
    for (const double nu : nus) {
        double p = 0, q = 0;
        converged[nu] = extrapolate("sri", nu, &p);
        const double incompatible = extrapolate("incompatible", nu, &q);
        fmt::print("  nu = {:<7} {:.6f} (order {:.2f}); incompatible {:.6f} (order {:.2f}, {:+.2f}%)\n",
                   nu, converged[nu], p, incompatible, q, 100 * (incompatible / converged[nu] - 1));
    }
    fmt::print("\n| element | formulation | nu |");
    for (const auto& g : grids) fmt::print(" {} |", grid_name(g));
    fmt::print("\n|---|---|---|");
    for (std::size_t i = 0; i < grids.size(); ++i) fmt::print("---|");
    fmt::print("\n");
    for (const Variant& v : variants)
        for (const double nu : nus) {
            fmt::print("| {} | {} | {} |", v.element, v.formulation, nu);
            for (const auto& g : grids) {
                const double u = tip_deflection(dim, v, g, nu);
                results[{v.element + " " + v.formulation, nu}].push_back(u);
                fmt::print(" {:.4f} ({:+.1f}%) |", u, 100 * (u / converged[nu] - 1));
            }
            fmt::print("\n");
            std::fflush(stdout);
        }
    fmt::print("\n(deflection, and in brackets its error against the converged answer)\n");
}

}  // namespace

int main(int argc, char** argv) {
    const bool only2d = argc > 1 && std::strcmp(argv[1], "--2d") == 0;
    if (argc > 1 && !only2d) {
        fmt::print(stderr, "usage: bench_locking [--2d]\n");
        return 2;
    }
    table(2);
    if (!only2d) table(3);
    return 0;
}
