// `coarsegrain simulate` and `coarsegrain modes` end to end: the summary.json contract, the
// ParaView series, and identities that the whole pipeline (assembly, coarse model, stepping,
// carrying frames to the fine mesh, errors) must reproduce.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "cli/cli_test_util.hpp"
#include "io/ccx_output.hpp"

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

/// The JSON header line of an animation_data.bin.
json animation_header(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    std::string line;
    std::getline(in, line);
    return json::parse(line);
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
        // One phase entry per probe; 0.8 s is about one period of this bar's bending, too short
        // for two upward crossings: no periods, no lag.
        ASSERT_EQ(m["errors"]["phase"].size(), 2u);
        for (const json& ph : m["errors"]["phase"]) {
            EXPECT_EQ(ph["component"], "z");
            for (const char* key :
                 {"crossings_fine", "crossings", "period_fine", "period", "period_rel", "lag"})
                EXPECT_TRUE(ph.contains(key)) << key;
            if (ph["crossings_fine"].get<int>() < 2) {
                EXPECT_TRUE(ph["period_fine"].is_null());
            }
            if (ph["period"].is_null()) {
                EXPECT_TRUE(ph["lag"].is_null());
            }
        }
        EXPECT_EQ(m["timings"]["fine"], s["timings"]["fine"]);
        const std::string series = m["method"].get<std::string>();
        EXPECT_TRUE(std::filesystem::exists(dir + "/out/" + series + ".pvd"));
        EXPECT_TRUE(std::filesystem::exists(dir + "/out/" + series + "/frame_00010.vtu"));
    }
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/fine.pvd"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/fine/frame_00010.vtu"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/trajectory.csv"));
    EXPECT_THAT(r.output, ::testing::HasSubstr("lag p0"));

    // The animation: every saved frame (11 <= 60), one panel per model.
    EXPECT_EQ(s["plots"], json({"trajectory.png", "animation.gif"}));
    EXPECT_TRUE(s["timings"]["fine"].contains("animation"));
    EXPECT_EQ(s["animation_frames"], 11);
    const json header = animation_header(dir + "/out/animation_data.bin");
    EXPECT_EQ(header["models"], json({"fine", "effective-tensor", "mra"}));
    // The soft bar sags by more than 2% of its size (1.06 of 2): drawn at true scale.
    EXPECT_GT(header["max_displacement"].get<double>(), 0.04);
    EXPECT_EQ(header["scale"], 1.0);
    EXPECT_EQ(header["times"], s["times"]);
    const GifInfo gif = read_gif(dir + "/out/animation.gif");
    EXPECT_EQ(gif.error, "");
    EXPECT_EQ(gif.frames, 11);
    EXPECT_GE(gif.width, 400);
    EXPECT_GE(gif.height, 300);
    EXPECT_EQ(gif.delays_cs, std::vector<int>(11, 10));  // 10 frames per second
}

// More saved frames than the animation shows: 60 of them, evenly spaced with the first and the
// last. The view drops the axis the bar moves least along (y: its loads are along -z) and draws
// the boundary faces that face the viewer, the 8 x 4 hex faces at y = 0; the file's sizes are
// those of the format (scripts/plot_animation.py). The bar is 1e4 times stiffer than the
// contract test's, so that it moves far less than 2% of its size: it is drawn magnified.
TEST(CliSimulate, AnimationShowsSixtyFramesOfTheFacingSurface) {
    const std::string dir = temp_dir("cli_simulate_animation");
    json j = small_scene();
    for (const char* id : {"1", "2"})
        j["materials"][id]["E"] = 1e4 * j["materials"][id]["E"].get<double>();
    j["dynamics"] = {{"dt", 0.01}, {"steps", 130}};
    const Result r = cli("simulate " + write_scene(dir, j) + " --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string data = dir + "/out/animation_data.bin";
    const json h = animation_header(data);
    EXPECT_EQ(h["format"], "coarsegrain-animation");
    EXPECT_EQ(h["models"], json({"fine"}));
    ASSERT_EQ(h["times"].size(), 60u);
    EXPECT_EQ(h["times"][0].get<double>(), 0.0);
    EXPECT_NEAR(h["times"][59].get<double>(), 1.3, 1e-12);
    for (std::size_t k = 1; k < 60; ++k)  // saved frame round(k * 130 / 59): spacing 2 or 3 steps
        EXPECT_NEAR(h["times"][k].get<double>() - h["times"][k - 1].get<double>(), 0.025, 0.0051);
    EXPECT_EQ(h["axes"], json({"x", "z"}));
    EXPECT_EQ(h["dropped"], "y");
    EXPECT_EQ(h["faces"], 32);
    EXPECT_EQ(h["face_size"], 4);
    EXPECT_EQ(h["points"], 45);
    EXPECT_EQ(h["body_size"], 2.0);
    const double largest = h["max_displacement"], scale = h["scale"];
    ASSERT_LT(largest, 0.04);  // below 2% of the body's size: drawn at 10%
    EXPECT_NEAR(scale * largest, 0.2, 1e-12);
    std::ifstream in(data, std::ios::binary);
    std::string line;
    std::getline(in, line);
    const auto header_bytes = static_cast<std::uintmax_t>(line.size() + 1);
    EXPECT_EQ(std::filesystem::file_size(data),
              header_bytes + 4 * (45 * 2 + 32 * 4 + 60 * 45 * 3));  // rest, faces, frames
    const GifInfo gif = read_gif(dir + "/out/animation.gif");
    EXPECT_EQ(gif.error, "");
    EXPECT_EQ(gif.frames, 60);
}

// A 2D body is drawn in its own plane, every element a polygon; above 4000 polygons only their
// nodes are drawn, at most 4000 of them.
TEST(CliSimulate, AnimationOfALarge2dMeshDrawsPoints) {
    const std::string dir = temp_dir("cli_simulate_animation_2d");
    const json j = json::parse(R"({
      "dimension": 2,
      "mesh": { "grid": { "min": [0,0], "max": [2,1], "cells": [80,60], "element": "quad" } },
      "materials": { "0": { "E": 1000, "nu": 0.3, "density": 1 } },
      "dirichlet": [ { "box": { "min": [-1e-9,-1], "max": [1e-9,2] } } ],
      "loads": { "gravity": [0,-1] },
      "dynamics": { "dt": 0.02, "steps": 10 }
    })");
    const Result r = cli("simulate " + write_scene(dir, j) + " --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json h = animation_header(dir + "/out/animation_data.bin");
    EXPECT_EQ(h["axes"], json({"x", "y"}));
    EXPECT_TRUE(h["dropped"].is_null());
    EXPECT_EQ(h["faces"], 0);  // 4800 elements
    EXPECT_LE(h["points"].get<int>(), 4000);
    EXPECT_GE(h["points"].get<int>(), 2000);  // 81 x 61 = 4941 nodes, every second one
    const GifInfo gif = read_gif(dir + "/out/animation.gif");
    EXPECT_EQ(gif.error, "");
    EXPECT_EQ(gif.frames, 11);
}

// Without a usable Python the run succeeds, keeps the animation's data and says how to make it.
TEST(CliSimulate, WithoutPythonTheRunSucceedsWithoutTheGif) {
    const std::string dir = temp_dir("cli_simulate_no_python");
    std::string output;
    EXPECT_EQ(run("COARSEGRAIN_PYTHON=/nonexistent/python3 " + kCli + " --quiet simulate " +
                      write_scene(dir, with_dynamics(small_scene())) + " --out " + dir + "/out",
                  &output),
              0)
        << output;
    EXPECT_THAT(output, ::testing::HasSubstr("note: animation.gif not made"));
    EXPECT_THAT(output, ::testing::HasSubstr("plot_animation.py"));
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_TRUE(s["plots"].empty());
    EXPECT_FALSE(std::filesystem::exists(dir + "/out/animation.gif"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/animation_data.bin"));
}

TEST(CliSimulate, AnimationScriptRejectsATruncatedFile) {
    const std::string dir = temp_dir("cli_animation_bad");
    std::ofstream(dir + "/bad.bin")
        << R"({"format": "coarsegrain-animation", "version": 1, "axes": ["x", "y"],)"
        << R"( "dropped": null, "scale": 1, "models": ["fine"], "times": [0],)"
        << R"( "points": 3, "faces": 1, "face_size": 3})"
        << "\n"
        << "short";
    std::string output;
    EXPECT_NE(run("/usr/bin/python3 " COARSEGRAIN_TEST_DATA "/../../scripts/plot_animation.py " +
                      dir + "/x.gif " + dir + "/bad.bin",
                  &output),
              0);
    EXPECT_THAT(output, ::testing::HasSubstr("the arrays do not have the sizes the header gives"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.gif"));
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

// Corotated too: the effective tensors of a coarse mesh equal to the fine mesh are the fine
// tensors to round-off, so the two corotated runs (each step's Newton solve to the default
// relative residual 1e-8) agree to far below any coarsening error.
TEST(CliSimulate, CoarseMeshEqualToTheFineMeshReproducesTheCorotatedTrajectory) {
    const std::string dir = temp_dir("cli_simulate_identity_corotated");
    json j = identity_scene();
    j["kinematics"] = "corotational";
    j["loads"]["gravity"] = {0, 0, -20};  // the tip sags by a third of the length
    const Result r = cli("simulate " + write_scene(dir, j) + " --method effective-tensor --out " +
                         dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["coarse"]["frames"]["kinematics"], "corotational");
    EXPECT_LT(s["errors"]["trajectory_l2_rel"].get<double>(), 1e-6);
    EXPECT_GT(s["fine"]["linear"]["errors"]["trajectory_l2_rel"].get<double>(), 0.01);
}

// The phase figures of a coarse model equal to the fine one: the same crossings (period error
// and lag 0 up to round-off), and the fine tip's period is that of the lowest mode of the same
// mesh (`modes`). The bar is 4 times thinner in z than in y, so that its load along -z excites
// mostly that mode (bending in z, 0.68 Hz; the next one, in y, is at 1.23 Hz). Measured: 0.9997
// times the mode's period; midpoint lengthens periods by (ω dt)²/12 = 6e-4 and the other modes
// shift the crossings a little: tolerance 3e-3.
TEST(CliSimulate, PhaseOfACoarseModelEqualToTheFineOneIsExact) {
    const std::string dir = temp_dir("cli_simulate_phase");
    json j = identity_scene();
    j["mesh"]["grid"]["max"] = {2, 1, 0.25};
    j["mesh"]["grid"]["cells"] = {8, 4, 1};
    j["coarse"]["mesh"] = j["mesh"];
    j["probes"] = {{2, 0.5, 0.125}, {1, 0.5, 0.125}};
    j["dynamics"] = {{"dt", 0.02}, {"steps", 300}};  // about 4 periods
    const Result r =
        cli("simulate " + write_scene(dir, j) + " --method effective-tensor --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json tip = read_json(dir + "/out/summary.json")["errors"]["phase"][0];
    EXPECT_EQ(tip["component"], "z");
    ASSERT_GE(tip["crossings_fine"].get<int>(), 3);
    EXPECT_EQ(tip["crossings"], tip["crossings_fine"]);
    EXPECT_LT(std::abs(tip["period_rel"].get<double>()), 1e-9);
    EXPECT_LT(std::abs(tip["lag"].get<double>()), 1e-9);
    const Result m = cli("modes " + write_scene(dir, j) + " --count 2 --out " + dir + "/modes");
    ASSERT_EQ(m.code, 0) << m.output;
    const json f = read_json(dir + "/modes/summary.json")["fine"]["frequencies_hz"];
    ASSERT_GT(f[1].get<double>(), 1.5 * f[0].get<double>());  // the modes are well apart
    EXPECT_NEAR(tip["period_fine"].get<double>() * f[0].get<double>(), 1.0, 3e-3);
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

// With the iterative fine solver, simulate's fine trajectory (every step solves the step operator
// M + dt²/4 K by mra-pcg at a 1e-10 residual) and modes' fine frequencies (shift-invert Lanczos
// on K_ff) equal the direct solver's: to 1e-7 of the largest probe displacement over 40 steps,
// and 1e-8 relative for the frequencies (the iterated operators' error is the residual times
// their condition numbers; measured 3e-12 for both); the coarse model, factorized either way.
TEST(CliSimulate, MraPcgFineRunsMatchCholmod) {
    const std::string dir = temp_dir("cli_simulate_mra_pcg");
    json j = identity_scene();
    j["mesh"]["grid"]["element"] = "hex";
    j["mesh"]["grid"]["cells"] = {12, 4, 4};  // 900 free DOFs: modes iterates (dense up to 600)
    const std::string direct = write_scene(dir, j, "direct.json");
    j["solver"] = {{"backend", "mra-pcg"}, {"tolerance", 1e-10}};
    const std::string iterative = write_scene(dir, j, "pcg.json");
    for (const char* command : {"simulate", "modes"}) {
        SCOPED_TRACE(command);
        const std::string args = std::string(command) + " --method effective-tensor ";
        ASSERT_EQ(cli(args + direct + " --out " + dir + "/a_" + command).code, 0);
        const Result r = cli(args + iterative + " --out " + dir + "/b_" + command);
        ASSERT_EQ(r.code, 0) << r.output;
    }
    const json a = read_json(dir + "/a_simulate/summary.json");
    const json b = read_json(dir + "/b_simulate/summary.json");
    double top = 0, diff = 0;
    for (std::size_t p = 0; p < a["probes"].size(); ++p)
        for (std::size_t t = 0; t < a["times"].size(); ++t)
            for (int d = 0; d < 3; ++d) {
                const double ua = a["probes"][p]["u_fine"][t][d];
                top = std::max(top, std::abs(ua));
                diff = std::max(diff, std::abs(b["probes"][p]["u_fine"][t][d].get<double>() - ua));
            }
    EXPECT_GT(top, 0);
    EXPECT_LE(diff, 1e-7 * top);
    EXPECT_NEAR(b["errors"]["trajectory_l2_rel"].get<double>(),
                a["errors"]["trajectory_l2_rel"].get<double>(), 1e-6);
    const json ma = read_json(dir + "/a_modes/summary.json");
    const json mb = read_json(dir + "/b_modes/summary.json");
    for (std::size_t i = 0; i < ma["fine"]["frequencies_hz"].size(); ++i) {
        const double fa = ma["fine"]["frequencies_hz"][i], fb = mb["fine"]["frequencies_hz"][i];
        EXPECT_NEAR(fb, fa, 1e-8 * fa) << i;
    }
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

// simulate --export inp: each element model's deck holds the run as a *DYNAMIC step with the
// lumped coarse masses, and ccx steps it (tests/io checks its trajectory against coarsegrain's);
// runs no deck states are refused before any work.
TEST(CliSimulate, ExportInpWritesADynamicDeckThatCalculixRuns) {
    const std::string dir = temp_dir("cli_simulate_export");
    json j = with_dynamics(small_scene());
    j["coarse"] = json::parse(R"({
      "mesh": { "grid": { "min": [0,0,0], "max": [2,1,1], "cells": [2,1,1], "element": "tet" } }
    })");
    const Result r = cli("simulate " + write_scene(dir, j) +
                         " --method effective-tensor --export inp --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string sub = dir + "/out/effective-tensor";
    std::ifstream deck(sub + "/coarse_model.inp");
    const std::string text((std::istreambuf_iterator<char>(deck)), {});
    EXPECT_THAT(text, ::testing::HasSubstr("*DYNAMIC, DIRECT, ALPHA=0\n0.02, 0.8"));
    EXPECT_THAT(text, ::testing::HasSubstr("*MASS, ELSET=MASS1"));
    std::string output;
    ASSERT_EQ(run("cd " + sub + " && ccx -i coarse_model", &output), 0) << output;
    // 40 steps, every 4th
    EXPECT_EQ(read_ccx_displacements(sub + "/coarse_model.dat").size(), 10u);

    j["kinematics"] = "corotational";
    const Result corotated = cli("simulate " + write_scene(dir, j) +
                                 " --method effective-tensor --export inp --out " + dir + "/cr");
    EXPECT_NE(corotated.code, 0);
    EXPECT_THAT(corotated.output, ::testing::HasSubstr("kinematics: --export inp writes linear"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/cr"));
}
