// End-to-end tests of "kinematics": "corotational" in `coarsegrain solve` and `coarsen`: the
// summary keys, the Newton report, element models solved corotated and the hierarchy linear,
// and the scene errors.
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

    scene["corotation"] = {{"tolerance", 2}};
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("corotation.tolerance"));

    scene = corotated_scene();
    scene["dynamics"] = {{"dt", 0.01}, {"steps", 2}};
    r = cli("simulate " + write_scene(dir, scene) + " --out " + dir + "/sim");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("simulate steps linear models only"));

    // Newton that cannot reach its tolerance says how far it got.
    scene = corotated_scene();
    scene["corotation"] = {{"max_iterations", 1}, {"max_bisections", 0}, {"tolerance", 1e-15}};
    r = cli("solve " + write_scene(dir, scene) + " --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("did not converge beyond load factor 0"));
}

}  // namespace
