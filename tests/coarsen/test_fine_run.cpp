// coarsen::solve_fine / run_method (one method's run as the CLI does it), scenes with meshes
// given directly, with_coarse_overrides and request_interrupt.
#include <gtest/gtest.h>

#include "coarsegrain/coarsen/fine_run.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/mesh/grid.hpp"

namespace coarsegrain {
namespace {

scene::Scene demo_beam() { return scene::parse_scene(scene::demo_scene(0.25), "demo", ""); }

// run_method is build_coarse_model, solve_coarse and compare, step by step: the same numbers.
TEST(FineRun, RunMethodIsItsStepsOneByOne) {
    const scene::Scene sc = demo_beam();
    coarsen::FineRun run = coarsen::solve_fine(sc, scene::build_fine_model(sc), {"naive"});
    const coarsen::MethodRun r = coarsen::run_method(sc, run, "naive");

    const scene::FineModel fine = scene::build_fine_model(sc);
    const scene::StaticSolution u = scene::solve_static(fine, sc.solver);
    const coarsen::CoarseModel model = coarsen::build_coarse_model(sc, fine, "naive");
    const coarsen::CoarseSolution uc = coarsen::solve_coarse(model, sc.solver);
    const coarsen::Errors e = coarsen::compare(fine, u.u, uc.u_fine);
    // the same operations on the same data: equal to round-off of the solves' reductions
    EXPECT_NEAR(r.errors.energy_rel, e.energy_rel, 1e-12 * e.energy_rel);
    EXPECT_NEAR(r.errors.l2_rel, e.l2_rel, 1e-12 * e.l2_rel);
    EXPECT_NEAR(r.errors.stress_rel, e.stress_rel, 1e-12 * e.stress_rel);
    EXPECT_LE((r.solution.u_fine - uc.u_fine).norm(), 1e-12 * uc.u_fine.norm());
    EXPECT_LE((run.solution.u - u.u).norm(), 1e-12 * u.u.norm());
    ASSERT_NE(r.model.to_fine.matrix(), nullptr);  // the baselines' map is a matrix
    EXPECT_LE((*r.model.to_fine.matrix() * r.solution.u - r.solution.u_fine).norm(),
              1e-12 * uc.u_fine.norm());
    const nlohmann::json j = coarsen::errors_json(r.errors);
    EXPECT_EQ(j.size(), 6u);
    EXPECT_EQ(j.at("compliance_ratio").get<double>(), r.errors.compliance_ratio);
}

// With "warp": "rs" the fine and the coarse solution are post-warped; the linear fine solution
// is kept beside the warped one.
TEST(FineRun, WarpedSceneWarpsBothSolutions) {
    nlohmann::json j = scene::demo_scene(0.25);
    j["warp"] = "rs";
    const scene::Scene sc = scene::parse_scene(j, "demo", "");
    coarsen::FineRun run = coarsen::solve_fine(sc, scene::build_fine_model(sc), {"naive"});
    ASSERT_TRUE(run.linear.has_value());
    ASSERT_TRUE(run.warp != nullptr);
    EXPECT_LE(((*run.warp)(run.linear->u) - run.solution.u).norm(), 1e-12 * run.solution.u.norm());
    Timings t;
    const coarsen::MethodRun r = coarsen::run_method(sc, run, "naive", &t);
    const coarsen::CoarseSolution linear = coarsen::solve_coarse(r.model, sc.solver);
    EXPECT_LE(((*run.warp)(linear.u_fine) - r.solution.u_fine).norm(),
              1e-12 * r.solution.u_fine.norm());
    EXPECT_GT(t["warp"], 0.0);
}

TEST(FineRun, CoarseOverridesAreValidatedAsInTheFile) {
    const scene::Scene sc = demo_beam();
    const scene::Scene two = scene::with_coarse_overrides(sc, {{"levels", 2}});
    EXPECT_EQ(two.coarse.mra.levels, 2);
    EXPECT_EQ(two.coarse_block.at("levels"), 2);
    ASSERT_TRUE(two.coarse.mesh.has_value());  // kept
    EXPECT_EQ(two.coarse.mesh->num_elements(), sc.coarse.mesh->num_elements());
    nlohmann::json j = scene::demo_scene(0.25);
    j["coarse"]["levels"] = 2;
    EXPECT_EQ(scene::parse_scene(j, "demo", "").coarse.mra.levels, 2);
    try {
        scene::with_coarse_overrides(sc, {{"level", 2}});
        FAIL() << "an unknown key was accepted";
    } catch (const InvalidScene& e) {
        EXPECT_NE(std::string(e.what()).find("coarse.level"), std::string::npos) << e.what();
    }
    EXPECT_THROW(scene::with_coarse_overrides(sc, {{"levels", 0}}), InvalidScene);
    const scene::Scene mesh = scene::with_coarse_overrides(
        sc,
        {{"mesh",
          {{"grid",
            {{"min", {0, 0, 0}}, {"max", {4, 1, 1}}, {"cells", {2, 1, 1}}, {"element", "tet"}}}}}});
    EXPECT_EQ(mesh.coarse.mesh->num_elements(), 2 * 6);
}

// A mesh given directly (the grid itself, or one tensor per element) makes the same model.
TEST(FineRun, GivenMeshesMakeTheSameModel) {
    const scene::Scene sc = demo_beam();
    nlohmann::json j = scene::demo_scene(0.25);
    j.erase("mesh");
    scene::GivenMeshes given;
    given.mesh = sc.mesh;
    given.mesh->grid.reset();  // no grid: every element's matrix is computed
    const scene::Scene direct = scene::parse_scene(j, "given", "", given);
    const SparseMatrix K = scene::build_fine_model(sc).K, Kd = scene::build_fine_model(direct).K;
    // the grid's congruent elements share one element matrix; round-off apart
    EXPECT_LE((K - Kd).norm(), 1e-12 * K.norm());

    j.erase("materials");
    j.erase("material_field");
    given.element_materials.clear();
    for (Index e = 0; e < sc.mesh.num_elements(); ++e) {
        given.element_materials[e] = sc.materials.at(sc.mesh.material_ids[e]);
        given.mesh->material_ids[e] = e;
    }
    const scene::Scene per_element = scene::parse_scene(j, "given", "", given);
    EXPECT_LE((K - scene::build_fine_model(per_element).K).norm(), 1e-12 * K.norm());

    nlohmann::json both = scene::demo_scene(0.25);
    EXPECT_THROW(scene::parse_scene(both, "given", "", given), InvalidScene);
    given.mesh->elements(0, 0) = given.mesh->elements(0, 1);  // degenerate
    EXPECT_THROW(scene::parse_scene(j, "given", "", given), InvalidScene);
}

TEST(FineRun, InterruptStopsAtTheNextPhase) {
    request_interrupt();
    EXPECT_TRUE(interrupt_requested());
    EXPECT_THROW(Phase("work"), Interrupted);
    const scene::Scene sc = demo_beam();
    EXPECT_THROW(scene::build_fine_model(sc), Interrupted);
    clear_interrupt();
    EXPECT_FALSE(interrupt_requested());
    Timings t;
    { const Phase p("work", &t); }
    EXPECT_EQ(t.entries().size(), 1u);
}

}  // namespace
}  // namespace coarsegrain
