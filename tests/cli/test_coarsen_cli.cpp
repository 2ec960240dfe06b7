// End-to-end tests of `coarsegrain coarsen`: every method, the summary.json contract, errors.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unsupported/Eigen/SparseExtra>

#include "cli/cli_test_util.hpp"
#include "io/ccx_output.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/mesh/grid.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

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
            EXPECT_TRUE(s["coarse"]["timings"][phase].is_number()) << phase;
        for (const char* key : {"energy_rel", "l2_rel", "max_displacement_rel", "compliance_ratio"})
            EXPECT_TRUE(std::isfinite(s["errors"][key].get<double>())) << key;
        // Every coarse model carries the load the right way (f.u_c > 0). A sanity window, not a
        // theorem for the barycentric methods (their coarse energy is not the fine one, so they
        // can be too soft: compliance ratio 1.65 on docs/guide.md's layered cube), with a
        // margin over the values on this bar (0.07 to 1.0).
        const double compliance_ratio = s["errors"]["compliance_ratio"].get<double>();
        EXPECT_GT(compliance_ratio, 0.0);
        EXPECT_LT(compliance_ratio, 1.5);
        if (method.starts_with("mra") && !method.ends_with("-blind")) {
            // The hierarchy's coarse model is a Galerkin projection of the fine problem (K_c =
            // Φ K Φ^T, f_c = Φ f, u_c carried by Φ^T): u_c is the K-orthogonal projection of u,
            // so compliance_ratio = 1 - energy_rel^2 <= 1 (1e-9: round-off of the two solves).
            // Not for the boundary-blind constructions: their basis ignores the clamps, so it is
            // not a subspace of the constrained fine space (measured here: compliance ratio
            // 1.03 with Dirac refinement).
            const double e = s["errors"]["energy_rel"].get<double>();
            EXPECT_NEAR(compliance_ratio, 1.0 - e * e, 1e-9);
            EXPECT_LE(compliance_ratio, 1.0 + 1e-9);
            // ... and the coarse model's own compliance f_c.u_c is f.u_c.
            EXPECT_NEAR(s["compliance"].get<double>(),
                        compliance_ratio * 2 * s["fine_strain_energy"].get<double>(),
                        1e-9 * s["compliance"].get<double>());
        }
        ASSERT_EQ(s["probes"].size(), 2u);
        EXPECT_EQ(s["probes"][0]["u"].size(), 3u);
        EXPECT_EQ(s["probes"][0]["u_fine"].size(), 3u);
        EXPECT_TRUE(s["speedup"]["factorize_and_solve"].is_number());
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

// Several methods share one fine solve; each writes what it writes alone into its own folder,
// and the comparison adds report.md. Python is switched off: the report says the pictures were
// not made, and the run still succeeds.
TEST(CliCoarsen, AllMethodsCompareInOneRun) {
    const std::string dir = temp_dir("cli_coarsen_all");
    std::string output;
    const int code =
        run("COARSEGRAIN_PYTHON=false " + kCli + " --quiet coarsen " +
                write_scene(dir, coarse_scene()) + " --method all --out " + dir + "/out",
            &output);
    ASSERT_EQ(code, 0) << output;
    EXPECT_THAT(output, HasSubstr("not made"));
    const json s = read_json(dir + "/out/summary.json");
    const std::vector<std::string> all = {"effective-tensor", "naive",    "voigt", "reuss",
                                          "mra-linear",       "mra-dirac"};
    ASSERT_EQ(s["methods"].size(), all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
        EXPECT_EQ(s["methods"][i]["method"], all[i]);
        const json m = read_json(dir + "/out/" + all[i] + "/summary.json");
        EXPECT_EQ(m["method"], all[i]);
        EXPECT_EQ(m["errors"], s["methods"][i]["errors"]);
        EXPECT_TRUE(fs::exists(dir + "/out/" + all[i] + "/solution_coarse.vtu"));
    }
    EXPECT_TRUE(fs::exists(dir + "/out/solution_fine.vtu"));
    EXPECT_FALSE(fs::exists(dir + "/out/solution_coarse.vtu"));
    // Voigt's tensor exceeds Reuss's on every coarse element (arithmetic against harmonic mean
    // of SPD tensors), so on the same coarse mesh, load and conditions K_voigt >= K_reuss and
    // the coarse compliance f_c.K^{-1}f_c of Voigt is at most Reuss's (1e-12: round-off of the
    // solves). In 3D the isotropic tensor is linear in (lambda, mu): naive is Voigt, and the
    // compliances agree to round-off.
    const auto coarse_compliance = [&](const std::string& method) {
        return read_json(dir + "/out/" + method + "/summary.json")["compliance"].get<double>();
    };
    const double voigt = coarse_compliance("voigt");
    EXPECT_LE(voigt, coarse_compliance("reuss") * (1 + 1e-12));
    EXPECT_NEAR(coarse_compliance("naive"), voigt, 1e-10 * voigt);
    // The same computation as a run of the method alone, to round-off.
    const json alone = run_method("reuss", temp_dir("cli_coarsen_reuss_alone"));
    EXPECT_NEAR(s["methods"][3]["errors"]["l2_rel"].get<double>(),
                alone["errors"]["l2_rel"].get<double>(), 1e-12);
    std::ifstream in(dir + "/out/report.md");
    const std::string report((std::istreambuf_iterator<char>(in)), {});
    EXPECT_THAT(report, HasSubstr("| reuss |"));
    EXPECT_THAT(report, HasSubstr("deformed.png was not made"));
}

// A method that cannot run does not stop the others: with an anisotropic fine material the
// naive average (isotropic parameters only) fails, the others run, and the exit code says so.
TEST(CliCoarsen, AllRunsEveryMethodThatCanRun) {
    const std::string dir = temp_dir("cli_coarsen_all_partial");
    json j = coarse_scene();
    j["coarse"].erase("levels");
    j["materials"]["2"] = {{"C_voigt",
                            {{12, 4, 4, 0, 0, 0},
                             {4, 20, 4, 0, 0, 0},
                             {4, 4, 12, 0, 0, 0},
                             {0, 0, 0, 4, 0, 0},
                             {0, 0, 0, 0, 4, 0},
                             {0, 0, 0, 0, 0, 4}}},
                           {"density", 2}};
    std::string output;
    const int code = run("COARSEGRAIN_PYTHON=false " + kCli + " --quiet coarsen " +
                             write_scene(dir, j) + " --method all --out " + dir + "/out",
                         &output);
    EXPECT_EQ(code, 1) << output;
    EXPECT_THAT(output, HasSubstr("method naive failed"));
    EXPECT_THAT(output, HasSubstr("error: 1 method failed"));
    const json s = read_json(dir + "/out/summary.json");
    EXPECT_EQ(s["failed_methods"], 1);
    ASSERT_EQ(s["methods"].size(), 4u);
    for (const json& m : s["methods"]) {
        const std::string method = m["method"];
        if (method == "naive") {
            EXPECT_THAT(m["error"].get<std::string>(), HasSubstr("isotropic"));
            EXPECT_FALSE(m.contains("errors"));
            EXPECT_FALSE(fs::exists(dir + "/out/naive"));
        } else {
            EXPECT_TRUE(std::isfinite(m["errors"]["l2_rel"].get<double>())) << method;
            EXPECT_TRUE(fs::exists(dir + "/out/" + method + "/summary.json")) << method;
        }
    }
    std::ifstream in(dir + "/out/report.md");
    const std::string report((std::istreambuf_iterator<char>(in)), {});
    EXPECT_THAT(report, HasSubstr("| naive | failed: "));
}

// A run into a folder that holds an earlier run's outputs replaces them: nothing of the
// comparison is left beside the single method's files, and the user's own files stay.
TEST(CliCoarsen, AFolderNeverMixesTwoRuns) {
    const std::string dir = temp_dir("cli_coarsen_rerun");
    const std::string scene = write_scene(dir, coarse_scene());
    const std::string out = dir + "/out";
    std::string output;
    ASSERT_EQ(run("COARSEGRAIN_PYTHON=false " + kCli +
                      " --quiet coarsen " + scene + " --method naive,mra-dirac --out " + out,
                  &output),
              0)
        << output;
    ASSERT_TRUE(fs::exists(out + "/report.md"));
    ASSERT_TRUE(fs::exists(out + "/mra-dirac/summary.json"));
    std::ofstream(out + "/notes.txt") << "mine";
    ASSERT_EQ(run(kCli + " --quiet coarsen " + scene + " --method naive --out " + out, &output), 0)
        << output;
    EXPECT_FALSE(fs::exists(out + "/report.md"));
    EXPECT_FALSE(fs::exists(out + "/report_data.json"));
    EXPECT_FALSE(fs::exists(out + "/naive"));
    EXPECT_FALSE(fs::exists(out + "/mra-dirac"));
    EXPECT_TRUE(fs::exists(out + "/solution_coarse.vtu"));
    EXPECT_TRUE(fs::exists(out + "/notes.txt"));
    EXPECT_EQ(read_json(out + "/summary.json")["method"], "naive");
    // The same for `solve`: its files replace the coarsening's.
    ASSERT_EQ(run(kCli + " --quiet solve " + scene + " --out " + out, &output), 0) << output;
    EXPECT_FALSE(fs::exists(out + "/solution_coarse.vtu"));
    EXPECT_FALSE(fs::exists(out + "/coarse_model.vtu"));
    EXPECT_TRUE(fs::exists(out + "/solution_fine.vtu"));
    EXPECT_TRUE(fs::exists(out + "/notes.txt"));
}

TEST(CliCoarsen, MethodListErrors) {
    const std::string dir = temp_dir("cli_coarsen_method_list");
    const std::string scene = write_scene(dir, coarse_scene());
    Result r = cli("coarsen " + scene + " --method naive,magic --out " + dir + "/out");
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.output, HasSubstr("unknown method 'magic'"));
    r = cli("coarsen " + scene + " --method naive,naive --out " + dir + "/out");
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.output, HasSubstr("'naive' is given twice"));
    r = cli("coarsen " + write_scene(dir, small_scene(), "plain.json") + " --method all --out " +
            dir + "/out");
    EXPECT_EQ(r.code, 1);
    EXPECT_THAT(r.output, HasSubstr("configures no method"));
    EXPECT_FALSE(fs::exists(dir + "/out/summary.json"));
    json blind = coarse_scene();
    blind["coarse"]["boundary_blind"] = "yes";
    r = cli("coarsen " + write_scene(dir, blind, "blind.json") + " --method all --out " + dir +
            "/out");
    EXPECT_EQ(r.code, 1);
    EXPECT_THAT(r.output, HasSubstr("coarse.boundary_blind: expected true or false, got \"yes\""));
    EXPECT_FALSE(fs::exists(dir + "/out/summary.json"));
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

/// Names of a VTU file's point or cell fields.
std::vector<std::string> field_names(const std::vector<io::Field>& fields) {
    std::vector<std::string> names;
    for (const io::Field& f : fields) names.push_back(f.name);
    return names;
}

// The effective-tensor method's own figures and files: the build phases timed separately
// (harmonic solves, intersections, tensor assembly), the coarse model with all 21
// Voigt entries, density and the directional Young's moduli per coarse element, and the fine
// mesh with the six harmonic displacements.
TEST(CliCoarsen, EffectiveTensorWritesItsPhasesAndFiles) {
    const std::string dir = temp_dir("cli_coarsen_et_files");
    const json s = run_method("effective-tensor", dir);
    for (const char* phase :
         {"intersect", "harmonic", "tensors", "assemble", "maps", "build", "factorize", "solve"})
        EXPECT_TRUE(s["coarse"]["timings"][phase].is_number()) << phase;
    for (const char* phase : {"assemble", "factorize", "solve"})
        EXPECT_TRUE(s["fine"]["timings"][phase].is_number()) << phase;
    for (const char* key : {"normals", "boundary", "map", "mollifier_condition", "overlaps"})
        EXPECT_TRUE(s["coarse"].contains(key)) << key;
    EXPECT_EQ(s["coarse"]["normals"], "coarse");  // the paper's recommendation is the default
    EXPECT_EQ(s["coarse"]["boundary"], "neumann");
    EXPECT_EQ(s["coarse"]["map"], "barycentric");
    EXPECT_TRUE(s["speedup"]["solve"].is_number());
    // The coarse grid's nodes are fine nodes (on the boundary and inside): none lies outside,
    // whatever the round-off of locating them.
    EXPECT_EQ(s["coarse"]["coarse_nodes_outside"], 0);

    const auto [coarse, cells] = io::read_vtu(dir + "/out/coarse_model.vtu");
    EXPECT_EQ(coarse.num_elements(), s["coarse"]["elements"].get<int>());
    const std::vector<std::string> names = field_names(cells.cell_data);
    auto has = [&](const std::string& name) {
        return std::find(names.begin(), names.end(), name) != names.end();
    };
    int tensor_entries = 0;
    for (int I = 1; I <= 6; ++I)
        for (int J = I; J <= 6; ++J) tensor_entries += has(fmt::format("C_voigt_{}{}", I, J));
    EXPECT_EQ(tensor_entries, 21);
    for (const char* name : {"density", "E_x", "E_y", "E_z", "G_condition"})
        EXPECT_TRUE(has(name)) << name;

    const auto [fine, harmonic] = io::read_vtu(dir + "/out/harmonic.vtu");
    EXPECT_EQ(fine.num_nodes() * 3, s["fine"]["dofs"].get<int>());
    EXPECT_EQ(field_names(harmonic.point_data),
              (std::vector<std::string>{"h_xx", "h_yy", "h_zz", "h_yz", "h_xz", "h_xy"}));
}

// The coarse model file is a mesh with one tensor and density per element: `coarsegrain solve`
// on a scene whose mesh is coarse_model.vtu (same boxes and loads, no fine mesh) reproduces the
// coarse solve of `coarsen` up to the load: the coarse model carries the fine load, P^T f, the
// file's scene applies gravity and traction to the coarse mesh again. The two agree where the
// density is constant in each coarse element (one density here) and the coarse tets' faces cut
// no fine element; here the tets' diagonal faces cut fine hexes. The probes lie on fine nodes,
// where the barycentric embedding is the coarse interpolant itself.
TEST(CliCoarsen, CoarseModelFileIsSolvedWithoutTheFineMesh) {
    const std::string dir = temp_dir("cli_coarsen_reload");
    json scene = coarse_scene();
    scene["materials"]["2"]["density"] = 1;
    const Result run = cli("coarsen " + write_scene(dir, scene) +
                           " --method effective-tensor --out " + dir + "/out");
    ASSERT_EQ(run.code, 0) << run.output;
    const json c = read_json(dir + "/out/summary.json");
    json j = small_scene();
    j.erase("material_field");
    j.erase("materials");
    j["mesh"] = {{"file", dir + "/out/coarse_model.vtu"}};
    const Result r =
        cli("solve " + write_scene(dir, j, "coarse_scene.json") + " --out " + dir + "/solve");
    ASSERT_EQ(r.code, 0) << r.output;
    const json s = read_json(dir + "/solve/summary.json");
    EXPECT_EQ(s["fine"]["elements"], c["coarse"]["elements"]);
    // The same K up to the Voigt round trip of the tensors (round-off); the loads differ in the
    // cut fine hexes: measured 5.5e-4 in compliance, 4.2e-4 of the largest displacement at the
    // probes.
    const double compliance = c["compliance"].get<double>();
    EXPECT_NEAR(s["compliance"].get<double>(), compliance, 2e-3 * std::abs(compliance));
    for (std::size_t p = 0; p < 2; ++p)
        for (std::size_t k = 0; k < 3; ++k) {
            const double u = c["probes"][p]["u"][k].get<double>();
            EXPECT_NEAR(s["probes"][p]["u"][k].get<double>(), u,
                        2e-3 * c["max_displacement"].get<double>())
                << "probe " << p << " component " << k;
        }
}

struct BadCoarseMesh {
    std::string name;
    std::function<json(const std::string& dir)> mesh;  ///< coarse.mesh, given a scratch folder
    std::string where;                                 ///< the key or file the message names
    std::string message;
};

class CliCoarsenBadMesh : public ::testing::TestWithParam<BadCoarseMesh> {};

// A coarse mesh the effective-tensor method cannot use stops the command with exit code 1 and
// one message naming coarse.mesh (or the coarse mesh file), before any file is written.
TEST_P(CliCoarsenBadMesh, FailsWithAClearMessageAndNoOutput) {
    const BadCoarseMesh& bad = GetParam();
    const std::string dir = temp_dir("cli_coarsen_bad_" + bad.name);
    json j = coarse_scene();
    j["coarse"]["mesh"] = bad.mesh(dir);
    const Result r = cli("coarsen " + write_scene(dir, j) + " --out " + dir + "/out");
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_THAT(r.output, HasSubstr("error: "));
    EXPECT_THAT(r.output, HasSubstr(bad.where));
    EXPECT_THAT(r.output, HasSubstr(bad.message));
    EXPECT_TRUE(!fs::exists(dir + "/out") || fs::is_empty(dir + "/out")) << "files left behind";
}

json grid_json(const std::vector<double>& min, const std::vector<double>& max) {
    return {{"grid", {{"min", min}, {"max", max}, {"cells", {2, 1, 1}}, {"element", "tet"}}}};
}

INSTANTIATE_TEST_SUITE_P(
    Cases, CliCoarsenBadMesh,
    ::testing::Values(
        // Covers x in [0, 1] of the bar [0, 2] x [0, 1] x [0, 1].
        BadCoarseMesh{"half_the_object",
                      [](const std::string&) {
                          return grid_json({0, 0, 0}, {1, 1, 1});
                      },
                      "coarse.mesh", "misses part of the object"},
        // The 12 tets of the covering grid plus a flat tet on four corners of the face z = 0.
        BadCoarseMesh{"degenerate_element",
                      [](const std::string& dir) {
                          mesh::Mesh m =
                              mesh::make_grid(mesh::ElementType::Tet4, Eigen::Vector3d(0, 0, 0),
                                              Eigen::Vector3d(2, 1, 1), Eigen::Vector3i(2, 1, 1));
                          const Index n = m.num_elements();
                          m.elements.conservativeResize(n + 1, 4);
                          m.elements.row(n) << 0, 1, 3, 4;  // (0,0,0) (1,0,0) (0,1,0) (1,1,0)
                          m.material_ids.conservativeResize(n + 1);
                          m.material_ids[n] = 0;
                          io::write_mesh(dir + "/coarse.vtu", m);
                          return json{{"file", dir + "/coarse.vtu"}};
                      },
                      "coarse.vtu", "element 12 is degenerate"},
        // The bar's coarse mesh in millimetres: 1000 times its size.
        BadCoarseMesh{"millimetres",
                      [](const std::string&) {
                          return grid_json({0, 0, 0}, {2000, 1000, 1000});
                      },
                      "coarse.mesh", "same units"},
        // The right size, moved away (another origin): it does not meet the object at all.
        BadCoarseMesh{"far_away",
                      [](const std::string&) {
                          return grid_json({100, 0, 0}, {102, 1, 1});
                      },
                      "coarse.mesh", "does not overlap the fine mesh at all"}),
    [](const auto& p) { return p.param.name; });

}  // namespace

// --export inp writes each element model as a CalculiX deck that ccx runs: its largest nodal
// displacement is the coarse solution's (coarsen's max_displacement: the barycentric map's
// largest displacement is at a coarse node), to ccx's 7 printed digits (2 units of the 7th).
TEST(CliCoarsen, ExportInpWritesDecksThatCalculixRuns) {
    const std::string dir = temp_dir("cli_coarsen_export");
    const Result r = cli("coarsen " + write_scene(dir, coarse_scene()) +
                         " --method effective-tensor,naive --export inp --out " + dir + "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    for (const char* method : {"effective-tensor", "naive"}) {
        const std::string sub = dir + "/out/" + method;
        ASSERT_TRUE(fs::exists(sub + "/coarse_model.inp")) << method;
        std::string output;
        ASSERT_EQ(run("cd " + sub + " && ccx -i coarse_model", &output), 0) << output;
        const std::vector<Matrix> blocks = read_ccx_displacements(sub + "/coarse_model.dat");
        ASSERT_EQ(blocks.size(), 1u) << method;
        const double largest = blocks[0].rowwise().norm().maxCoeff();
        const double expected = read_json(sub + "/summary.json")["max_displacement"].get<double>();
        EXPECT_NEAR(largest, expected, 2e-6 * expected) << method;
    }
}

// The hierarchy is no element model: --export inp writes its coarse operators as Matrix Market
// files, which Eigen's reader (as SciPy's, MATLAB's) reads back to the doubles written (17
// digits): K, f and the mass equal a rebuild of the same model, and the map carries a coarse
// vector as the model's does.
TEST(CliCoarsen, ExportWritesTheHierarchysMatricesAsMatrixMarket) {
    const std::string dir = temp_dir("cli_coarsen_export_mra");
    const std::string file = write_scene(dir, coarse_scene());
    const Result r = cli("coarsen " + file + " --method mra-linear --export inp --out " + dir +
                         "/out");
    ASSERT_EQ(r.code, 0) << r.output;
    const scene::Scene sc = scene::load_scene(file);
    const scene::FineModel fine = scene::build_fine_model(sc);
    const coarsen::CoarseModel model = coarsen::build_coarse_model(sc, fine, "mra-linear");
    SparseMatrix K, M, T;
    Vector f;
    ASSERT_TRUE(Eigen::loadMarket(K, dir + "/out/coarse_K.mtx"));
    ASSERT_TRUE(Eigen::loadMarket(M, dir + "/out/coarse_M.mtx"));
    ASSERT_TRUE(Eigen::loadMarket(T, dir + "/out/to_fine.mtx"));
    ASSERT_TRUE(Eigen::loadMarketVector(f, dir + "/out/coarse_f.mtx"));
    const SparseMatrix M_model = model.mass(
        fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent));
    // A rebuild differs from the exported run by the order of parallel sums only.
    EXPECT_LE((K - model.K).norm(), 1e-12 * model.K.norm());
    EXPECT_LE((M - M_model).norm(), 1e-12 * M_model.norm());
    EXPECT_LE((f - model.f).norm(), 1e-12 * model.f.norm());
    const Vector u = Vector::LinSpaced(model.K.rows(), -1, 2);
    EXPECT_LE((T * u - model.to_fine * u).norm(), 1e-12 * (model.to_fine * u).norm());
    EXPECT_FALSE(fs::exists(dir + "/out/coarse_model.inp"));
}
