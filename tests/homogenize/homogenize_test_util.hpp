#pragma once
/// @file Helpers shared by the homogenize tests: scenes on box grids, coarse solves through the
/// CoarseModel interface (as the CLI's runtime does) and fine-vs-coarse comparisons.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::test {

/// {"grid": {...}} JSON for a box grid.
inline nlohmann::json grid(const std::vector<double>& min, const std::vector<double>& max,
                           const std::vector<int>& cells, const std::string& element) {
    return {{"grid", {{"min", min}, {"max", max}, {"cells", cells}, {"element", element}}}};
}

/// {"E", "nu", "density"} JSON of an isotropic material.
inline nlohmann::json iso(double E, double nu, double density = 1.0) {
    return {{"E", E}, {"nu", nu}, {"density", density}};
}

/// A dirichlet/traction box entry.
inline nlohmann::json box(const std::vector<double>& min, const std::vector<double>& max,
                          const std::vector<double>& value = {}) {
    nlohmann::json j = {{"box", {{"min", min}, {"max", max}}}};
    if (!value.empty()) j["value"] = value;
    return j;
}

/// A parsed scene and its fine model.
struct Setup {
    scene::Scene scene;
    scene::FineModel fine;
};

inline Setup setup(const nlohmann::json& j) {
    Setup s;
    s.scene = scene::parse_scene(j, "test.json", "");
    s.fine = scene::build_fine_model(s.scene);
    return s;
}

/// Solves a coarse model: K_c u = f with its Dirichlet conditions eliminated (CHOLMOD).
inline Vector solve_coarse(const coarsen::CoarseModel& m) {
    const fem::ReducedSystem sys = fem::reduce(m.K, m.f, m.bc);
    solve::SpdSolver solver;
    solver.compute(sys.K);
    return fem::expand(sys, solver.solve(sys.rhs), m.bc, static_cast<Index>(m.K.rows()));
}

/// The error figures of docs/guide.md (summary.json's `errors`) of a coarse solution carried to
/// the fine nodes.
struct Comparison {
    double l2_rel = 0;             ///< |u_c - u|_2 / |u|_2 over the fine nodes
    double compliance_ratio = 0;   ///< f·u_c / f·u with the fine load f
    double coarse_compliance = 0;  ///< f_c·K_c^{-1} f_c, the coarse model's own compliance
};

inline Comparison compare(const scene::FineModel& fine, const Vector& u_fine,
                          const coarsen::CoarseModel& m) {
    const Vector u_coarse = solve_coarse(m);
    const Vector u_c = m.to_fine * u_coarse;
    return {(u_c - u_fine).norm() / u_fine.norm(), fine.f.dot(u_c) / fine.f.dot(u_fine),
            m.f.dot(u_coarse)};
}

}  // namespace coarsegrain::test
