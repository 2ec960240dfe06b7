// End-to-end tests of the coarsegrain executable: outputs, exit codes and error messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "cli/cli_test_util.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/scene/scene.hpp"

using namespace coarsegrain;
using nlohmann::json;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

using namespace coarsegrain::test;

// `solve` with the iterative fine solver: the probes equal the direct solve's to 1e-8 (the
// residual is 1e-10; the scene test bounds the error by cond(K_ff) times it), and the summary
// names the solver.
TEST(Cli, SolveWithMraPcgMatchesCholmod) {
    const std::string dir = test::temp_dir("cli_solve_mra_pcg");
    json j = small_scene();
    ASSERT_EQ(cli("solve " + write_scene(dir, j, "direct.json") + " --out " + dir + "/a").code, 0);
    j["solver"] = {{"backend", "mra-pcg"}, {"tolerance", 1e-10}};
    const Result r = cli("solve " + write_scene(dir, j, "pcg.json") + " --out " + dir + "/b");
    ASSERT_EQ(r.code, 0) << r.output;
    const json a = read_json(dir + "/a/summary.json"), b = read_json(dir + "/b/summary.json");
    EXPECT_EQ(b["solver"], "mra-pcg");
    for (std::size_t p = 0; p < a["probes"].size(); ++p)
        for (int d = 0; d < 3; ++d) {
            const double ua = a["probes"][p]["u"][d], ub = b["probes"][p]["u"][d];
            EXPECT_NEAR(ub, ua, 1e-8 * a["max_displacement"].get<double>()) << p << " " << d;
        }
}

TEST(Cli, SolveWritesSummaryAndVtuWithTheContractKeys) {
    const std::string dir = test::temp_dir("cli_solve");
    const Result r = cli("solve " + write_scene(dir, small_scene()) + " --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["command"], "solve");
    EXPECT_EQ(s["fine"]["nodes"], 9 * 5 * 5);
    EXPECT_EQ(s["fine"]["elements"], 8 * 4 * 4);
    EXPECT_EQ(s["fine"]["dofs"], 3 * 9 * 5 * 5);
    for (const char* phase : {"read", "assemble", "factorize", "solve", "write"})
        EXPECT_TRUE(s["fine"]["timings"].contains(phase)) << phase;
    ASSERT_EQ(s["probes"].size(), 2u);
    EXPECT_EQ(s["probes"][0]["point"], json({2, 0.5, 0.5}));
    // Gravity and traction both push down: the tip moves down, more than the middle.
    const double tip = s["probes"][0]["u"][2], mid = s["probes"][1]["u"][2];
    EXPECT_LT(tip, mid);
    EXPECT_LT(mid, 0.0);
    EXPECT_GE(s["max_displacement"].get<double>(), -tip);
    EXPECT_GT(s["strain_energy"].get<double>(), 0.0);
    // At equilibrium the strain energy is half the work of the load (Clapeyron), to round-off.
    EXPECT_NEAR(s["strain_energy"].get<double>(), 0.5 * s["compliance"].get<double>(),
                1e-9 * s["strain_energy"].get<double>());

    const auto [m, fields] = io::read_vtu(dir + "/out/solution_fine.vtu");
    EXPECT_EQ(m.num_nodes(), 9 * 5 * 5);
    std::vector<std::string> names;
    for (const auto& f : fields.point_data) names.push_back(f.name);
    for (const auto& f : fields.cell_data) names.push_back(f.name);
    for (const char* name : {"displacement", "E", "stress", "von_mises"})
        EXPECT_THAT(names, ::testing::Contains(std::string(name)));
    // read_vtu returns the "material_id" cell field as the mesh's material ids.
    EXPECT_EQ(m.material_ids.minCoeff(), 1);
    EXPECT_EQ(m.material_ids.maxCoeff(), 2);
    for (const auto& entry : fs::directory_iterator(dir + "/out"))
        EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
            << "temporary file left behind: " << entry.path();
}

namespace {

// A picture a person would look at: decodes as a PNG, is not tiny and is not blank (it has
// many colours and contrast; a blank or single-colour image has a handful and none).
void expect_picture(const std::string& file) {
    int w = 0, h = 0, channels = 0;
    std::unique_ptr<unsigned char, void (*)(void*)> pixels(
        stbi_load(file.c_str(), &w, &h, &channels, 3), stbi_image_free);
    ASSERT_TRUE(pixels) << file << ": not a readable image";
    EXPECT_GE(w, 300) << file;
    EXPECT_GE(h, 200) << file;
    std::set<int> colours;
    double sum = 0, sum2 = 0;
    const int n = w * h;
    for (int i = 0; i < n; ++i) {
        const unsigned char* p = pixels.get() + 3 * i;
        colours.insert(p[0] << 16 | p[1] << 8 | p[2]);
        const double grey = (p[0] + p[1] + p[2]) / 3.0;
        sum += grey;
        sum2 += grey * grey;
    }
    EXPECT_GE(colours.size(), 50u) << file;
    EXPECT_GE(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 10.0) << file << ": no contrast";
}

}  // namespace

// --scale picks 16b x 4b x 4b cubic cells, b = round(3 S): whole coarse grids 4x coarser for
// the 3 levels of the hierarchy and the effective tensors' tets.
TEST(CliDemo, ScaleGivesCubicCellsInWholeCoarseGrids) {
    const std::map<double, int> blocks = {{1.67, 5}, {1.33, 4}, {1.0, 3}, {0.67, 2},
                                          {0.5, 2},  {0.33, 1}, {0.25, 1}};
    for (const auto& [scale, b] : blocks) {
        SCOPED_TRACE(scale);
        const json d = scene::demo_scene(scale);
        EXPECT_EQ(d["mesh"]["grid"]["cells"], json({16 * b, 4 * b, 4 * b}));
        EXPECT_EQ(d["coarse"]["mesh"]["grid"]["cells"], json({4 * b, b, b}));
        EXPECT_EQ(d["coarse"]["levels"], 3);
        EXPECT_NO_THROW(scene::parse_scene(d, "demo", ""));
    }
}

// The README's first command at a quarter of the grid: every method, the table, the report.
TEST(CliDemoSlow, ComparesEveryMethodAndWritesTheReport) {
    const std::string dir = test::temp_dir("cli_demo");
    const Result r = cli("demo --scale 0.25 --out " + dir);
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/summary.json");
    EXPECT_EQ(s["command"], "demo");
    EXPECT_EQ(s["fine"]["elements"], 16 * 4 * 4);
    // The tip of a beam clamped at x = 0 under gravity -z moves down.
    EXPECT_LT(s["probes"][0]["u"][2].get<double>(), 0.0);

    const std::vector<std::string> methods = {"effective-tensor", "naive",    "voigt", "reuss",
                                              "mra-linear",       "mra-dirac"};
    ASSERT_EQ(s["methods"].size(), methods.size());
    std::map<std::string, json> row;
    for (std::size_t i = 0; i < methods.size(); ++i) {
        const json& m = s["methods"][i];
        EXPECT_EQ(m["method"], methods[i]);
        EXPECT_THAT(r.output, HasSubstr(methods[i])) << "the table lists every method";
        EXPECT_GT(m["speedup"]["factorize_and_solve"].get<double>(), 1.0) << methods[i];
        EXPECT_LT(m["coarse"]["dofs"].get<int>(), s["fine"]["dofs"].get<int>());
        EXPECT_NO_THROW(io::read_vtu(dir + "/" + methods[i] + "/solution_coarse.vtu"));
        row[methods[i]] = m["errors"];
    }
    EXPECT_NO_THROW(io::read_vtu(dir + "/solution_fine.vtu"));
    // Sane figures: the effective tensors beat the naive average in the l2 norm (barycentric
    // carry-over, docs/guide.md), both refinements of the hierarchy in the energy norm, and
    // linear is more accurate than Dirac (Chen 2019, Fig. 9).
    const double naive_l2 = row["naive"]["l2_rel"], naive_energy = row["naive"]["energy_rel"];
    // The hierarchy's coarse models are Galerkin projections of the fine problem: compliance
    // ratio 1 - energy_rel^2 <= 1 (1e-9: round-off of the solves).
    for (const char* mra : {"mra-linear", "mra-dirac"}) {
        const double e = row[mra]["energy_rel"], ratio = row[mra]["compliance_ratio"];
        EXPECT_NEAR(ratio, 1.0 - e * e, 1e-9) << mra;
        EXPECT_LE(ratio, 1.0 + 1e-9) << mra;
    }
    EXPECT_LT(row["effective-tensor"]["l2_rel"].get<double>(), naive_l2);
    EXPECT_LT(row["mra-dirac"]["energy_rel"].get<double>(), naive_energy);
    EXPECT_LT(row["mra-linear"]["energy_rel"].get<double>(),
              row["mra-dirac"]["energy_rel"].get<double>());

    for (const char* png : {"deformed.png", "methods.png", "mra_levels.png"}) {
        SCOPED_TRACE(png);
        expect_picture(dir + "/" + png);
    }
    std::ifstream in(dir + "/report.md");
    const std::string report((std::istreambuf_iterator<char>(in)), {});
    for (const char* text :
         {"| method | coarse DOFs", "| mra-dirac |", "![", "(deformed.png)", "(methods.png)",
          "(mra_levels.png)", "## Dynamics", "| model | DOFs | per step s",
          "(dynamics/trajectory.png)", "(dynamics/animation.gif)"})
        EXPECT_THAT(report, HasSubstr(text));

    // The dynamic run of the same models: released from rest under gravity, 1.1 time units,
    // about 2.8 periods of this coarse beam's lowest bending mode (period 0.386).
    const json& d = s["dynamics"];
    EXPECT_EQ(d["folder"], "dynamics");
    EXPECT_EQ(d["start"], "rest");
    EXPECT_EQ(d["plots"], json({"dynamics/trajectory.png", "dynamics/animation.gif"}));
    const json ds = read_json(dir + "/dynamics/summary.json");
    EXPECT_EQ(ds["command"], "simulate");
    ASSERT_EQ(d["methods"].size(), methods.size());
    ASSERT_EQ(ds["methods"].size(), methods.size());
    std::map<std::string, json> dyn;
    for (std::size_t i = 0; i < methods.size(); ++i) {
        const json& m = d["methods"][i];
        SCOPED_TRACE(methods[i]);
        EXPECT_EQ(m["method"], methods[i]);
        EXPECT_EQ(m["errors"], ds["methods"][i]["errors"]);  // the overview is the run's figures
        EXPECT_EQ(m["coarse"]["dofs"], s["methods"][i]["coarse"]["dofs"]);  // the same models
        EXPECT_EQ(m["coarse"]["timings"]["build"], s["methods"][i]["coarse"]["timings"]["build"]);
        EXPECT_GT(m["speedup"]["per_step"].get<double>(), 1.0);
        dyn[methods[i]] = m["errors"];
    }
    ASSERT_GE(dyn["mra-linear"]["phase"][0]["crossings_fine"].get<int>(), 2);
    // Measured at this scale: trajectory errors mra-linear 1.5e-3, mra-dirac 0.030,
    // effective-tensor 0.75, naive 0.998 (its beam is about 200 times too stiff in bending, so
    // it hardly moves); mra-linear's period error 1.3e-4 and lag 1.5e-4 (of a 0.386 period).
    // Bounds with a margin of 10 on the small errors.
    EXPECT_LT(dyn["mra-linear"]["trajectory_l2_rel"].get<double>(), 0.015);
    EXPECT_LT(dyn["mra-dirac"]["trajectory_l2_rel"].get<double>(), 0.3);
    EXPECT_GT(dyn["naive"]["trajectory_l2_rel"].get<double>(), 0.9);
    EXPECT_LT(std::abs(dyn["mra-linear"]["phase"][0]["period_rel"].get<double>()), 1.5e-3);
    EXPECT_LT(std::abs(dyn["mra-linear"]["phase"][0]["lag"].get<double>()), 1.5e-3);
    // A model stiffer than the fine one in statics (compliance ratio below 1) vibrates faster.
    for (const char* stiff : {"effective-tensor", "naive", "reuss"}) {
        SCOPED_TRACE(stiff);
        ASSERT_LT(row[stiff]["compliance_ratio"].get<double>(), 1.0);
        EXPECT_LT(dyn[stiff]["phase"][0]["period_rel"].get<double>(), 0.0);
    }
    const GifInfo gif = read_gif(dir + "/dynamics/animation.gif");
    EXPECT_EQ(gif.error, "");
    EXPECT_EQ(gif.frames, 60);  // of 111 saved frames
    expect_picture(dir + "/dynamics/trajectory.png");
}

TEST(Cli, UsageErrorsExitWithTwo) {
    EXPECT_EQ(cli("").code, 2);
    EXPECT_EQ(cli("frobnicate").code, 2);
    EXPECT_EQ(cli("solve").code, 2);
    EXPECT_EQ(cli("--help").code, 0);
}

// One bad-input case: the scene modification, and text the single error line must contain.
struct BadScene {
    std::string name;
    std::function<void(json&)> modify;
    std::string message;
};

class CliBadScene : public ::testing::TestWithParam<BadScene> {};

TEST_P(CliBadScene, FailsWithOneClearMessageAndNoOutput) {
    const BadScene& bad = GetParam();
    const std::string dir = test::temp_dir("cli_bad_" + bad.name);
    json j = small_scene();
    bad.modify(j);
    const Result r = cli("solve " + write_scene(dir, j) + " --out " + dir + "/out");
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("error: "));
    EXPECT_THAT(r.output, HasSubstr(bad.message));
    EXPECT_FALSE(fs::exists(dir + "/out/summary.json"));
    EXPECT_FALSE(fs::exists(dir + "/out/solution_fine.vtu"));
}

INSTANTIATE_TEST_SUITE_P(
    Cases, CliBadScene,
    ::testing::Values(
        BadScene{"unknown_key",
                 [](json& j) {
                     j["gravity"] = {0, 0, 1};
                 },
                 "gravity: unknown key"},
        BadScene{"missing_material", [](json& j) { j["materials"].erase("2"); }, "material id 2"},
        BadScene{"bad_nu", [](json& j) { j["materials"]["1"]["nu"] = 0.5; }, "materials.1"},
        BadScene{"negative_E", [](json& j) { j["materials"]["1"]["E"] = -1; }, "materials.1"},
        BadScene{"empty_dirichlet_box",
                 [](json& j) {
                     j["dirichlet"][0]["box"]["min"] = {5, 5, 5};
                     j["dirichlet"][0]["box"]["max"] = {6, 6, 6};
                 },
                 "dirichlet[0].box selects no node"},
        BadScene{"empty_traction_box",
                 [](json& j) {
                     j["loads"]["traction"][0]["box"]["min"] = {0.5, 0.2, 0.2};
                     j["loads"]["traction"][0]["box"]["max"] = {0.6, 0.3, 0.3};
                 },
                 "traction[0].box selects no boundary face"},
        BadScene{"singular", [](json& j) { j.erase("dirichlet"); }, "not positive definite"},
        BadScene{"short_vector",
                 [](json& j) {
                     j["loads"]["gravity"] = {0, -1};
                 },
                 "loads.gravity: expected 3 numbers"},
        BadScene{"probe_outside",
                 [](json& j) {
                     j["probes"] = {{9, 9, 9}};
                 },
                 "probes[0]"},
        BadScene{"missing_mesh_file",
                 [](json& j) {
                     j["mesh"] = {{"file", "nope.msh"}};
                 },
                 "nope.msh"},
        BadScene{"bad_element", [](json& j) { j["mesh"]["grid"]["element"] = "prism"; },
                 "mesh.grid.element: unknown element"},
        BadScene{"bad_backend",
                 [](json& j) {
                     j["solver"] = {{"backend", "magic"}};
                 },
                 "solver.backend"}),
    [](const auto& p) { return p.param.name; });

TEST(Cli, InvalidJsonNamesTheFile) {
    const std::string dir = test::temp_dir("cli_invalid_json");
    const std::string file = dir + "/broken.json";
    std::ofstream(file) << "{ \"mesh\": ";
    const Result r = cli("solve " + file + " --out " + dir + "/out");
    EXPECT_EQ(r.code, 1);
    EXPECT_THAT(r.output, HasSubstr("broken.json"));
    EXPECT_THAT(r.output, HasSubstr("not valid JSON"));
}

TEST(Cli, UnwritableOutputFolderIsReportedBeforeAnyWork) {
    const std::string dir = test::temp_dir("cli_unwritable");
    const std::string file = write_scene(dir, small_scene());
    std::ofstream(dir + "/blocker") << "a file, not a folder";
    const Result r = cli("solve " + file + " --out " + dir + "/blocker/out");
    EXPECT_EQ(r.code, 1);
    EXPECT_THAT(r.output, HasSubstr("blocker/out"));
}
