#pragma once
/// @file The reduced-size runs of the examples (examples/<name>/) that CI asserts numbers on.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "test_util.hpp"

namespace coarsegrain::test {

/// A run of an example: the top `summary.json` of `coarsen` or `simulate --method ...` (one
/// method, a list, or `all`).
struct ExampleRun {
    nlohmann::json summary;
    std::string out;  ///< the output folder

    /// The `errors` object of method `name` (fails the test if the method did not run).
    const nlohmann::json& errors(const std::string& name) const {
        if (summary.value("method", "") == name) return summary.at("errors");  // one method alone
        if (summary.contains("methods"))
            for (const nlohmann::json& m : summary.at("methods"))
                if (m.at("method") == name) return m.at("errors");
        ADD_FAILURE() << "no method " << name << " in " << out << "/summary.json";
        static const nlohmann::json none = nlohmann::json::object();
        return none;
    }
    double error(const std::string& name, const std::string& key) const {
        return errors(name).at(key).get<double>();
    }
    /// The `summary.json` of method `name`'s own folder.
    nlohmann::json method_summary(const std::string& name) const {
        std::ifstream in(out + "/" + name + "/summary.json");
        return nlohmann::json::parse(in);
    }
};

/// Chen et al. 2019, Fig. 9: the energy error ||u^k - u||_A / ||u||_A of the single-level solve
/// of an mra method falls at every step from the coarsest level to the finest.
inline void expect_error_falls_with_level(const ExampleRun& r, const std::string& method) {
    const nlohmann::json levels = r.method_summary(method).at("coarse").at("levels");
    ASSERT_GE(levels.size(), 2u) << method;
    for (std::size_t k = 1; k < levels.size(); ++k)
        EXPECT_LT(levels[k].at("error_over_u").get<double>(),
                  levels[k - 1].at("error_over_u").get<double>())
            << method << ", level " << k + 1;
}

/// The coarse model of an mra method (hierarchy with the "constrain" treatment) is a Galerkin
/// projection of the fine problem: u_c is the K-orthogonal projection of u, so
/// ||u - u_c||_K^2 = ||u||_K^2 - ||u_c||_K^2 and f.u_c = ||u_c||_K^2, that is compliance_ratio =
/// 1 - energy_rel^2 <= 1. `tolerance` (absolute) allows the round-off of the fine and coarse
/// solves, which grows with the condition number of K: 1e-9 by default (the fine level solved
/// twice differs by ~1e-11 in the compliance ratio on a contrast of 5e4).
inline void expect_galerkin_projection(const ExampleRun& r, const std::string& method,
                                       double tolerance = 1e-9) {
    const double e = r.error(method, "energy_rel"), ratio = r.error(method, "compliance_ratio");
    EXPECT_NEAR(ratio, 1.0 - e * e, tolerance) << method;
    EXPECT_LE(ratio, 1.0 + tolerance) << method;
}

/// Runs examples/<name>/<name>.json with `patch` merged into it (RFC 7386: the reduced size), as
/// `coarsegrain coarsen --method methods` (`simulate` if the scene has a "dynamics" block, as
/// examples/run_all does), in a fresh temporary folder holding a copy of the
/// example's files. An example with a
/// `make_mesh` script first makes its meshes there with the mesh size scaled by `mesh_factor`
/// (the factor is not passed when it is 1). The pictures are not made (COARSEGRAIN_PYTHON=false):
/// tests/cli checks them on the demo.
inline ExampleRun run_example(const std::string& name, const nlohmann::json& patch,
                              const std::string& methods = "all", double mesh_factor = 1.0) {
    namespace fs = std::filesystem;
    const fs::path example = fs::path(COARSEGRAIN_EXAMPLES) / name;
    const std::string dir = temp_dir("example_" + name);
    // The example's other files (images) beside the scene: its relative paths hold.
    for (const fs::directory_entry& f : fs::directory_iterator(example))
        if (f.is_regular_file()) fs::copy_file(f.path(), dir / f.path().filename());
    if (fs::exists(example / "make_mesh")) {
        std::string output;
        const std::string factor = mesh_factor == 1.0 ? "" : fmt::format(" {}", mesh_factor);
        const int code =
            run(fmt::format("{} {}{}", (example / "make_mesh").string(), dir, factor), &output);
        EXPECT_EQ(code, 0) << output;
    }
    std::ifstream in(example / (name + ".json"));
    nlohmann::json scene = nlohmann::json::parse(in);
    scene.merge_patch(patch);
    const std::string file = dir + "/" + name + ".json";
    std::ofstream(file) << scene.dump(2);
    ExampleRun r;
    r.out = dir + "/out";
    std::string output;
    std::string command = "COARSEGRAIN_PYTHON=false " COARSEGRAIN_CLI " --quiet ";
    command += scene.contains("dynamics") ? "simulate " : "coarsen ";
    command += file + " --method " + methods + " --out " + r.out;
    const int code = run(command, &output);
    EXPECT_EQ(code, 0) << output;
    if (code == 0) {
        std::ifstream s(r.out + "/summary.json");
        r.summary = nlohmann::json::parse(s);
    }
    return r;
}

}  // namespace coarsegrain::test
