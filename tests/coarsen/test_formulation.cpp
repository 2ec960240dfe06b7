// The scene's "fem": {"formulation": ..} through the pipeline: parsing, the fine model, its
// locking warnings, and the coarsening methods on the incompatible element's fine stiffness.
#include <gtest/gtest.h>

#include <cmath>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

// A 4 x 1 x 1 hex beam, layers of E = 1000 (nu 0.3) and E = 50 (nu = 0.499) across its axis,
// clamped at x = 0 under gravity; a coarse tet grid for the effective tensors, 2 levels for mra.
nlohmann::json layered_beam(const std::string& element, const std::string& formulation) {
    nlohmann::json j = {
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}}, {"max", {4, 1, 1}}, {"cells", {16, 4, 4}}, {"element", element}}}}},
        {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.5}, {"ids", {1, 2}}}}}},
        {"materials",
         {{"1", {{"E", 1000.0}, {"nu", 0.3}, {"density", 1.0}}},
          {"2", {{"E", 50.0}, {"nu", 0.499}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1, -1, -1}}, {"max", {1e-9, 2, 2}}}}}}},
        {"loads", {{"gravity", {0, 0, -1}}}},
        {"coarse",
         {{"mesh",
           {{"grid",
             {{"min", {0, 0, 0}}, {"max", {4, 1, 1}}, {"cells", {4, 1, 1}}, {"element", "tet"}}}}},
          {"levels", 2},
          {"cell_tensors", true},
          {"spectrum_max_dofs", 0}}}};
    if (!formulation.empty()) j["fem"] = {{"formulation", formulation}};
    return j;
}

TEST(SceneFormulation, ParsedAndCheckedAgainstTheElementType) {
    EXPECT_EQ(scene::parse_scene(layered_beam("hex", ""), "beam", "").formulation,
              fem::Formulation::Standard);
    EXPECT_EQ(scene::parse_scene(layered_beam("hex", "incompatible"), "beam", "").formulation,
              fem::Formulation::Incompatible);
    EXPECT_EQ(scene::parse_scene(layered_beam("hex", "standard"), "beam", "").formulation,
              fem::Formulation::Standard);
    test::expect_error([] { scene::parse_scene(layered_beam("tet", "incompatible"), "beam", ""); },
                       "beam: fem.formulation: \"incompatible\" does not apply to tet elements; "
                       "expected \"standard\" (any element) or \"incompatible\" (hex and quad "
                       "elements only)");
    test::expect_error([] { scene::parse_scene(layered_beam("hex", "bbar"), "beam", ""); },
                       "beam: fem.formulation: unknown formulation \"bbar\"; expected "
                       "\"standard\" or \"incompatible\"");
    nlohmann::json typo = layered_beam("hex", "");
    typo["fem"] = {{"formulations", "incompatible"}};
    test::expect_error([&] { scene::parse_scene(typo, "beam", ""); }, "fem.formulations");
}

// The fine stiffness is the incompatible element's, and its solution differs from the
// standard one (material 2 locks): the fine solution of every command is the new element's.
TEST(SceneFormulation, FineModelUsesTheFormulation) {
    const scene::Scene sc = scene::parse_scene(layered_beam("hex", "incompatible"), "beam", "");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const SparseMatrix K = fem::stiffness_matrix(fine.mesh, fine.materials,
                                                 fem::Formulation::Incompatible);
    EXPECT_EQ((fine.K - K).norm(), 0.0);  // the same assembly, bit for bit
    const scene::Scene sc_std = scene::parse_scene(layered_beam("hex", ""), "beam", "");
    const Vector u = scene::solve_static(fine, sc.solver).u;
    const Vector u_std = scene::solve_static(scene::build_fine_model(sc_std), sc.solver).u;
    // Softer: the standard element locks in the nu = 0.499 layers (measured 1.4x here).
    EXPECT_GT(u.lpNorm<Eigen::Infinity>(), 1.1 * u_std.lpNorm<Eigen::Infinity>());
}

// One warning per locking material, with its id, nu and the measured error; none for the
// incompatible hex at nu = 0.499 (it does not lock there), for plane stress and for materials
// below the threshold.
TEST(SceneFormulation, LockingWarnings) {
    const scene::FineModel std_fine =
        scene::build_fine_model(scene::parse_scene(layered_beam("hex", ""), "beam", ""));
    ASSERT_EQ(std_fine.warnings.size(), 1u);
    EXPECT_EQ(std_fine.warnings[0],
              "material 2: nu = 0.499: standard hex elements lock (tip deflection error ~40% on "
              "a 32x8x8 cantilever, 1.3% at nu = 0.3); use \"fem\": {\"formulation\": "
              "\"incompatible\"}");
    EXPECT_TRUE(scene::build_fine_model(
                    scene::parse_scene(layered_beam("hex", "incompatible"), "beam", ""))
                    .warnings.empty());
    const scene::FineModel tets =
        scene::build_fine_model(scene::parse_scene(layered_beam("tet", ""), "beam", ""));
    ASSERT_EQ(tets.warnings.size(), 1u);
    EXPECT_NE(tets.warnings[0].find("material 2: nu = 0.499: standard tet elements lock"),
              std::string::npos);
    EXPECT_NE(tets.warnings[0].find("quadratic tets are not available: use a finer mesh, or hex "
                                    "elements with \"fem\": {\"formulation\": \"incompatible\"}"),
              std::string::npos);
    // The incompatible hex beyond the measured range: a mild lock, "at least".
    nlohmann::json extreme = layered_beam("hex", "incompatible");
    extreme["materials"]["2"]["nu"] = 0.4999999;
    const scene::FineModel ex = scene::build_fine_model(scene::parse_scene(extreme, "beam", ""));
    ASSERT_EQ(ex.warnings.size(), 1u);
    EXPECT_NE(ex.warnings[0].find("incompatible hex elements lock mildly (tip deflection error at "
                                  "least"),
              std::string::npos);
    // 2D: plane strain warns, plane stress has no incompressibility constraint.
    nlohmann::json plate = {
        {"mesh", {{"grid", {{"min", {0, 0}}, {"max", {4, 1}}, {"cells", {8, 2}}}}}},
        {"materials", {{"0", {{"E", 1.0}, {"nu", 0.49}, {"density", 1.0}}}}}};
    const scene::FineModel strain = scene::build_fine_model(scene::parse_scene(plate, "p", ""));
    ASSERT_EQ(strain.warnings.size(), 1u);
    EXPECT_NE(strain.warnings[0].find("material 0: nu = 0.49: standard quad elements lock (tip "
                                      "deflection error ~20% on a 32x8 plane-strain cantilever"),
              std::string::npos);
    plate["plane"] = "stress";
    EXPECT_TRUE(scene::build_fine_model(scene::parse_scene(plate, "p", "")).warnings.empty());
    plate["plane"] = "strain";
    plate["materials"]["0"]["nu"] = 0.4;  // below the threshold (growth < 5 points)
    EXPECT_TRUE(scene::build_fine_model(scene::parse_scene(plate, "p", "")).warnings.empty());
}

// The coarsening methods take the fine K as it is: effective-tensor (its harmonic problems on
// the tet split of the fine mesh, its comparison on the incompatible fine solution) and the
// hierarchy (built from the incompatible K) run and give finite errors, and the reference they are compared with is the
// incompatible element's fine solution.
TEST(SceneFormulation, CoarseningMethodsRunOnTheIncompatibleElement) {
    const scene::Scene sc = scene::parse_scene(layered_beam("hex", "incompatible"), "beam", "");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const Vector u = scene::solve_static(fine, sc.solver).u;
    for (const std::string method : {"effective-tensor", "reuss", "mra-linear", "mra-dirac"}) {
        const coarsen::CoarseModel model = coarsen::build_coarse_model(sc, fine, method);
        const coarsen::CoarseSolution uc = coarsen::solve_coarse(model, sc.solver);
        const coarsen::Errors e = coarsen::compare(fine, u, uc.u_fine);
        EXPECT_TRUE(std::isfinite(e.energy_rel) && std::isfinite(e.l2_rel) &&
                    std::isfinite(e.compliance_ratio) && std::isfinite(e.stress_rel))
            << method;
        EXPECT_GT(e.compliance_ratio, 0.0) << method;
        // The hierarchy's coarsest level is the Galerkin projection of the incompatible K: its
        // compliance cannot exceed the fine one (energy minimization), up to round-off.
        if (method.starts_with("mra")) {
            EXPECT_LE(e.compliance_ratio, 1.0 + 1e-9) << method;
        }
    }
}

}  // namespace
}  // namespace coarsegrain
