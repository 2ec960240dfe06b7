// End-to-end tests of "kinematics": "corotational" in `coarsegrain solve`, `coarsen` and
// `simulate`: the summary keys, the Newton report, element models solved corotated and the
// hierarchy linear (and warped), and the scene errors.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/cli_test_util.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;
using ::testing::HasSubstr;

namespace {

// The small bar bent far (twice the contract scene's gravity, no traction: the corotated tip
// sags by 1.58, 79% of the length; linear elasticity says 1.97), with a 2x1x1 coarse tet mesh
// and a 2-level hierarchy, corotated.
json corotated_scene() {
    json j = small_scene();
    j["loads"]["gravity"] = {0, 0, -2};
    j["loads"].erase("traction");
    j["kinematics"] = "corotational";
    j["coarse"] = json::parse(R"({
      "mesh": { "grid": { "min": [0,0,0], "max": [2,1,1], "cells": [2,1,1], "element": "tet" } },
      "levels": 2 })");
    return j;
}

TEST(CliCorotational, SolveReportsTheNewtonSolve) {
    const std::string dir = temp_dir("cli_corotational_solve");
    json scene = corotated_scene();
    scene["corotation"] = {{"frame", "polar"}, {"tolerance", 1e-9}};
    const Result r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("Newton iterations"));
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["kinematics"], "corotational");
    EXPECT_EQ(s["newton"]["frame"], "polar");
    EXPECT_LE(s["newton"]["residual"].get<double>(), 1e-9);
    EXPECT_GE(s["newton"]["iterations"].get<int>(), 2);
    EXPECT_EQ(s["newton"]["history"].size(), s["newton"]["iterations"].get<std::size_t>());

    // The linear solve of the same scene sags further: corotation shortens the arm as it bends.
    scene.erase("kinematics");
    scene.erase("corotation");
    const Result linear = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/linear");
    ASSERT_EQ(linear.code, 0) << linear.output;
    const json l = read_json(dir + "/linear/summary.json");
    EXPECT_EQ(l["kinematics"], "linear");
    EXPECT_FALSE(l.contains("newton"));
    EXPECT_GT(l["max_displacement"].get<double>(), 1.15 * s["max_displacement"].get<double>());
}

TEST(CliCorotational, CoarsenSolvesElementModelsCorotatedAndTheHierarchyLinear) {
    const std::string dir = temp_dir("cli_corotational_coarsen");
    const Result r = cli("coarsen " + write_scene(dir, corotated_scene()) +
                         " --method effective-tensor,naive,mra-linear --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["kinematics"], "corotational");
    EXPECT_TRUE(s["fine"].contains("newton"));
    EXPECT_GT(s["fine"]["linear_max_displacement"].get<double>(),
              s["max_displacement"].get<double>());
    for (const char* method : {"effective-tensor", "naive"}) {
        const json m = read_json(dir + "/out/" + method + "/summary.json");
        EXPECT_EQ(m["coarse"]["kinematics"], "corotational") << method;
        EXPECT_LE(m["coarse"]["newton"]["residual"].get<double>(), 1e-8) << method;
        EXPECT_TRUE(m["coarse"]["timings"].contains("newton")) << method;
    }
    const json mra = read_json(dir + "/out/mra-linear/summary.json");
    EXPECT_EQ(mra["coarse"]["kinematics"], "linear");
    EXPECT_FALSE(mra["coarse"].contains("newton"));
    // Its level diagnostics are those of the linear operator: the finest level reproduces the
    // linear fine solution to round-off.
    EXPECT_LT(mra["coarse"]["levels"].back()["errors"]["energy_rel"].get<double>(), 1e-6);
}

/// The probe displacements (probe 0: the tip's centre) of a summary.
Eigen::Vector3d tip(const json& summary) {
    const json& u = summary["probes"][0]["u"];
    return {u[0].get<double>(), u[1].get<double>(), u[2].get<double>()};
}

TEST(CliCorotational, RsWarpBringsALinearSolutionTowardsTheCorotatedOne) {
    // Chen 2019, Sec. 4.3: the warp turns the linear solution's ballooning rotation into a
    // finite one. At the bent bar's tip it is closer to the corotated solution than the linear
    // solution is (measured: 0.20 against 0.52 of the corotated tip displacement).
    const std::string dir = temp_dir("cli_corotational_warp");
    json scene = corotated_scene();
    ASSERT_EQ(cli("solve " + write_scene(dir, scene, "cr.json") + " --out " + dir + "/cr").code, 0);
    scene.erase("kinematics");
    ASSERT_EQ(cli("solve " + write_scene(dir, scene, "lin.json") + " --out " + dir + "/lin").code,
              0);
    scene["warp"] = "rs";
    const Result r = cli("solve " + write_scene(dir, scene, "rs.json") + " --out " + dir + "/rs");
    ASSERT_EQ(r.code, 0) << r.output;
    const json cr = read_json(dir + "/cr/summary.json"), lin = read_json(dir + "/lin/summary.json"),
               rs = read_json(dir + "/rs/summary.json");
    EXPECT_EQ(rs["warp"], "rs");
    EXPECT_EQ(lin["warp"], "none");
    EXPECT_DOUBLE_EQ(rs["linear_max_displacement"].get<double>(),
                     lin["max_displacement"].get<double>());
    const double warp_error = (tip(rs) - tip(cr)).norm(),
                 linear_error = (tip(lin) - tip(cr)).norm();
    EXPECT_LT(warp_error, 0.5 * linear_error) << warp_error << " against " << linear_error;
}

TEST(CliCorotational, CoarsenWarpsTheHierarchyAgainstTheCorotatedFineModel) {
    const std::string dir = temp_dir("cli_corotational_coarsen_warp");
    json scene = corotated_scene();
    scene["warp"] = "rs";
    const Result r = cli("coarsen " + write_scene(dir, scene) +
                         " --method effective-tensor,mra-linear --out " + dir + "/rs");
    ASSERT_EQ(r.code, 0) << r.output;
    scene.erase("warp");
    ASSERT_EQ(
        cli("coarsen " + write_scene(dir, scene) + " --method mra-linear --out " + dir + "/plain")
            .code,
        0);
    const json et = read_json(dir + "/rs/effective-tensor/summary.json");
    EXPECT_EQ(et["coarse"]["warp"], "none");  // corotated, not warped
    const json warped = read_json(dir + "/rs/mra-linear/summary.json");
    const json plain = read_json(dir + "/plain/summary.json");
    EXPECT_EQ(warped["coarse"]["warp"], "rs");
    EXPECT_EQ(plain["coarse"]["warp"], "none");
    EXPECT_TRUE(warped["coarse"]["timings"].contains("warp"));
    // Against the corotated fine solution, the warp removes most of the linear model's error
    // (measured: l2 0.21 against 0.51).
    EXPECT_LT(warped["errors"]["l2_rel"].get<double>(),
              0.5 * plain["errors"]["l2_rel"].get<double>());
}

TEST(CliCorotational, SceneErrorsNameTheKey) {
    const std::string dir = temp_dir("cli_corotational_errors");
    json scene = corotated_scene();
    scene["kinematics"] = "nonlinear";
    Result r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("kinematics: unknown value \"nonlinear\""));

    scene = corotated_scene();
    scene.erase("kinematics");
    scene["corotation"] = {{"frame", "polar"}};
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("corotation: applies to \"kinematics\": \"corotational\""));

    scene = corotated_scene();
    scene["corotation"] = {{"frame", "qr"}};
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("corotation.frame: unknown value \"qr\""));

    scene["warp"] = "exponential";
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("warp: unknown value \"exponential\""));

    scene.erase("warp");
    scene["corotation"] = {{"tolerance", 2}};
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("corotation.tolerance"));

    scene = corotated_scene();
    scene["corotation"] = {{"step", "explicit"}};
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("corotation.step: unknown value \"explicit\""));

    // Newton that cannot reach its tolerance says how far it got.
    scene = corotated_scene();
    scene["corotation"] = {{"max_iterations", 1}, {"max_bisections", 0}, {"tolerance", 1e-15}};
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("did not converge beyond load factor 0"));
}

}  // namespace

TEST(CliCorotational, SimulateStepsElementModelsCorotatedAndWarpsTheHierarchy) {
    // The bar swinging down under twice its contract gravity from rest (its tip sags by 79% of
    // the length at equilibrium): a large rotation, in 24 midpoint steps.
    const std::string dir = temp_dir("cli_corotational_simulate");
    json scene = corotated_scene();
    scene["warp"] = "rs";
    scene["dynamics"] = {{"dt", 0.05}, {"steps", 24}, {"output_every", 2}};
    const Result r = cli("simulate " + write_scene(dir, scene) +
                         " --method effective-tensor,mra-linear --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("fine (linear)"));
    EXPECT_THAT(r.output, HasSubstr("mra-linear (linear+warp)"));
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["kinematics"], "corotational");
    EXPECT_EQ(s["warp"], "rs");
    EXPECT_EQ(s["corotation"]["step"], "newton");
    const json& frames = s["fine"]["frames"];
    ASSERT_EQ(frames["energy"].size(), 13u);
    ASSERT_EQ(frames["solves"].size(), 13u);
    EXPECT_EQ(frames["solves"][0], 0);
    // Newton iterations: at least one per step, a handful at most (quadratic convergence from
    // the step's start).
    EXPECT_GE(frames["solves_per_step"].get<double>(), 1.0);
    EXPECT_LE(frames["solves_per_step"].get<double>(), 6.0);
    EXPECT_LT(frames["energy_drift"].get<double>(), 0.05);
    // The linear fine model beside it balloons: its trajectory differs by tens of percent.
    EXPECT_GT(s["fine"]["linear"]["errors"]["trajectory_l2_rel"].get<double>(), 0.1);
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/fine-linear.pvd"));
    const json et = s["methods"][0], mra = s["methods"][1];
    EXPECT_EQ(et["coarse"]["frames"]["kinematics"], "corotational");
    EXPECT_EQ(et["coarse"]["frames"]["warp"], "none");
    EXPECT_EQ(mra["coarse"]["frames"]["kinematics"], "linear");
    EXPECT_EQ(mra["coarse"]["frames"]["warp"], "rs");
    EXPECT_FALSE(mra["coarse"]["frames"].contains("factorizations"));
    EXPECT_GT(mra["timings"]["coarse"]["warp_per_frame"].get<double>(), 0.0);
    // The errors of 6 coarse tets and of 2 levels (measured 0.31 and 0.24, against 0.23 for
    // the linear fine model): coarsening errors; the accordion tests compare methods.
    std::printf(
        "  trajectory l2 against the corotated fine model: linear fine %.3f, "
        "effective-tensor %.3f, mra-linear + warp %.3f\n",
        s["fine"]["linear"]["errors"]["trajectory_l2_rel"].get<double>(),
        et["errors"]["trajectory_l2_rel"].get<double>(),
        mra["errors"]["trajectory_l2_rel"].get<double>());
}

TEST(CliCorotational, SimulateCountsTheKrylovIterationsAndFactorizationsPerFrame) {
    // corotation.linear_solve "factorize": every Newton iteration factorizes. "lagged_krylov"
    // (the default): the first Newton iteration of each run factorizes, the others solve by
    // Krylov iterations preconditioned by that factorization (refreshed only when they fail),
    // fine and coarse alike.
    const std::string dir = temp_dir("cli_corotational_lagged");
    for (const bool lagged : {false, true}) {
        json scene = corotated_scene();
        if (!lagged) scene["corotation"] = {{"linear_solve", "factorize"}};
        scene["dynamics"] = {{"dt", 0.05}, {"steps", 12}, {"output_every", 4}};
        const std::string out = dir + (lagged ? "/lagged" : "/factorize");
        const Result r =
            cli("simulate " + write_scene(dir, scene) + " --method effective-tensor --out " + out);
        ASSERT_EQ(r.code, 0) << r.output;
        const json s = read_json(out + "/summary.json");
        EXPECT_EQ(s["corotation"]["linear_solve"], lagged ? "lagged_krylov" : "factorize");
        for (const json* frames : {&s["fine"]["frames"], &s["coarse"]["frames"]}) {
            int solves = 0, factorizations = 0, krylov = 0;
            ASSERT_EQ((*frames)["factorizations"].size(), 4u);
            for (std::size_t i = 0; i < 4; ++i) {
                solves += (*frames)["solves"][i].get<int>();
                factorizations += (*frames)["factorizations"][i].get<int>();
                krylov += (*frames)["krylov_iterations"][i].get<int>();
            }
            if (lagged) {
                EXPECT_EQ((*frames)["factorizations"][1], 1);  // the run's first iteration
                EXPECT_LT(factorizations, solves);
                EXPECT_GE(krylov, solves - factorizations);  // one or more per Krylov solve
            } else {
                EXPECT_EQ((*frames)["factorizations"], (*frames)["solves"]);
                EXPECT_EQ(krylov, 0);
            }
        }
    }
}
