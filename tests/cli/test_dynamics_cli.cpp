// `coarsegrain simulate` and `coarsegrain modes` end to end: the summary.json contract, the
// ParaView series, and identities that the whole pipeline (assembly, coarse model, stepping,
// carrying frames to the fine mesh, errors) must reproduce.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "cli/cli_test_util.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;

namespace {

json with_dynamics(json scene) {
    scene["dynamics"] = {{"dt", 0.02}, {"steps", 40}, {"output_every", 4}};
    return scene;
}

/// A homogeneous bar whose coarse mesh is its own: the effective-tensor model is the fine one.
json identity_scene() {
    json j = small_scene();
    j.erase("material_field");
    j["materials"] = {{"0", {{"E", 1000}, {"nu", 0.3}, {"density", 1}}}};
    j["mesh"]["grid"]["element"] = "tet";
    j["mesh"]["grid"]["cells"] = {4, 2, 2};
    j["coarse"] = {{"mesh", j["mesh"]}, {"mass", "galerkin"}};
    return with_dynamics(j);
}

}  // namespace

TEST(CliSimulate, WritesTheContractKeysAndTheSeries) {
    const std::string dir = temp_dir("cli_simulate");
    json j = with_dynamics(small_scene());
    j["coarse"] = {
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}}, {"max", {2, 1, 1}}, {"cells", {2, 1, 1}}, {"element", "tet"}}}}},
        {"levels", 3}};
    const Result r = cli("simulate " + write_scene(dir, j) +
                         " --method effective-tensor,mra --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["command"], "simulate");
    ASSERT_EQ(s["times"].size(), 11u);  // t = 0 and every 4th of 40 steps
    EXPECT_NEAR(s["times"][10].get<double>(), 0.8, 1e-12);
    ASSERT_EQ(s["probes"].size(), 2u);
    ASSERT_EQ(s["probes"][0]["u_fine"].size(), 11u);
    EXPECT_EQ(s["probes"][0]["u_fine"][0], json({0.0, 0.0, 0.0}));  // from rest
    for (const char* phase : {"factorize", "per_step"})
        EXPECT_TRUE(s["timings"]["fine"].contains(phase)) << phase;
    ASSERT_EQ(s["methods"].size(), 2u);
    for (const json& m : s["methods"]) {
        SCOPED_TRACE(m["method"].get<std::string>());
        for (const char* phase : {"build", "mass", "factorize", "per_step"})
            EXPECT_TRUE(m["timings"]["coarse"].contains(phase)) << phase;
        EXPECT_TRUE(m["speedup"].contains("per_step"));
        ASSERT_EQ(m["probes"][0]["u"].size(), 11u);
        EXPECT_EQ(m["probes"][0]["u_fine"], s["probes"][0]["u_fine"]);
        // errors.probe_max_rel is its definition applied to the listed probe trajectories.
        double diff = 0, top = 0;
        for (std::size_t p = 0; p < 2; ++p)
            for (std::size_t t = 0; t < 11; ++t) {
                double d2 = 0, u2 = 0;
                for (std::size_t c = 0; c < 3; ++c) {
                    const double u = m["probes"][p]["u_fine"][t][c], uc = m["probes"][p]["u"][t][c];
                    d2 += (uc - u) * (uc - u);
                    u2 += u * u;
                }
                diff = std::max(diff, std::sqrt(d2));
                top = std::max(top, std::sqrt(u2));
            }
        EXPECT_NEAR(m["errors"]["probe_max_rel"].get<double>(), diff / top, 1e-12);
        EXPECT_GE(m["errors"]["trajectory_l2_rel"].get<double>(), 0.0);
        const std::string series = m["method"].get<std::string>();
        EXPECT_TRUE(std::filesystem::exists(dir + "/out/" + series + ".pvd"));
        EXPECT_TRUE(std::filesystem::exists(dir + "/out/" + series + "/frame_00010.vtu"));
    }
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/fine.pvd"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/fine/frame_00010.vtu"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/trajectory.csv"));
}

// The pipeline reproduces the fine dynamics when the coarse model is the fine model.
TEST(CliSimulate, CoarseMeshEqualToTheFineMeshReproducesTheFineTrajectory) {
    const std::string dir = temp_dir("cli_simulate_identity");
    const Result r = cli("simulate " + write_scene(dir, identity_scene()) +
                         " --method effective-tensor --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["method"], "effective-tensor");
    EXPECT_LT(s["errors"]["trajectory_l2_rel"].get<double>(), 1e-10);
    EXPECT_LT(s["errors"]["probe_max_rel"].get<double>(), 1e-10);
}

TEST(CliModes, CoarseMeshEqualToTheFineMeshReproducesTheFineFrequencies) {
    const std::string dir = temp_dir("cli_modes_identity");
    const Result r = cli("modes " + write_scene(dir, identity_scene()) +
                         " --method effective-tensor --count 5 --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["command"], "modes");
    ASSERT_EQ(s["fine"]["frequencies_hz"].size(), 5u);
    ASSERT_EQ(s["coarse"]["frequencies_hz"].size(), 5u);
    for (std::size_t i = 0; i < 5; ++i) {
        EXPECT_LT(s["errors"]["frequency_rel"][i].get<double>(), 1e-10) << i;
        EXPECT_NEAR(s["mac"][i].get<double>(), 1.0, 1e-9) << i;
    }
    for (std::size_t i = 1; i < 5; ++i)  // ascending
        EXPECT_LE(s["fine"]["frequencies_hz"][i - 1].get<double>(),
                  s["fine"]["frequencies_hz"][i].get<double>());
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/mode_05.vtu"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/frequencies.csv"));
}

// Bad dynamics input fails before any work, names the key, and leaves no output folder.
TEST(CliSimulate, BadDynamicsFailsNamingTheKey) {
    const std::string dir = temp_dir("cli_simulate_bad");
    const auto expect_failure = [&](const json& scene, const std::string& text) {
        const Result r = cli("simulate " + write_scene(dir, scene) + " --out " + dir + "/out");
        EXPECT_EQ(r.code, 1) << r.output;
        EXPECT_THAT(r.output, ::testing::HasSubstr(text));
        EXPECT_FALSE(std::filesystem::exists(dir + "/out")) << text;
    };
    expect_failure(small_scene(), "simulate needs a \"dynamics\" block");
    json j = with_dynamics(small_scene());
    j["dynamics"]["dt"] = 0;
    expect_failure(j, "dynamics.dt: expected a positive number");
    j = with_dynamics(small_scene());
    j["dynamics"]["output_every"] = 41;
    expect_failure(j, "dynamics.output_every: expected an integer in [1, 40]");
    j = with_dynamics(small_scene());
    j["dynamics"]["integrator"] = "euler";
    expect_failure(j, "dynamics.integrator: unknown value \"euler\"");
    j = with_dynamics(small_scene());
    j["dynamics"]["initial_velocity"] = {1, 2};
    expect_failure(j, "dynamics.initial_velocity: expected 3 numbers for a 3D scene");
    j = with_dynamics(small_scene());
    j["dynamics"]["damping"] = {{"rayleigh", {0.1, -1}}};
    expect_failure(j, "dynamics.damping.rayleigh: expected [alpha, beta] >= 0");
    j = with_dynamics(small_scene());
    j["dynamics"]["mass"] = "diagonal";
    expect_failure(j, "dynamics.mass: unknown value \"diagonal\"");
    j = with_dynamics(small_scene());
    j["coarse"] = {{"mass", "exact"}};
    expect_failure(j, "coarse.mass: unknown value \"exact\"");
}
