// Coarse models in time and frequency: identities that must hold to round-off.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/sim/modes.hpp"
#include "sim/layered_bar.hpp"

using namespace coarsegrain;
using nlohmann::json;

namespace {

json grid(const char* element, std::vector<int> cells) {
    return {
        {"grid", {{"min", {0, 0, 0}}, {"max", {3, 1, 1}}, {"cells", cells}, {"element", element}}}};
}

/// A homogeneous clamped bar under gravity whose coarse mesh is its own mesh.
scene::Scene identity_scene(const char* coarse_mass) {
    return scene::parse_scene(
        {{"mesh", grid("tet", {6, 2, 2})},
         {"materials", {{"0", {{"E", 100.0}, {"nu", 0.3}, {"density", 2.0}}}}},
         {"dirichlet", {{{"box", {{"min", {-1e-9, -1, -1}}, {"max", {1e-9, 2, 2}}}}}}},
         {"loads", {{"gravity", {0, 0, -1}}}},
         {"coarse", {{"mesh", grid("tet", {6, 2, 2})}, {"mass", coarse_mass}}},
         {"dynamics", {{"dt", 0.05}, {"steps", 60}}}},
        "identity.json", "");
}

}  // namespace

// On a homogeneous body the harmonic displacements are affine, so the effective tensor of every
// element is the material's; with the coarse mesh equal to the fine one the barycentric map is
// the identity, the Galerkin mass PᵀMP the consistent fine mass and the lumped mass Pᵀ(M1) the
// fine lumped one. The coarse model is then the fine model: same trajectory and frequencies to
// round-off (1e-10 relative; the tensors carry ~1e-13 from the harmonic solves).
TEST(CoarseDynamics, CoarseMeshEqualToTheFineMeshGivesTheFineDynamics) {
    for (const auto& [coarse_mass, fine_mass] : {std::pair{"galerkin", fem::MassType::Consistent},
                                                 std::pair{"lumped", fem::MassType::Lumped}}) {
        const scene::Scene sc = identity_scene(coarse_mass);
        const scene::FineModel fine = scene::build_fine_model(sc);
        const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fine_mass);
        const coarsen::CoarseModel c = coarsen::build_coarse_model(sc, fine, "effective-tensor");
        const SparseMatrix Mc = c.mass(M);
        const sim::DynamicsOptions& o = *sc.dynamics;
        const auto [s, f] = sim::initial_state(fine.K, fine.f, fine.bc, Vector(), o);
        const auto [sc0, fc] = sim::initial_state(c.K, c.f, c.bc, Vector(), o);
        const sim::Trajectory tf = sim::simulate(fine.K, M, fine.bc, s, f, o);
        const sim::Trajectory tc = sim::simulate(c.K, Mc, c.bc, sc0, fc, o);
        double worst = 0, scale = 0;
        for (std::size_t i = 0; i < tf.u.size(); ++i) {
            worst = std::max(worst, (c.to_fine * tc.u[i] - tf.u[i]).lpNorm<Eigen::Infinity>());
            scale = std::max(scale, tf.u[i].lpNorm<Eigen::Infinity>());
        }
        EXPECT_GT(scale, 0);
        EXPECT_LT(worst, 1e-10 * scale) << coarse_mass;

        const sim::Modes mf = sim::modes(fine.K, M, fine.bc, 6);
        const sim::Modes mc = sim::modes(c.K, Mc, c.bc, 6);
        for (Index i = 0; i < 6; ++i)
            EXPECT_NEAR(mc.eigenvalues[i], mf.eigenvalues[i], 1e-10 * mf.eigenvalues[i])
                << coarse_mass << " mode " << i;
    }
}

// The hierarchy's Galerkin mass, level by level (C̃^l X C̃^{l,T}), equals Φ^k X Φ^{k,T} with the
// basis Φ^k formed explicitly (mra::basis), to round-off, at every level.
TEST(CoarseDynamics, HierarchyGalerkinMassIsThePhiProduct) {
    const scene::Scene sc = scene::parse_scene(test::layered_bar_json(), "layers.json", "");
    const scene::FineModel fine = scene::build_fine_model(sc);
    mra::Options o;
    o.levels = 3;
    o.radius = {2.0};
    const mra::Hierarchy h = mra::build_hierarchy(fine.mesh, fine.K, fine.bc.dofs, o);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    for (int k = 1; k <= 3; ++k) {
        const SparseMatrix level = mra::galerkin_operator(h, M, k);
        const SparseMatrix Phi = mra::basis(h, k);  // #dofs(k) x fine grid DOFs
        const Matrix expected = Matrix(Phi) * Matrix(M) * Matrix(Phi).transpose();
        EXPECT_LT((Matrix(level) - expected).norm(), 1e-12 * expected.norm()) << "level " << k;
    }
}

// The layered (accordion) beam of the demo at 32x8x8 hexes (stiff/soft layers, contrast 1000),
// coarsened 4x per axis: the lowest bending frequency (two equal ones, the section is square)
// of each coarse model, paired with the fine modes by MAC. The effective tensors soften the
// averaged beam to within 15% (measured +14.7% and +11.5%), naive and Voigt averages are stiffer
// by more than 3x (measured 14.6x: the soft layers carry the bending), and the hierarchy's
// coarsest level (3 levels, global solves, linear refinement) is within 2% (measured 4e-6).
// The two bending modes are degenerate, so each model returns an arbitrary rotation of the pair
// and their MAC pairs are about 0.6: the frequencies, not the MAC values, are compared.
TEST(CoarseDynamicsSlow, AccordionLowestBendingFrequencyPerMethod) {
    const scene::Scene sc = scene::parse_scene(scene::demo_scene(0.67), "demo", "");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    const sim::Modes mf = sim::modes(fine.K, M, fine.bc, 2);
    const auto relative_errors = [&](const std::string& method) {
        const coarsen::CoarseModel c = coarsen::build_coarse_model(sc, fine, method);
        const sim::Modes mc = sim::modes(c.K, c.mass(M), c.bc, 4);
        const std::vector<sim::ModePair> pairs =
            sim::pair_modes(mf.vectors, c.to_fine * mc.vectors);
        std::vector<double> errors;
        for (Index i = 0; i < 2; ++i) {
            const double f = mf.frequencies_hz[i];
            errors.push_back(
                std::abs(mc.frequencies_hz[pairs[static_cast<std::size_t>(i)].coarse] - f) / f);
        }
        return errors;
    };
    for (const double e : relative_errors("effective-tensor")) EXPECT_LT(e, 0.15);
    for (const char* average : {"naive", "voigt"})
        for (const double e : relative_errors(average)) EXPECT_GT(e, 2.0) << average;  // f_c > 3 f
    for (const double e : relative_errors("mra-linear")) EXPECT_LT(e, 0.02);
}
