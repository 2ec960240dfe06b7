// Locking warnings on the command line: one "warning: ..." line on stderr and the "warnings"
// array of summary.json, for every command that assembles a fine model.
#include <gtest/gtest.h>

#include "cli/cli_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;

namespace {

const char* const kLockWarning =
    "material 2: nu = 0.499: standard hex elements lock (tip deflection error ~40% on a 32x8x8 "
    "cantilever, 1.3% at nu = 0.3); use \"fem\": {\"formulation\": \"incompatible\"}";

json locking_scene() {
    json j = small_scene();
    j["materials"]["2"]["nu"] = 0.499;
    j["coarse"] = {{"mesh",
                    {{"grid",
                      {{"min", {0, 0, 0}}, {"max", {2, 1, 1}}, {"cells", {2, 1, 1}},
                       {"element", "tet"}}}}}};
    return j;
}

TEST(CliWarnings, SolveAndCoarsenReportLockingOnStderrAndInTheSummary) {
    const std::string dir = temp_dir("cli_warnings");
    const std::string scene = write_scene(dir, locking_scene());
    const Result solve = cli("solve " + scene + " --out " + dir + "/solve");
    ASSERT_EQ(solve.code, 0) << solve.output;
    EXPECT_NE(solve.output.find(std::string("warning: ") + kLockWarning + "\n"), std::string::npos)
        << solve.output;  // also under --quiet
    EXPECT_EQ(read_json(dir + "/solve/summary.json")["warnings"], json({kLockWarning}));

    const Result one = cli("coarsen " + scene + " --method naive --out " + dir + "/one");
    ASSERT_EQ(one.code, 0) << one.output;
    EXPECT_NE(one.output.find(kLockWarning), std::string::npos);
    EXPECT_EQ(read_json(dir + "/one/summary.json")["warnings"], json({kLockWarning}));

    const Result two = cli("coarsen " + scene + " --method naive,reuss --out " + dir + "/two");
    ASSERT_EQ(two.code, 0) << two.output;
    EXPECT_EQ(read_json(dir + "/two/summary.json")["warnings"], json({kLockWarning}));
    EXPECT_EQ(read_json(dir + "/two/reuss/summary.json")["warnings"], json({kLockWarning}));
}

TEST(CliWarnings, IncompatibleFormulationHasNoWarningAndAnEmptyArray) {
    const std::string dir = temp_dir("cli_no_warnings");
    json j = locking_scene();
    j["fem"] = {{"formulation", "incompatible"}};
    const Result r = cli("solve " + write_scene(dir, j) + " --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(r.output.find("warning:"), std::string::npos) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    ASSERT_TRUE(s.contains("warnings"));
    EXPECT_EQ(s["warnings"], json::array());

    j["mesh"]["grid"]["element"] = "tet";
    const Result tet = cli("solve " + write_scene(dir, j, "tet.json") + " --out " + dir + "/tet");
    EXPECT_EQ(tet.code, 1);
    EXPECT_NE(tet.output.find("error: " + dir +
                              "/tet.json: fem.formulation: \"incompatible\" does not apply to tet "
                              "elements"),
              std::string::npos)
        << tet.output;
}

}  // namespace
