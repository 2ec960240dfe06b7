// The mra coarsening method's entry point: scene options and the CoarseModel it returns.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <variant>
#include <vector>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mra/coarse_model.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "test_util.hpp"

namespace coarsegrain::mra {
namespace {

using json = nlohmann::json;

/// A 2D 8x8 layered square clamped at y = 1 under gravity.
json scene_json() {
    return json::parse(R"({
      "dimension": 2,
      "mesh": { "grid": { "min": [0, 0], "max": [1, 1], "cells": [8, 8], "element": "quad" } },
      "material_field": { "layers": { "axis": "x", "thickness": 0.25, "ids": [1, 2] } },
      "materials": { "1": { "E": 1000, "nu": 0.3, "density": 1 },
                     "2": { "E": 10, "nu": 0.45, "density": 2 } },
      "dirichlet": [ { "box": { "min": [-1, 0.999], "max": [2, 2] } } ],
      "loads": { "gravity": [0, -1] },
      "coarse": { "levels": 3, "refinement": "linear", "radius": "inf" }
    })");
}

TEST(MraCoarseModel, CoarsestLevelAsCoarseModel) {
    for (const char* refinement : {"linear", "dirac"}) {
        json j = scene_json();
        j["coarse"]["refinement"] = refinement;
        const scene::Scene s = scene::parse_scene(j, "test.json", "");
        const scene::FineModel fine = scene::build_fine_model(s);
        const coarsen::CoarseModel m = coarsen::build_coarse_model(s, fine, "mra");
        EXPECT_EQ(m.method, "mra");
        EXPECT_EQ(m.nodes, 9);  // 2x2 cells
        EXPECT_EQ(m.elements, 4);
        ASSERT_EQ(m.K.rows(), 18);
        ASSERT_EQ(m.to_fine.rows(), fine.mesh.num_dofs());
        ASSERT_EQ(m.to_fine.cols(), 18);
        // Dirac: the three top coarse nodes sit on the clamped edge and have no basis function
        // (constrain = eliminate for Dirac); linear keeps them.
        EXPECT_EQ(m.bc.dofs.size(), std::string(refinement) == "dirac" ? 6u : 0u);
        const auto& report = std::get<mra::HierarchyReport>(m.report);
        EXPECT_EQ(report.levels.size(), 2u);
        EXPECT_EQ(report.options.dirichlet, mra::DirichletTreatment::Constrain);
        EXPECT_FALSE(report.options.patch_clip);
        // The build phases are reported per level (their durations are not checked).
        std::vector<std::string> phases;
        for (const auto& entry : m.timings.entries()) phases.push_back(entry.first);
        for (const char* phase : {"level 1: A", "level 2: A"})
            EXPECT_NE(std::find(phases.begin(), phases.end(), phase), phases.end()) << phase;

        // Solving the model as the runtime does (conditions eliminated) gives the hierarchy's
        // single-level solve of level 1.
        const fem::ReducedSystem sys = fem::reduce(m.K, m.f, m.bc);
        solve::SpdSolver solver;
        solver.compute(sys.K);
        const Vector u = m.to_fine * fem::expand(sys, solver.solve(sys.rhs), m.bc, 18);
        const Hierarchy h = build_hierarchy(fine.mesh, fine.K, fine.bc.dofs,
                                            scene::parse_coarse_options(j["coarse"], "t").mra);
        MultilevelSolver ms(h);
        const Vector expected = ms.solve_level(fine.f, 1);
        // Two solves of the same 18-DOF system: round-off, 1e-12.
        EXPECT_LT((u - expected).norm(), 1e-12 * expected.norm()) << refinement;

        // Coarse DOFs are displacements: a unit x translation of the coarse nodes maps to what
        // the hierarchy's basis makes of the fine translation's measurements, Φ^{1,T} C...C t.
        Vector t_fine = Vector::Zero(h.fine_dofs.size());
        for (Index a = 0; a < t_fine.size(); ++a) t_fine[a] = h.fine_dofs[a] % 2 == 0 ? 1.0 : 0.0;
        Vector measured = t_fine;
        for (int k = h.num_levels() - 1; k >= 1; --k) measured = h.level(k).C * measured;
        Vector t_coarse = Vector::Zero(18);
        for (Index a = 0; a < h.level(1).dofs.size(); ++a)
            t_coarse[h.level(1).dofs[a]] = h.level(1).dofs[a] % 2 == 0 ? 1.0 : 0.0;
        const Vector via_model = m.to_fine * t_coarse;
        const Vector via_basis = reconstruct(h, measured, 1);
        // Division and multiplication by the same power-of-two sums: 1e-14.
        EXPECT_LT((via_model - via_basis).cwiseAbs().maxCoeff(), 1e-14) << refinement;
    }
}

// The coarse model's Galerkin mass of the fine stiffness is its stiffness: both are P Φ^1 K Φ^{1,T}
// P^T, the one by the products of the build (A^k = C̃^k A^{k+1} C̃^{k,T}), the other by
// galerkin_operator's, in another storage and order: round-off, 1e-12 relative. Global solves
// and 2 rings (relaxed, cell-wise), both refinements (Dirac drops the clamped coarse DOFs, whose
// rows and columns stay empty).
TEST(MraCoarseModel, GalerkinMassOfTheStiffnessIsTheStiffness) {
    for (const char* refinement : {"linear", "dirac"})
        for (const json& radius : {json("inf"), json(2)}) {
            if (radius != json("inf") && std::string(refinement) == "dirac") continue;  // global
            json j = scene_json();
            j["coarse"]["refinement"] = refinement;
            j["coarse"]["radius"] = radius;
            const scene::Scene s = scene::parse_scene(j, "test.json", "");
            const scene::FineModel fine = scene::build_fine_model(s);
            const coarsen::CoarseModel m = coarsen::build_coarse_model(s, fine, "mra");
            const Matrix K(m.K), KM(m.mass(fine.K));
            ASSERT_GT(K.norm(), 0.0);
            EXPECT_LT((KM - K).norm(), 1e-12 * K.norm()) << refinement << " " << radius;
            EXPECT_EQ(Matrix(K - K.transpose()).norm(), 0.0);
        }
}

// The comparison with the fine solution takes the fine solve's factorization of K_ff for the
// fine level's spectrum instead of factorizing the same operator again: given a solution whose
// factorization is that of 2 K_ff, the fine level's lambda_min doubles. The runtime keeps the
// factorization when an mra method will use it (coarsen::uses_fine_factorization).
TEST(MraCoarseModel, ComparisonUsesTheFineSolvesFactorization) {
    const scene::Scene s = scene::parse_scene(scene_json(), "test.json", "");
    const scene::FineModel fine = scene::build_fine_model(s);
    EXPECT_FALSE(scene::solve_static(fine, s.solver).factorization);
    const scene::StaticSolution kept = scene::solve_static(fine, s.solver, nullptr, true);
    ASSERT_TRUE(kept.factorization);
    scene::StaticSolution twice = kept;
    auto solver = std::make_shared<solve::SpdSolver>();
    solver->compute(SparseMatrix(2.0 * fem::reduce(fine.K, fine.f, fine.bc).K));
    twice.factorization = solver;
    const coarsen::CoarseModel m = coarsen::build_coarse_model(s, fine, "mra");
    const auto fine_level = [&](const scene::StaticSolution& u) {
        const coarsen::FineComparison c = m.compare_with_fine(s, fine, u);
        return std::get<ComparisonReport>(c.report).levels.back();
    };
    const LevelDiagnostics a = fine_level(kept), b = fine_level(twice);
    ASSERT_FALSE(a.spectrum_skipped) << a.spectrum_note;
    // Lanczos converges to 1e-12 relative on both; 1e-10.
    EXPECT_NEAR(b.lambda_min_A, 2 * a.lambda_min_A, 1e-10 * a.lambda_min_A);
    EXPECT_NEAR(b.lambda_max_A, a.lambda_max_A, 1e-10 * a.lambda_max_A);
}

// The fine factorization is kept for an mra method that computes the fine spectrum of K_ff with
// a direct solver, and only then.
TEST(MraCoarseModel, UsesFineFactorization) {
    const auto uses = [](const json& j, const std::vector<std::string>& methods) {
        const scene::Scene s = scene::parse_scene(j, "test.json", "");
        return coarsen::uses_fine_factorization(s, scene::build_fine_model(s), methods);
    };
    json j = scene_json();
    EXPECT_TRUE(uses(j, {"effective-tensor", "mra"}));
    EXPECT_TRUE(uses(j, {"mra-dirac"}));
    EXPECT_FALSE(uses(j, {"effective-tensor", "naive"}));
    j["coarse"]["spectrum_max_dofs"] = 10;  // the fine spectrum is skipped
    EXPECT_FALSE(uses(j, {"mra"}));
    j["coarse"].erase("spectrum_max_dofs");
    j["coarse"]["dirichlet"] = "penalty";  // its own fine operator; not so the blind variants
    EXPECT_FALSE(uses(j, {"mra", "mra-linear"}));
    EXPECT_TRUE(uses(j, {"mra", "mra-linear-blind"}));
    j["coarse"].erase("dirichlet");
    j["solver"] = {{"backend", "cg"}};  // no factorization
    EXPECT_FALSE(uses(j, {"mra"}));
}

TEST(MraCoarseModel, OptionsDefaultsAndValues) {
    const Options d = scene::parse_coarse_options(json(), "t").mra;
    EXPECT_EQ(d.levels, 3);
    EXPECT_EQ(d.refinement, Refinement::Linear);
    EXPECT_TRUE(d.radius.empty());  // automatic_construction
    EXPECT_EQ(d.radius_grid, RadiusGrid::Fine);
    EXPECT_EQ(d.localization, Localization::Node);
    EXPECT_EQ(d.measurement, Measurement::Canonical);
    EXPECT_EQ(d.patch, 1);
    EXPECT_FALSE(d.patch_clip);
    EXPECT_EQ(d.truncation, 1e-7);
    EXPECT_TRUE(d.invariance);
    EXPECT_EQ(d.dirichlet, DirichletTreatment::Constrain);
    EXPECT_EQ(d.defect_tolerance, 0.0);
    EXPECT_EQ(d.max_radius, 16.0);
    EXPECT_EQ(d.relaxation, 0.0);
    const Options o =
        scene::parse_coarse_options(
            json::parse(R"({"levels": 4, "refinement": "dirac", "radius": [2, "inf", 3.5],
                        "radius_grid": "coarse", "defect_tolerance": 1e-3, "max_radius": 12, "localization": "node", "measurement": "stiffness", "patch": 2, "patch_clip": true, "truncation": 1e-5,
                        "invariance": false, "dirichlet": "diagonal_penalty", "mesh": {"file": "ignored.msh"}})"),
            "t")
            .mra;
    EXPECT_EQ(o.levels, 4);
    EXPECT_EQ(o.refinement, Refinement::Dirac);
    ASSERT_EQ(o.radius.size(), 3u);
    EXPECT_EQ(o.radius[0], 2.0);
    EXPECT_TRUE(std::isinf(o.radius[1]));
    EXPECT_EQ(o.radius[2], 3.5);
    EXPECT_EQ(o.radius_grid, RadiusGrid::Coarse);
    EXPECT_EQ(o.defect_tolerance, 1e-3);
    EXPECT_EQ(o.max_radius, 12.0);
    EXPECT_EQ(o.localization, Localization::Node);  // cell does not take patch_clip
    EXPECT_EQ(o.measurement, Measurement::Stiffness);
    EXPECT_EQ(o.patch, 2);
    EXPECT_TRUE(o.patch_clip);
    EXPECT_EQ(o.truncation, 1e-5);
    EXPECT_FALSE(o.invariance);
    EXPECT_EQ(o.dirichlet, DirichletTreatment::DiagonalPenalty);
    EXPECT_EQ(scene::parse_coarse_options(json::parse(R"({"localization": "cell"})"), "t")
                  .mra.localization,
              Localization::Cell);
    const Options relaxed =
        scene::parse_coarse_options(
            json::parse(R"({"radius": 4, "localization": "cell", "relaxation": 3})"), "t")
            .mra;
    EXPECT_EQ(relaxed.relaxation, 3.0);
    // With relaxation an infinite radius is the relaxed step on the whole level.
    const Options spanning =
        scene::parse_coarse_options(
            json::parse(
                R"({"levels": 3, "radius": ["inf", 4], "localization": "cell", "relaxation": 3})"),
            "t")
            .mra;
    EXPECT_TRUE(std::isinf(spanning.radius.at(0)));
    EXPECT_EQ(spanning.relaxation, 3.0);
}

TEST(MraCoarseModel, BadOptionsNameTheirKey) {
    const struct {
        const char* coarse;
        const char* message;
    } cases[] = {
        {R"({"levels": 1})", "test.json: coarse.levels: expected an integer in [2, 17], got 1"},
        {R"({"levels": 4294967298})", "coarse.levels: expected an integer in [2, 17]"},
        {R"({"levels": 33})", "coarse.levels: expected an integer in [2, 17], got 33"},
        {R"({"levels": 2.5})", "coarse.levels: expected an integer"},
        {R"({"refinement": "cubic"})",
         "coarse.refinement: unknown value \"cubic\"; expected one of \"dirac\", \"linear\""},
        {R"({"radius": 0.5})", "coarse.radius: expected a number >= 1 or \"inf\""},
        {R"({"radius": "infinite"})", "coarse.radius: expected a number >= 1 or \"inf\""},
        {R"({"levels": 3, "radius": [2, 3, 4]})", "coarse.radius: expected levels - 1 = 2"},
        {R"({"radius": [2, "x"]})", "coarse.radius[1]"},
        {R"({"radius_grid": "medium"})", "coarse.radius_grid"},
        {R"({"localization": "patch"})",
         "coarse.localization: unknown value \"patch\"; expected one of \"node\", \"cell\""},
        {R"({"measurement": "mass"})", "coarse.measurement: unknown value \"mass\""},
        {R"({"patch": 0})", "coarse.patch: expected an integer in [1, 65536], got 0"},
        {R"({"patch_clip": 1})", "coarse.patch_clip: expected true or false, got 1"},
        {R"({"defect_tolerance": -1e-3})",
         "coarse.defect_tolerance: expected a number >= 0 (0: fixed radius), got -0.001"},
        {R"({"max_radius": 0.5})", "coarse.max_radius: expected a number >= 1, got 0.5"},
        {R"({"relaxation": -1})",
         "coarse.relaxation: expected a number >= 0 (0: exact measurements), got -1"},
        {R"({"radius": 4, "relaxation": 3})", "coarse: mra: relaxation needs cell localization"},
        {R"({"relaxation": 3})", "coarse: mra: relaxation needs cell localization"},
        {R"({"levels": 3, "radius": ["inf", 4], "localization": "cell", "relaxation": 3,
             "refinement": "dirac"})",
         "coarse: mra: relaxation with a finite radius needs the linear refinement"},
        {R"({"truncation": 1})", "coarse.truncation: expected a number in [0, 1)"},
        {R"({"invariance": "yes"})", "coarse.invariance: expected true or false"},
        {R"({"dirichlet": "clamp"})", "coarse.dirichlet: unknown value \"clamp\""},
        {R"({"spectrum_max_dofs": -1})", "coarse.spectrum_max_dofs: expected an integer in [0, "},
        {R"({"cell_tensors": 1})", "coarse.cell_tensors: expected true or false"},
        {R"({"radius": 2, "localization": "cell", "patch": 2, "patch_clip": true})",
         "coarse: mra: cell localization does not clip patches"},
        {R"({"radius": 2, "localization": "cell", "dirichlet": "penalty"})",
         "coarse: mra: cell localization needs the eliminate, constrain or ignore"},
    };
    // Every value is checked when the scene is parsed, before a mesh is built.
    for (const auto& c : cases) {
        json j = scene_json();
        j["coarse"] = json::parse(c.coarse);
        j["mesh"] = {{"file", "does-not-exist.msh"}};
        test::expect_error([&] { scene::parse_scene(j, "test.json", ""); }, c.message);
    }
    // What depends on the mesh is checked before any assembly.
    json j = scene_json();
    j["coarse"]["levels"] = 4;
    j["mesh"]["grid"]["cells"] = {8, 12};
    const scene::Scene s = scene::parse_scene(j, "test.json", "");
    test::expect_error([&] { coarsen::validate_method(s, "mra-linear"); },
                       "test.json: coarse.levels: mra: 4 levels need cells per axis divisible by "
                       "2^3 = 8, but axis 1 has 12 cells");
}

TEST(MraCoarseModel, UnsupportedInputIsReported) {
    json j = scene_json();
    j["dirichlet"][0]["value"] = {0.0, 0.1};
    const scene::Scene s = scene::parse_scene(j, "test.json", "");
    test::expect_error([&] { coarsen::validate_method(s, "mra-dirac"); },
                       "test.json: dirichlet[0].value: the mra-dirac method supports only zero "
                       "prescribed displacements, got [0, 0.1]");
    j = scene_json();
    const scene::Scene s2 = scene::parse_scene(j, "test.json", "");
    scene::Scene s3 = s2;
    s3.mesh.grid.reset();  // a quad mesh that is no grid: no automatic level meshes
    test::expect_error([&] { coarsen::validate_method(s3, "mra"); }, "needs a regular grid");
}

}  // namespace
}  // namespace coarsegrain::mra
