// End-to-end tests of `coarsegrain coarsen`: every method, the summary.json contract, errors.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "cli/cli_test_util.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/io/vtu.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;
using ::testing::HasSubstr;

namespace {

// The small two-material bar with a coarse block every method can use: a 2x1x1-cell coarse tet
// mesh (effective tensors and baselines) and 2 levels (the hierarchy: 4x2x2 coarse cells).
json coarse_scene() {
    json j = small_scene();
    j["coarse"] = json::parse(R"({
      "mesh": { "grid": { "min": [0,0,0], "max": [2,1,1], "cells": [2,1,1], "element": "tet" } },
      "levels": 2 })");
    return j;
}

json run_method(const std::string& method, const std::string& dir) {
    const Result r = cli("coarsen " + write_scene(dir, coarse_scene()) + " --method " + method +
                         " --out " + dir + "/out");
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("speedup"));
    return read_json(dir + "/out/summary.json");
}

TEST(CliCoarsen, EveryMethodWritesTheContractKeys) {
    for (const std::string& method : coarsen::method_names()) {
        SCOPED_TRACE(method);
        const std::string dir = temp_dir("cli_coarsen_" + method);
        const json s = run_method(method, dir);
        EXPECT_EQ(s["command"], "coarsen");
        EXPECT_EQ(s["method"], method);
        EXPECT_EQ(s["fine"]["dofs"], 3 * 9 * 5 * 5);
        for (const char* key : {"nodes", "elements", "dofs"})
            EXPECT_GT(s["coarse"][key].get<int>(), 0) << key;
        EXPECT_LT(s["coarse"]["dofs"].get<int>(), s["fine"]["dofs"].get<int>());
        for (const char* phase : {"build", "factorize", "solve"})
            EXPECT_GE(s["coarse"]["timings"][phase].get<double>(), 0.0) << phase;
        for (const char* key : {"energy_rel", "l2_rel", "max_displacement_rel", "compliance_ratio"})
            EXPECT_TRUE(std::isfinite(s["errors"][key].get<double>())) << key;
        // A coarse model is stiffer than the fine one in this test (none of them is exact) but
        // carries the load the right way: the compliance ratio lies in (0, 1.5).
        EXPECT_GT(s["errors"]["compliance_ratio"].get<double>(), 0.0);
        EXPECT_LT(s["errors"]["compliance_ratio"].get<double>(), 1.5);
        ASSERT_EQ(s["probes"].size(), 2u);
        EXPECT_EQ(s["probes"][0]["u"].size(), 3u);
        EXPECT_EQ(s["probes"][0]["u_fine"].size(), 3u);
        EXPECT_GT(s["speedup"]["factorize_and_solve"].get<double>(), 0.0);
        for (const char* file : {"solution_fine.vtu", "solution_coarse.vtu"})
            EXPECT_NO_THROW(io::read_vtu(dir + "/out/" + file)) << file;
    }
}

TEST(CliCoarsen, EffectiveTensorsBeatTheNaiveAverageOnLayers) {
    const json et = run_method("effective-tensor", temp_dir("cli_coarsen_et"));
    const json naive = run_method("naive", temp_dir("cli_coarsen_naive"));
    EXPECT_LT(et["errors"]["l2_rel"].get<double>(), naive["errors"]["l2_rel"].get<double>());
}

TEST(CliCoarsen, UnknownMethodIsAUsageError) {
    const std::string dir = temp_dir("cli_coarsen_bad_method");
    const Result r = cli("coarsen " + write_scene(dir, coarse_scene()) + " --method magic");
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.output, HasSubstr("magic"));
}

TEST(CliCoarsen, UnknownCoarseKeyIsNamed) {
    const std::string dir = temp_dir("cli_coarsen_bad_key");
    json j = coarse_scene();
    j["coarse"]["radious"] = 3;
    const Result r = cli("coarsen " + write_scene(dir, j) + " --out " + dir + "/out");
    EXPECT_EQ(r.code, 1);
    EXPECT_THAT(r.output, HasSubstr("coarse.radious"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/out/summary.json"));
}

}  // namespace
