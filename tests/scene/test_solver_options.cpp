// The scene's "solver" block: the mra-pcg backend's keys, its checks before any work, and the
// fine solves it makes for coarsen (coarse models keep a direct solver).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "coarsegrain/coarsen/fine_run.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

using nlohmann::json;

/// A 16 x 8 plate of two materials at contrast 1e4 (a checkerboard of 4 x 4 cells), hung from
/// its left edge, under gravity.
json checker_plate() {
    return json::parse(R"({
      "mesh": { "grid": { "min": [0, 0], "max": [2, 1], "cells": [16, 8], "element": "quad" } },
      "material_field": { "checkerboard": { "size": 0.5, "ids": [1, 2] } },
      "materials": { "1": { "E": 1e4, "nu": 0.3, "density": 1 },
                     "2": { "E": 1, "nu": 0.3, "density": 1 } },
      "dirichlet": [ { "box": { "min": [-1, -1], "max": [0, 2] } } ],
      "loads": { "gravity": [0, -1] }
    })");
}

scene::Scene parse(const json& j) { return scene::parse_scene(j, "plate.json", ""); }

TEST(SolverOptions, MraPcgKeysAndDefaults) {
    json j = checker_plate();
    j["solver"] = {{"backend", "mra-pcg"}};
    scene::Scene sc = parse(j);
    EXPECT_EQ(sc.solver.backend, solve::Backend::MraPcg);
    EXPECT_EQ(sc.solver.cg_tolerance, 1e-8);
    EXPECT_EQ(sc.preconditioner.levels, 0);
    EXPECT_TRUE(sc.preconditioner.deflation);
    EXPECT_EQ(sc.preconditioner.deflation_rings, 2);
    j["solver"] = {{"backend", "mra-pcg"}, {"tolerance", 1e-10}, {"max_iterations", 50},
                   {"time_limit", 60},     {"levels", 3},        {"radius", 2},
                   {"smoother_degree", 4}, {"deflation", false}, {"deflation_rings", 5}};
    sc = parse(j);
    EXPECT_EQ(sc.solver.cg_tolerance, 1e-10);
    EXPECT_EQ(sc.solver.cg_max_iterations, 50);
    EXPECT_EQ(sc.solver.time_limit, 60);
    EXPECT_EQ(sc.preconditioner.levels, 3);
    EXPECT_EQ(sc.preconditioner.radius, 2);
    EXPECT_EQ(sc.preconditioner.smoother_degree, 4);
    EXPECT_FALSE(sc.preconditioner.deflation);
    EXPECT_EQ(sc.preconditioner.deflation_rings, 5);
    // cholmod keeps its options; a direct solver serves everything but the fine model
    EXPECT_EQ(scene::direct_solver(sc).backend, solve::Backend::Cholmod);
    EXPECT_EQ(parse(checker_plate()).solver.cg_tolerance, solve::SolverOptions{}.cg_tolerance);
}

TEST(SolverOptions, MraPcgIsCheckedBeforeAnyWork) {
    const auto expect = [](const std::function<void(json&)>& edit, const std::string& message) {
        json j = checker_plate();
        j["solver"] = {{"backend", "mra-pcg"}};
        edit(j);
        test::expect_error([&] { parse(j); }, message);
    };
    expect([](json& j) { j["mesh"]["grid"]["cells"] = {15, 8}; }, "solver.backend");
    expect([](json& j) { j["mesh"]["grid"]["cells"] = {15, 8}; }, "must be even");
    expect([](json& j) { j["solver"]["levels"] = 5; }, "solver.levels");  // 8 / 16
    expect([](json& j) { j["solver"]["levels"] = 1; }, "solver.levels");
    expect([](json& j) { j["solver"]["radius"] = 0.5; }, "solver.radius");
    expect([](json& j) { j["solver"]["tolerance"] = 2; }, "solver.tolerance");
    expect([](json& j) { j["solver"]["smoother_degree"] = 0; }, "solver.smoother_degree");
    expect([](json& j) { j["solver"]["deflation"] = 1; }, "solver.deflation");
    expect([](json& j) { j["solver"]["deflation_rings"] = 17; }, "solver.deflation_rings");
    expect([](json& j) { j["solver"]["deflation_rings"] = -1; }, "solver.deflation_rings");
    expect([](json& j) { j["kinematics"] = "corotational"; }, "corotated kinematics");
    expect(
        [](json& j) {
            j["solver"] = {{"backend", "cholmod"}, {"levels", 3}};
        },
        "mra-pcg backend only");
    expect(
        [](json& j) {
            j["solver"] = {{"backend", "cholmod"}, {"max_iterations", 10}};
        },
        "iterative backends");
}

// The fine solve by mra-pcg at a 1e-10 residual equals CHOLMOD's to 1e-8 (the error is at most
// cond(K_ff) times the residual; measured 1e-11), and the coarse models are solved directly,
// so every error of a method agrees with the CHOLMOD run to the fine solutions' difference.
TEST(SolverOptions, MraPcgFineSolveMatchesCholmodThroughCoarsen) {
    json j = checker_plate();
    j["coarse"] = {
        {"mesh",
         {{"grid", {{"min", {0, 0}}, {"max", {2, 1}}, {"cells", {4, 2}}, {"element", "quad"}}}}}};
    const scene::Scene direct = parse(j);
    j["solver"] = {{"backend", "mra-pcg"}, {"tolerance", 1e-10}};
    const scene::Scene iterative = parse(j);
    coarsen::FineRun a = coarsen::solve_fine(direct, scene::build_fine_model(direct), {"naive"});
    coarsen::FineRun b =
        coarsen::solve_fine(iterative, scene::build_fine_model(iterative), {"naive"});
    EXPECT_LE((a.solution.u - b.solution.u).norm(), 1e-8 * a.solution.u.norm());
    const coarsen::MethodRun ra = coarsen::run_method(direct, a, "effective-tensor");
    const coarsen::MethodRun rb = coarsen::run_method(iterative, b, "effective-tensor");
    EXPECT_NEAR(rb.errors.l2_rel, ra.errors.l2_rel, 1e-6 * ra.errors.l2_rel);
    EXPECT_NEAR(rb.errors.energy_rel, ra.errors.energy_rel, 1e-6 * ra.errors.energy_rel);
}

TEST(SolverOptions, MraPcgReportsTheIterationLimit) {
    json j = checker_plate();
    j["solver"] = {{"backend", "mra-pcg"}, {"max_iterations", 2}};
    const scene::Scene sc = parse(j);
    const scene::FineModel model = scene::build_fine_model(sc);
    try {
        scene::solve_static(model, scene::fine_solver(sc, model));
        ADD_FAILURE() << "expected NotConverged";
    } catch (const solve::NotConverged& e) {
        EXPECT_THAT(e.what(), ::testing::HasSubstr("no convergence in 2 iterations"));
        EXPECT_THAT(e.what(), ::testing::HasSubstr("solver.max_iterations"));
    }
    // Without its preconditioner (the options of another model) the backend refuses to run.
    test::expect_error([&] { scene::solve_static(model, sc.solver); }, "no preconditioner");
}

}  // namespace
}  // namespace coarsegrain
