// Scene input that used to crash, hang or be misread: each is rejected with a message naming
// the file and the key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "../fuzz/load_fuzz_scene.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

json plate() {
    return json::parse(R"({
      "mesh": { "grid": { "min": [0, 0], "max": [2, 1], "cells": [4, 2], "element": "quad" } },
      "materials": { "1": { "E": 100, "nu": 0.3, "density": 1 } },
      "dirichlet": [ { "box": { "min": [-1, -1], "max": [0, 2] } } ],
      "loads": { "gravity": [0, -1] }
    })");
}

scene::Scene parse_text(const std::string& text) {
    return scene::parse_scene(scene::parse_json(text, "s.json"), "s.json", "");
}

TEST(SceneInput, GridSizesAreCheckedIn64BitBeforeAnyAllocation) {
    // (65535 + 1)^2 nodes overflowed the 32-bit node count (a crash); 46341^2 and 1291^3 cells
    // gave negative sizes; 2^32 + 1 was narrowed to 1.
    const struct {
        std::vector<std::int64_t> cells;
        const char* element;
        const char* message;
    } cases[] = {
        {{65535, 65535}, "quad", "mesh.grid.cells: 4294967296 nodes make 8589934592 DOFs"},
        {{46341, 46341}, "quad", "more than the 2147483647 that 32-bit indices hold"},
        {{1291, 1291, 1291}, "hex", "mesh.grid.cells: 2156689088 nodes make 6470067264 DOFs"},
        {{4294967297, 8}, "quad", "mesh.grid.cells[0]: expected an integer in [1, 100000], got "
                                  "4294967297"},
        {{-3, 8}, "quad", "mesh.grid.cells[0]: expected an integer in [1, 100000], got -3"},
    };
    for (const auto& c : cases) {
        json j = plate();
        const bool three = c.cells.size() == 3;
        j["mesh"]["grid"] = {{"min", three ? json{0, 0, 0} : json{0, 0}},
                             {"max", three ? json{1, 1, 1} : json{1, 1}},
                             {"cells", c.cells},
                             {"element", c.element}};
        test::expect_error([&] { scene::parse_scene(j, "s.json", ""); }, c.message);
    }
    // A grid that fits the indices but no machine: 600^3 hexes (651M DOFs) need about 633 GB of
    // stiffness.
    json j = plate();
    j["mesh"]["grid"] = {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"cells", {600, 600, 600}}};
    test::expect_error([&] { scene::parse_scene(j, "s.json", ""); }, "GB, more than this machine");
}

TEST(SceneInput, DuplicateKeysAreRejectedWithTheirPath) {
    test::expect_error(
        [] {
            parse_text(R"({"materials": {"0": {"E": 100, "nu": 0.3, "density": 1},
                                         "0": {"E": 5, "nu": 0.3, "density": 1}}})");
        },
        "s.json: materials.0: the key is given twice");
    test::expect_error([] { parse_text(R"({"dirichlet": [{"box": {}}, {"box": {"min": 1, "min": 2}}]})"); },
                       "s.json: dirichlet[1].box.min: the key is given twice");
    test::expect_error([] { parse_text(R"({"a": [[1, 2], {"b": 1}], "c": {"d": [], "d": 0}})"); },
                       "s.json: c.d: the key is given twice");
    // The same key in sibling objects is not a duplicate.
    EXPECT_EQ(scene::parse_json(R"({"a": {"k": 1}, "b": {"k": 2}, "c": [{"k": 1}, {"k": 2}]})", "s")
                  .size(),
              3u);
}

TEST(SceneInput, MaterialIdsAreCanonicalIntegers) {
    for (const char* key : {"01", "+1", "1.0", " 1", "x"}) {
        json j = plate();
        j["materials"] = {{key, {{"E", 100}, {"nu", 0.3}, {"density", 1}}}};
        test::expect_error([&] { scene::parse_scene(j, "s.json", ""); },
                           fmt::format("s.json: materials.{}: material keys must be integer ids",
                                       key));
    }
}

TEST(SceneInput, NumbersBeyondDoubleRangeAreInvalidJson) {
    test::expect_error([] { parse_text(R"({"loads": {"gravity": [0, 0, 1e400]}})"); },
                       "s.json: not valid JSON");
}

TEST(SceneInput, FilesMustBeRegular) {
    const std::string dir = test::temp_dir("scene_files");
    const std::string fifo = dir + "/fifo.raw";
    fs::remove(fifo);
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    // A FIFO or /dev/zero used to be read whole (forever) before any size check.
    for (const std::string& file : {std::string("/dev/zero"), fifo, dir}) {
        json j = plate();
        j["dimension"] = 3;
        j["mesh"]["grid"] = {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"cells", {2, 2, 2}}};
        j["material_field"] = {{"voxels", {{"file", file}, {"dims", {2, 2, 2}}}}};
        test::expect_error([&] { scene::parse_scene(j, "s.json", ""); },
                           "s.json: material_field.voxels.file: " + file +
                               " is not a regular file");
        json m = plate();
        m["mesh"] = {{"file", file}};
        test::expect_error([&] { scene::parse_scene(m, "s.json", ""); },
                           "s.json: mesh.file: " + file + " is not a regular file");
    }
    json j = plate();
    j["dimension"] = 3;
    j["mesh"]["grid"] = {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"cells", {2, 2, 2}}};
    j["material_field"] = {{"voxels", {{"file", "nonexist.raw"}, {"dims", {2, 2, 2}}}}};
    test::expect_error([&] { scene::parse_scene(j, "s.json", dir); },
                       "s.json: material_field.voxels.file: file " + dir +
                           "/nonexist.raw does not exist");
    std::ofstream(dir + "/short.raw") << "abc";
    j["material_field"]["voxels"]["file"] = "short.raw";
    test::expect_error([&] { scene::parse_scene(j, "s.json", dir); },
                       "short.raw has 3 bytes, expected 2x2x2 = 8 (one byte per voxel)");
    test::expect_error([] { scene::load_scene("/dev/zero"); },
                       "cannot open scene file /dev/zero: not a regular file");
}

TEST(SceneInput, PlaneAppliesToIsotropic2DMaterialsOnly) {
    json j = plate();
    j["plane"] = "stress";
    j["materials"]["1"] = {{"C_voigt", {{10, 3, 0}, {3, 10, 0}, {0, 0, 4}}}, {"density", 1}};
    test::expect_error([&] { scene::parse_scene(j, "s.json", ""); },
                       "s.json: plane: applies to isotropic materials (E, nu) only, but material "
                       "1 is anisotropic");
    json k = plate();
    k["plane"] = "strain";
    k["mesh"]["grid"] = {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"cells", {1, 1, 1}}};
    k["dirichlet"][0]["box"] = {{"min", {-1, -1, -1}}, {"max", {0, 2, 2}}};
    k["loads"]["gravity"] = {0, 0, -1};
    test::expect_error([&] { scene::parse_scene(k, "s.json", ""); },
                       "s.json: plane: applies to 2D scenes only");
}

TEST(SceneInput, RootLevelErrorsNameNoEmptyKey) {
    json j = plate();
    j.erase("materials");
    try {
        scene::parse_scene(j, "plate.json", "");
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_THAT(e.what(), ::testing::StartsWith("plate.json: no materials"));
    }
}

// A singular fine model says why: here a part of the mesh no Dirichlet box touches, named by
// its size and centre.
TEST(SceneInput, SingularModelsNameTheirCause) {
    const std::string dir = test::temp_dir("scene_singular");
    {
        std::ofstream mesh(dir + "/two_blocks.mesh");
        mesh << "MeshVersionFormatted 1\nDimension 3\nVertices\n16\n";
        for (const double x0 : {0.0, 3.0})
            for (int k = 0; k < 2; ++k)
                for (int j = 0; j < 2; ++j)
                    for (int i = 0; i < 2; ++i) mesh << x0 + i << " " << j << " " << k << " 0\n";
        mesh << "Hexahedra\n2\n1 2 4 3 5 6 8 7 1\n9 10 12 11 13 14 16 15 1\nEnd\n";
    }
    json j = json::parse(R"({
      "mesh": { "file": "two_blocks.mesh" },
      "materials": { "1": { "E": 100, "nu": 0.3, "density": 1 } },
      "dirichlet": [ { "box": { "min": [-1, -1, -1], "max": [0, 2, 2] } } ],
      "loads": { "gravity": [0, 0, -1] }
    })");
    const scene::Scene free = scene::parse_scene(j, "two.json", dir);
    test::expect_error([&] { scene::solve_static(scene::build_fine_model(free), {}); },
                       "two.json: the fine model is singular: part 2 of the mesh's 2 connected "
                       "parts (8 nodes, centred at (3.5, 0.5, 0.5)) has no Dirichlet node");
    // Both blocks held, the second at the two nodes of one edge: it turns about that edge.
    j["dirichlet"].push_back({{"box", {{"min", {2.5, -1, -1}}, {"max", {4.5, 0.5, 0.5}}}}});
    const scene::Scene hinged = scene::parse_scene(j, "two.json", dir);
    test::expect_error([&] { scene::solve_static(scene::build_fine_model(hinged), {}); },
                       "two.json: the fine model is singular: part 2 of the mesh's 2 connected "
                       "parts (8 nodes, centred at (3.5, 0.5, 0.5)) has 6 fixed DOFs, which do "
                       "not stop all its rigid motions");
}

// A body held against every rigid motion whose materials span a contrast of 1e15: the message
// blames the contrast (and gives it), not the Dirichlet conditions, for the factorization and
// for conjugate gradients, and does not advise another solver.
TEST(SceneInput, SingularAtExtremeContrastBlamesTheContrast) {
    json j = {
        {"dimension", 2},
        {"mesh",
         {{"grid", {{"min", {0, 0}}, {"max", {1, 1}}, {"cells", {16, 16}}, {"element", "quad"}}}}},
        {"material_field", {{"checkerboard", {{"size", 0.25}, {"ids", {1, 2}}}}}},
        {"materials",
         {{"1", {{"E", 1e-6}, {"nu", 0.3}, {"density", 1}}},
          {"2", {{"E", 1e9}, {"nu", 0.3}, {"density", 1}}}}},
        {"dirichlet", {{{"box", {{"min", {-1, 0.999}}, {"max", {2, 2}}}}}}},
        {"loads", {{"gravity", {0, -1}}}}};
    for (const std::string backend : {"cholmod", "cg"}) {
        j["solver"] = {{"backend", backend}};
        const scene::Scene sc = scene::parse_scene(j, "checker.json", "");
        try {
            scene::solve_static(scene::build_fine_model(sc), sc.solver);
            ADD_FAILURE() << backend << ": expected an error";
        } catch (const NotPositiveDefinite& e) {
            const std::string what = e.what();
            EXPECT_THAT(what, ::testing::HasSubstr(
                                  "is held against all its rigid motions, so the Dirichlet "
                                  "conditions are not missing: K is numerically singular at the "
                                  "materials' stiffness contrast of 1e+15 (Young's moduli 1e-06 "
                                  "to 1e+09)"))
                << backend;
            EXPECT_THAT(what, ::testing::Not(::testing::HasSubstr("enough Dirichlet"))) << what;
            EXPECT_THAT(what, ::testing::Not(::testing::HasSubstr("use cholmod"))) << what;
        }
    }
}

std::vector<std::uint8_t> file_bytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The fuzz target's seeds (the examples' scenes and two more) load but for missing files; the
// inputs it once crashed on now load or throw coarsegrain::Error, and nothing else (the
// sanitizer build runs this too).
TEST(SceneInput, FuzzSeedsLoadAndRegressionsAreReported) {
    const fs::path root = fs::path(COARSEGRAIN_TEST_DATA) / ".." / "..";
    int seeds = 0;
    for (const auto& entry : fs::directory_iterator(root / "fuzz" / "corpus_scene")) {
        const std::vector<std::uint8_t> bytes = file_bytes(entry.path());
        // Examples whose meshes or images their own scripts make name files that are not here.
        try {
            fuzz::load_fuzz_scene(bytes.data(), bytes.size(), COARSEGRAIN_TEST_DATA);
        } catch (const Error& e) {
            EXPECT_THAT(e.what(), ::testing::HasSubstr("does not exist")) << entry.path();
        }
        ++seeds;
    }
    EXPECT_GE(seeds, 10);
    int regressions = 0;
    for (const auto& entry :
         fs::directory_iterator(fs::path(COARSEGRAIN_TEST_DATA) / "fuzz_regressions_scene")) {
        if (entry.path().extension() == ".md") continue;
        const std::vector<std::uint8_t> bytes = file_bytes(entry.path());
        try {
            fuzz::load_fuzz_scene(bytes.data(), bytes.size(), COARSEGRAIN_TEST_DATA);
        } catch (const Error&) {
        }
        ++regressions;
    }
    EXPECT_GE(regressions, 2);
}

}  // namespace
}  // namespace coarsegrain
