#include "method_json.hpp"

#include <cmath>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::app {

namespace {

/// A radius, or "inf" for an infinite one (global solves).
nlohmann::json radius_json(double r) {
    return std::isinf(r) ? nlohmann::json("inf") : nlohmann::json(r);
}

nlohmann::json report_json(const homogenize::Report& r) {
    nlohmann::json j = {
        {"fine_simplices", r.fine_simplices},
        {"coarse_simplices", r.coarse_simplices},
        {"overlaps", r.overlaps},
        {"coarse_nodes_outside", r.coarse_nodes_outside},
        {"coarse_nodes_max_outside_distance", r.coarse_nodes_max_outside_distance},
        {"mass", {{"fine", r.fine_mass}, {"coarse", r.coarse_mass}}},
        {"map", r.harmonic_map ? "harmonic" : "barycentric"},
        {"conditions",
         {{"fixed_dofs", r.fixed_dofs},
          {"constrained_dofs", r.constrained_dofs},
          {"combinations", r.combinations}}},
    };
    if (const auto& e = r.effective_tensor) {
        j["normals"] = e->coarse_normals ? "coarse" : "fine";
        j["boundary"] = e->mixed_boundary ? "mixed" : "neumann";
        j["mollifier_condition"] = {{"min", e->mollifier_condition_min},
                                    {"max", e->mollifier_condition_max}};
        if (e->mixed_boundary) j["fallback_elements"] = e->fallback_elements;
    }
    return j;
}

nlohmann::json options_json(const mra::Options& o) {
    nlohmann::json radius = nlohmann::json::array();
    for (const double r : o.radius) radius.push_back(radius_json(r));
    return {{"levels", o.levels},
            {"refinement", mra::refinement_name(o.refinement)},
            {"radius", radius},
            {"radius_grid", mra::radius_grid_name(o.radius_grid)},
            {"truncation", o.truncation},
            {"invariance", o.invariance},
            {"dirichlet", mra::dirichlet_name(o.dirichlet)},
            {"patch", o.patch},
            {"patch_clip", o.patch_clip},
            {"localization", mra::localization_name(o.localization)},
            {"measurement", mra::measurement_name(o.measurement)},
            {"operator", mra::operator_name(o.fine_operator)},
            {"defect_tolerance", o.defect_tolerance},
            {"max_radius", o.max_radius},
            {"relaxation", o.relaxation}};
}

nlohmann::json level_build_json(const mra::LevelReport& L) {
    nlohmann::json j = {{"level", L.level},
                        {"cells", L.cells},
                        {"nodes", L.nodes},
                        {"elements", L.elements},
                        {"dofs", L.dofs},
                        {"wavelets", L.wavelets},
                        {"radius", radius_json(L.radius)},
                        {"build_seconds", L.build_seconds},
                        {"C_nnz", L.C_nnz},
                        {"C_density", L.C_density},
                        {"A_nnz", L.A_nnz},
                        {"A_density", L.A_density},
                        {"B_nnz", L.B_nnz},
                        {"B_density", L.B_density}};
    if (!L.mesh_file.empty()) j["mesh"] = L.mesh_file;
    if (L.region_rings_mean) j["region_rings_mean"] = *L.region_rings_mean;
    if (L.region_rings_max) j["region_rings_max"] = *L.region_rings_max;
    return j;
}

nlohmann::json report_json(const mra::HierarchyReport& r) {
    nlohmann::json levels = nlohmann::json::array();
    for (const mra::LevelReport& L : r.levels) levels.push_back(level_build_json(L));
    return {{"options", options_json(r.options)}, {"levels", levels}, {"fine_dofs", r.fine_dofs}};
}

nlohmann::json coarsest_cells_json(const mra::CoarsestCellsReport& r) {
    if (!r.skipped.empty()) return {{"cells", r.cells}, {"skipped", r.skipped}};
    nlohmann::json per_cell = nlohmann::json::array();
    for (const mra::CellYoungs& c : r.per_cell)
        per_cell.push_back({{"E_axes", c.E_axes}, {"E_min", c.E_min}, {"E_max", c.E_max}});
    return {{"cells", r.cells},
            {"vtu", r.vtu},
            {"E_min", r.E_min},
            {"E_max", r.E_max},
            {"per_cell", per_cell}};
}

/// The fields of one level's diagnostics (the CSV columns plus solve_note and spectrum_note; NaN
/// is null).
nlohmann::json level_json(const mra::LevelDiagnostics& L) {
    const auto number = [](double v) {
        return std::isnan(v) ? nlohmann::json() : nlohmann::json(v);
    };
    return {{"level", L.k},
            {"dofs", L.dofs},
            {"wavelets", L.wavelets},
            {"error_over_g", number(L.error_over_g)},
            {"error_over_u", number(L.error_over_u)},
            {"solve_note", L.solve_note},
            {"lambda_min_A", number(L.lambda_min_A)},
            {"lambda_max_A", number(L.lambda_max_A)},
            {"cond_A", number(L.cond_A)},
            {"lambda_min_B", number(L.lambda_min_B)},
            {"lambda_max_B", number(L.lambda_max_B)},
            {"cond_B", number(L.cond_B)},
            {"sparsity_A", number(L.sparsity_A)},
            {"sparsity_B", number(L.sparsity_B)},
            {"sparsity_C", number(L.sparsity_C)},
            {"bytes_Phi", L.bytes_Phi},
            {"bytes_Psi", L.bytes_Psi},
            {"bytes_C", L.bytes_C},
            {"bytes_A", L.bytes_A},
            {"bytes_B", L.bytes_B},
            {"build_seconds", L.build_seconds},
            {"spectrum_skipped", L.spectrum_skipped},
            {"spectrum_note", L.spectrum_note}};
}

/// "levels" of the hierarchy's comparison: level k < q is its build figures, level q the fine
/// level's (which has no refinement and no wavelets), each updated with its diagnostics.
nlohmann::json levels_json(const mra::HierarchyReport& build, const mra::ComparisonReport& c) {
    const std::size_t q = c.levels.size();
    CG_VERIFY(q == build.levels.size() + 1, "mra report: {} diagnosed levels for {} built", q,
              build.levels.size() + 1);
    nlohmann::json levels = nlohmann::json::array();
    for (std::size_t i = 0; i < q; ++i) {
        const mra::FineLevelReport& f = build.fine_level;
        nlohmann::json entry =
            i + 1 < q
                ? level_build_json(build.levels[i])
                : nlohmann::json{{"level", f.level}, {"cells", f.cells},    {"nodes", f.nodes},
                                 {"A_nnz", f.A_nnz}, {"C_nnz", nullptr},    {"C_density", nullptr},
                                 {"B_nnz", nullptr}, {"B_density", nullptr}};
        entry.update(level_json(c.levels[i]));
        levels.push_back(entry);
    }
    return levels;
}

}  // namespace

nlohmann::json method_json(const coarsen::MethodReport& report) {
    if (const auto* r = std::get_if<homogenize::Report>(&report)) return report_json(*r);
    if (const auto* r = std::get_if<mra::HierarchyReport>(&report)) return report_json(*r);
    return nlohmann::json::object();
}

void add_comparison_json(nlohmann::json& coarse, const coarsen::MethodReport& method,
                         const coarsen::ComparisonReport& comparison) {
    const auto* c = std::get_if<mra::ComparisonReport>(&comparison);
    if (!c) return;
    const auto* build = std::get_if<mra::HierarchyReport>(&method);
    CG_VERIFY(build, "mra report: a comparison of levels without the hierarchy's build figures");
    coarse["levels"] = levels_json(*build, *c);
    coarse["spectrum_max_dofs"] = c->spectrum_max_dofs;
    coarse["coarsest_cells"] = coarsest_cells_json(c->coarsest_cells);
}

}  // namespace coarsegrain::app
