// End-to-end: the material-adapted hierarchy on automatic level meshes (coarse.levels on a
// simplicial fine mesh that is no grid): the level files, their reuse as coarse.level_meshes, the
// errors over the levels against the effective tensors on the coarsest level, and bad input.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>

#include "cli/cli_test_util.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "coarsegrain/mesh/grid.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;
using ::testing::HasSubstr;

namespace {

/// A layered plate with a hole, written to dir/name: the triangles of a 32 x 32 grid over
/// [0, 1]^2 (interior nodes moved by up to a quarter cell) without those whose centroid lies
/// within 0.2 of the centre; material 1 (soft) and 2 (stiff) in horizontal layers 1/8 thick.
std::string write_holed_plate(const std::string& dir, const std::string& name) {
    mesh::Mesh grid = mesh::make_grid(mesh::ElementType::Tri3, Eigen::Vector2d::Zero(),
                                      Eigen::Vector2d::Ones(), Eigen::Vector2i(32, 32));
    distort_interior(grid, 0.25, 3);
    const Matrix centres = mesh::element_centroids(grid);
    mesh::Mesh plate = grid;
    Index kept = 0;
    for (Index e = 0; e < grid.num_elements(); ++e) {
        if ((centres.row(e) - Eigen::RowVector2d(0.5, 0.5)).norm() <= 0.2) continue;
        plate.elements.row(kept) = grid.elements.row(e);
        plate.material_ids[kept++] = 1 + static_cast<int>(std::floor(8 * centres(e, 1))) % 2;
    }
    plate.elements.conservativeResize(kept, 3);
    plate.material_ids.conservativeResize(kept);
    io::write_mesh(dir + "/" + name, plate);  // the readers drop the hole's unused nodes
    return name;
}

/// The plate (soft E = 100, stiff E = 1e5) hung from its top under gravity, with `coarse` as its
/// "coarse" block.
json holed_plate_scene(const std::string& dir, const json& coarse) {
    return {{"dimension", 2},
            {"mesh", {{"file", write_holed_plate(dir, "plate.msh")}}},
            {"materials",
             {{"1", {{"E", 100}, {"nu", 0.3}, {"density", 1}}},
              {"2", {{"E", 1e5}, {"nu", 0.3}, {"density", 1}}}}},
            {"dirichlet", {{{"box", {{"min", {-1, 0.999999}}, {"max", {2, 2}}}}}}},
            {"loads", {{"gravity", {0, -1}}}},
            {"coarse", coarse}};
}

/// A coarse mesh of the plate for the effective tensors, written to dir/name: the triangles of
/// an n x n grid over [0, 1]^2 but those with all corners within 0.2 of the centre, so that it
/// encloses the fine mesh and each of its elements holds some of it.
std::string write_coarse_plate(const std::string& dir, const std::string& name, int n) {
    mesh::Mesh m = mesh::make_grid(mesh::ElementType::Tri3, Eigen::Vector2d::Zero(),
                                   Eigen::Vector2d::Ones(), Eigen::Vector2i(n, n));
    Index kept = 0;
    for (Index e = 0; e < m.num_elements(); ++e) {
        bool in_hole = true;
        for (Index a = 0; a < 3; ++a)
            in_hole =
                in_hole &&
                (m.rest_positions.row(m.elements(e, a)) - Eigen::RowVector2d(0.5, 0.5)).norm() <
                    0.2;
        if (!in_hole) m.elements.row(kept++) = m.elements.row(e);
    }
    m.elements.conservativeResize(kept, 3);
    m.material_ids = IndexVector::Ones(kept);
    m.grid.reset();
    io::write_mesh(dir + "/" + name, m);
    return name;
}

json errors_of(const std::string& summary) { return read_json(summary)["errors"]; }

std::string read_text(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

TEST(CliCoarsenAutomaticLevels, WritesLevelsThatGiveTheSameHierarchyBack) {
    const std::string dir = temp_dir("cli_automatic_levels");
    const Result r = cli("coarsen " + write_scene(dir, holed_plate_scene(dir, {{"levels", 3}})) +
                         " --method mra-linear --out " + dir + "/auto");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/auto/summary.json");
    const json& levels = s["coarse"]["levels"];
    ASSERT_EQ(levels.size(), 3u);
    for (int k = 1; k <= 2; ++k) {
        const std::string file = "level_" + std::to_string(k) + ".vtu";
        EXPECT_EQ(levels[k - 1]["mesh"], file);
        EXPECT_TRUE(std::filesystem::exists(dir + "/auto/" + file)) << file;
    }
    EXPECT_GT(s["coarse"]["timings"]["automatic levels"].get<double>(), 0);
    // Each level's single-level solve is the A-orthogonal projection onto a space containing the
    // coarser levels' (Eq. 4): the energy error decreases over the levels, to the fine level's
    // round-off (1e-12).
    double previous = std::numeric_limits<double>::infinity();
    for (const json& L : levels) {
        const double e = L["errors"]["energy_rel"].get<double>();
        EXPECT_LT(e, previous) << "level " << L["level"];
        previous = e;
    }
    EXPECT_LT(previous, 1e-12);

    // The written levels given back as coarse.level_meshes build the same hierarchy (the VTU
    // holds the positions as Float64): the same errors, up to the solves' round-off (1e-9).
    const json given = holed_plate_scene(
        dir, {{"level_meshes", {dir + "/auto/level_1.vtu", dir + "/auto/level_2.vtu"}}});
    const Result g = cli("coarsen " + write_scene(dir, given, "given.json") +
                         " --method mra-linear --out " + dir + "/given");
    ASSERT_EQ(g.code, 0) << g.output;
    const json a = errors_of(dir + "/auto/summary.json"),
               b = errors_of(dir + "/given/summary.json");
    for (const char* key : {"l2_rel", "energy_rel", "compliance_ratio"})
        EXPECT_NEAR(b[key].get<double>(), a[key].get<double>(),
                    1e-9 * std::abs(a[key].get<double>()))
            << key;

    // The effective tensors on a coarse mesh of at least as many nodes as the coarsest level
    // (8 x 8 cells but the hole's: 80 nodes) have its nodes' P1 space, not adapted to the layers:
    // the hierarchy's coarsest level must beat them.
    const json tensors =
        holed_plate_scene(dir, {{"mesh", {{"file", write_coarse_plate(dir, "coarse.msh", 8)}}}});
    const Result t = cli("coarsen " + write_scene(dir, tensors, "tensors.json") +
                         " --method effective-tensor --out " + dir + "/tensors");
    ASSERT_EQ(t.code, 0) << t.output;
    const json ts = read_json(dir + "/tensors/summary.json");
    EXPECT_GE(ts["coarse"]["nodes"].get<Index>(), levels[0]["nodes"].get<Index>());
    EXPECT_LT(a["l2_rel"].get<double>(), ts["errors"]["l2_rel"].get<double>());
    EXPECT_LT(a["energy_rel"].get<double>(), ts["errors"]["energy_rel"].get<double>());
}

TEST(CliCoarsenAutomaticLevels, BadInputFailsBeforeAnyWork) {
    const std::string dir = temp_dir("cli_automatic_levels_bad");
    // About 990 nodes: the coarsest of 6 levels would have 990 / 4^5 < 3 nodes.
    Result r = cli("coarsen " + write_scene(dir, holed_plate_scene(dir, {{"levels", 6}})) +
                   " --method mra-linear --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("coarse.levels: mra: 6 levels are too many"));
    EXPECT_THAT(r.output, HasSubstr("use at most 5 levels"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/out/summary.json"));
    // A quad mesh read from a file is no grid and has no automatic levels.
    mesh::Mesh quad_mesh = mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d::Zero(),
                                           Eigen::Vector2d::Ones(), Eigen::Vector2i(8, 8));
    quad_mesh.material_ids.setOnes();
    io::write_mesh(dir + "/quads.msh", quad_mesh);
    json quads = holed_plate_scene(dir, {{"levels", 2}});
    quads["mesh"]["file"] = "quads.msh";
    r = cli("coarsen " + write_scene(dir, quads, "quads.json") + " --method mra-linear --out " +
            dir + "/out");
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.output, HasSubstr("mesh: the mra-linear method needs a regular grid"));
    EXPECT_THAT(r.output, HasSubstr("got quad elements"));
}

// In a comparison, levels the mesh cannot hold fail the hierarchy methods only: the effective
// tensors on coarse.mesh still run.
TEST(CliCoarsenAutomaticLevels, TooManyLevelsFailOnlyTheHierarchyInAComparison) {
    const std::string dir = temp_dir("cli_automatic_levels_all");
    const json scene = holed_plate_scene(
        dir, {{"mesh", {{"file", write_coarse_plate(dir, "coarse.msh", 8)}}}, {"levels", 6}});
    const Result r =
        cli("coarsen " + write_scene(dir, scene) + " --method all --out " + dir + "/out");
    EXPECT_NE(r.code, 0);
    const json s = read_json(dir + "/out/summary.json");
    int failed = 0;
    for (const json& m : s["methods"]) {
        const std::string method = m["method"];
        if (method.starts_with("mra")) {
            EXPECT_THAT(m["error"].get<std::string>(), HasSubstr("coarse.levels")) << method;
            ++failed;
        } else {
            EXPECT_FALSE(m.contains("error")) << method;
        }
    }
    EXPECT_EQ(failed, 2);
    EXPECT_EQ(s["failed_methods"], 2);
}

}  // namespace

// simulate and modes make the automatic levels once for all hierarchy methods and write them to
// each method's folder, listed in its entry; given back as coarse.level_meshes they step the
// same coarse model (the VTU holds Float64 positions: the trajectories agree to the solves'
// round-off, 1e-9 relative).
TEST(CliSimulateAutomaticLevels, SharesAndWritesTheLevels) {
    const std::string dir = temp_dir("cli_simulate_automatic_levels");
    json scene = holed_plate_scene(dir, {{"levels", 3}});
    scene["dynamics"] = {{"dt", 0.01}, {"steps", 10}, {"output_every", 5}};
    scene["probes"] = {{0.5, 0.1}};
    const Result r = cli("simulate " + write_scene(dir, scene) +
                         " --method mra-linear,mra-dirac --out " + dir + "/sim");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/sim/summary.json");
    ASSERT_EQ(s["methods"].size(), 2u);
    for (const json& m : s["methods"]) {
        const std::string method = m["method"];
        ASSERT_EQ(m["coarse"]["files"].size(), 2u) << method;
        for (int k = 1; k <= 2; ++k) {
            const std::string file = method + "/level_" + std::to_string(k) + ".vtu";
            EXPECT_EQ(m["coarse"]["files"][k - 1], file);
            EXPECT_TRUE(std::filesystem::exists(dir + "/sim/" + file)) << file;
        }
    }
    EXPECT_EQ(read_text(dir + "/sim/mra-linear/level_1.vtu"),
              read_text(dir + "/sim/mra-dirac/level_1.vtu"));

    json given = holed_plate_scene(dir, {{"level_meshes",
                                          {dir + "/sim/mra-linear/level_1.vtu",
                                           dir + "/sim/mra-linear/level_2.vtu"}}});
    given["dynamics"] = scene["dynamics"];
    given["probes"] = scene["probes"];
    const Result g = cli("simulate " + write_scene(dir, given, "given.json") +
                         " --method mra-linear --out " + dir + "/given");
    ASSERT_EQ(g.code, 0) << g.output;
    const json gs = read_json(dir + "/given/summary.json");
    EXPECT_FALSE(gs["coarse"].contains("files"));  // given levels are not written again
    const double a = s["methods"][0]["errors"]["trajectory_l2_rel"].get<double>(),
                 b = gs["errors"]["trajectory_l2_rel"].get<double>();
    EXPECT_NEAR(b, a, 1e-9 * a);

    const Result m = cli("modes " + write_scene(dir, scene) +
                         " --method mra-linear --count 2 --out " + dir + "/modes");
    ASSERT_EQ(m.code, 0) << m.output;
    const json ms = read_json(dir + "/modes/summary.json");
    ASSERT_EQ(ms["coarse"]["files"].size(), 2u);
    EXPECT_TRUE(std::filesystem::exists(dir + "/modes/mra-linear/level_2.vtu"));
}
