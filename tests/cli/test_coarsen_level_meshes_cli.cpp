// End-to-end: the material-adapted hierarchy on given level meshes (coarse.level_meshes), run
// with the effective tensors and the baselines on the same coarse mesh (Chen et al. 2019 Sec. 5.1
// against Kharevych et al. 2009).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "cli/cli_test_util.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "coarsegrain/mesh/grid.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;
using ::testing::HasSubstr;

namespace {

/// A simplex grid (triangles or tetrahedra) with n cells per axis over [0, 1]^dim scaled by
/// `scale` about its centre, interior nodes moved by up to `distortion` of a cell, written to
/// dir/name.
std::string write_simplices(const std::string& dir, const std::string& name, int dim, int n,
                            double distortion, double scale, unsigned seed) {
    const Eigen::VectorXd centre = Eigen::VectorXd::Constant(dim, 0.5);
    const Eigen::VectorXd half = Eigen::VectorXd::Constant(dim, 0.5 * scale);
    mesh::Mesh m = mesh::make_grid(dim == 2 ? mesh::ElementType::Tri3 : mesh::ElementType::Tet4,
                                   centre - half, centre + half, Eigen::VectorXi::Constant(dim, n));
    distort_interior(m, distortion, seed);
    io::write_mesh(dir + "/" + name, m);
    return name;
}

/// The layered square or cube (soft E = 100 and stiff E = 1e5 layers 1/8 thick along y, 24^2
/// cells of triangles or 12^3 of tetrahedra) hung from its top under gravity; coarse.mesh and
/// the hierarchy's coarsest level are one mesh of 3 cells per axis 2% larger than the object,
/// its middle level a distorted one of 7 (2D) or 5 (3D): no level is nested in another.
json layered_level_scene(const std::string& dir, int dim = 2) {
    const std::string coarse = write_simplices(dir, "coarse.msh", dim, 3, 0.2, 1.02, 1);
    const std::string middle =
        write_simplices(dir, "middle.msh", dim, dim == 2 ? 7 : 5, 0.2, 1.0, 2);
    const int n = dim == 2 ? 24 : 12;
    json grid = {{"min", json::array()},
                 {"max", json::array()},
                 {"cells", json::array()},
                 {"element", dim == 2 ? "tri" : "tet"}};
    json box_min = json::array(), box_max = json::array(), gravity = json::array();
    for (int d = 0; d < dim; ++d) {
        grid["min"].push_back(0);
        grid["max"].push_back(1);
        grid["cells"].push_back(n);
        box_min.push_back(d == 1 ? 0.999999 : -1);
        box_max.push_back(2);
        gravity.push_back(d == 1 ? -1 : 0);
    }
    return {
        {"dimension", dim},
        {"mesh", {{"grid", grid}}},
        {"material_field", {{"layers", {{"axis", "y"}, {"thickness", 0.125}, {"ids", {1, 2}}}}}},
        {"materials",
         {{"1", {{"E", 100}, {"nu", 0.3}, {"density", 1}}},
          {"2", {{"E", 1e5}, {"nu", 0.3}, {"density", 1}}}}},
        {"dirichlet", {{{"box", {{"min", box_min}, {"max", box_max}}}}}},
        {"loads", {{"gravity", gravity}}},
        {"coarse", {{"mesh", {{"file", coarse}}}, {"level_meshes", {coarse, middle}}}}};
}

// `--method all` with one coarse mesh runs both papers' methods on it (2D: the layered square,
// 3D: the layered cube as tetrahedra). The hierarchy's coarsest
// level spans the same P1 space of the coarse mesh's nodes as the effective tensors' model, but
// adapted to the layers: it must beat the effective tensors and every baseline in every error.
void expect_hierarchy_beats_the_effective_tensors(int dim) {
    const std::string dir = temp_dir("cli_level_meshes_" + std::to_string(dim) + "d");
    const Result r = cli("coarsen " + write_scene(dir, layered_level_scene(dir, dim)) +
                         " --method all --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/out/summary.json");
    std::map<std::string, json> errors;
    for (const json& m : s["methods"]) errors[m["method"]] = m["errors"];
    ASSERT_EQ(errors.size(), 6u) << s["methods"].dump();
    const json& mra = errors.at("mra-linear");
    for (const char* other : {"effective-tensor", "naive", "voigt", "reuss", "mra-dirac"}) {
        const json& e = errors.at(other);
        EXPECT_LT(mra["l2_rel"].get<double>(), e["l2_rel"].get<double>()) << other;
        EXPECT_LT(mra["energy_rel"].get<double>(), e["energy_rel"].get<double>()) << other;
        EXPECT_LT(std::abs(mra["compliance_ratio"].get<double>() - 1),
                  std::abs(e["compliance_ratio"].get<double>() - 1))
            << other;
    }
    // The level report: the levels' meshes, no grid cells, no cell tensors.
    const json m = read_json(dir + "/out/mra-linear/summary.json");
    const json& level1 = m["coarse"]["levels"][0];
    const mesh::Mesh coarse = io::read_mesh(dir + "/coarse.msh");
    EXPECT_EQ(level1["nodes"], coarse.num_nodes());
    EXPECT_EQ(level1["elements"], coarse.num_elements());
    EXPECT_TRUE(level1["cells"].empty());
    EXPECT_THAT(m["coarse"]["coarsest_cells"]["skipped"].get<std::string>(),
                HasSubstr("the coarsest level is a mesh"));
    // Each level's single-level solve is the A-orthogonal projection onto a space containing the
    // coarser levels' (Eq. 4), so the energy error decreases from level to level down to 0 at
    // the fine level (measured 0.0137, 0.0069, 0; 1e-12: the fine level's round-off).
    for (const char* method : {"mra-linear", "mra-dirac"}) {
        const json levels = read_json(dir + "/out/" + method + "/summary.json")["coarse"]["levels"];
        ASSERT_EQ(levels.size(), 3u) << method;
        double previous = std::numeric_limits<double>::infinity();
        for (const json& L : levels) {
            const double e = L["errors"]["energy_rel"].get<double>();
            EXPECT_LT(e, previous) << method << " level " << L["level"];
            previous = e;
        }
        EXPECT_LT(previous, 1e-12) << method;
    }
}

TEST(CliCoarsenLevelMeshes, BothPapersOnOneCoarseMeshLayeredSquare) {
    expect_hierarchy_beats_the_effective_tensors(2);
}

TEST(CliCoarsenLevelMeshes, BothPapersOnOneCoarseMeshLayeredCube) {
    expect_hierarchy_beats_the_effective_tensors(3);
}

TEST(CliCoarsenLevelMeshes, BadLevelsAreErrorsBeforeAnyWork) {
    const std::string dir = temp_dir("cli_level_meshes_bad");
    const json good = layered_level_scene(dir);
    const std::string quads = "quads.msh";
    io::write_mesh(dir + "/" + quads,
                   mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d::Zero(),
                                   Eigen::Vector2d::Ones(), Eigen::Vector2i(2, 2)));
    const auto expect_error = [&](json scene, const std::string& text) {
        const Result r = cli("coarsen " + write_scene(dir, scene) + " --method mra-linear --out " +
                             dir + "/out");
        EXPECT_NE(r.code, 0);
        EXPECT_THAT(r.output, HasSubstr(text));
    };
    json scene = good;
    scene["coarse"]["level_meshes"][0] = quads;
    expect_error(scene, "coarse.level_meshes[0]: the levels of the hierarchy must be simplicial");
    scene = good;
    scene["coarse"]["levels"] = 2;
    expect_error(scene, "coarse.level_meshes: 2 meshes for coarse.levels = 2");
    scene = good;
    scene["coarse"]["radius"] = 3;
    scene["coarse"]["patch"] = 2;
    expect_error(scene,
                 "coarse.level_meshes: mra: on level meshes the localized solves take one "
                 "region per node (patch 1), got patch 2");
    scene = good;
    scene["coarse"]["level_meshes"] = {"missing.msh"};
    expect_error(scene, "coarse.level_meshes[0]: file");
    scene = good;
    scene["coarse"]["level_meshes"] = {good["coarse"]["level_meshes"][1],
                                       good["coarse"]["level_meshes"][0]};
    expect_error(scene, "more than the finer level's");
}

}  // namespace
