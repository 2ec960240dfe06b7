// Dynamics against CalculiX: tests/data/calculix/hex_dynamics.json holds the hex problem of
// hex.json (8x4x4 C3D8 checkerboard of E = 1000 / 10, densities 2 / 0.5, clamped at x = 0) with
// its 10 lowest eigenpairs (*FREQUENCY) and a transient under the suddenly applied gravity and
// pressure loads (*DYNAMIC, DIRECT, ALPHA=0: Newmark's average acceleration, dt = 0.125, 64
// steps). scripts/calculix/make_dynamics_reference.py writes the file and says how ccx was
// driven; a dense numpy FEM written independently of this library agrees with ccx to the
// printed digits (its docstring, "Cross-check").
//
// Tolerances: ccx stores ω² in full double precision (.eig file); our shift-invert Lanczos
// converges Ritz values to 1e-10 relative and the dense numpy solve matched ccx to 6.6e-13, so
// eigenvalues must agree to 1e-9. Mode shapes and the transient's u and v are printed with 7
// significant digits: every component must match the printed value to half a unit in its last
// digit, which implies 1e-6 of the largest value. Components that are zero by symmetry are
// round-off in both codes; for mode shapes that round-off is Lanczos's: a Ritz vector converged
// to 1e-10 with relative eigenvalue gaps of at least 0.05 here is accurate to about 2e-9 of
// its largest entry, so they may differ by 1e-8 of it (the transient's by 1e-12).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "coarsegrain/sim/modes.hpp"
#include "fem/calculix_reference.hpp"

using namespace coarsegrain;
using namespace coarsegrain::test;

namespace {

struct Problem {
    mesh::Mesh mesh;
    SparseMatrix K, M;
    ReferenceConditions conditions;
};

Problem load_problem(const nlohmann::json& ref) {
    Problem p;
    p.mesh = reference_mesh(ref);
    const material::ElementMaterials mats = reference_materials(ref, p.mesh);
    p.K = fem::stiffness_matrix(p.mesh, mats);
    p.M = fem::mass_matrix(p.mesh, mats, fem::MassType::Consistent);
    p.conditions = reference_conditions(ref, p.mesh, mats);
    return p;
}

}  // namespace

TEST(CalculixDynamics, LowestTenFrequenciesAndModesAgree) {
    const nlohmann::json ref = read_reference("hex_dynamics");
    const Problem p = load_problem(ref);
    const auto& freq = ref["frequency"];
    const sim::Modes modes = sim::modes(p.K, p.M, p.conditions.bc, 10);
    ASSERT_EQ(modes.eigenvalues.size(), 10);
    double worst = 0;
    for (Index i = 0; i < 10; ++i) {
        const double ccx = freq["eigenvalues"][static_cast<std::size_t>(i)];
        worst = std::max(worst, std::abs(modes.eigenvalues[i] - ccx) / ccx);
        EXPECT_TRUE(matches_printed(modes.frequencies_hz[i],
                                    freq["frequencies_hz_printed"][static_cast<std::size_t>(i)], 0))
            << "mode " << i;
    }
    RecordProperty("eigenvalue_max_rel_difference", fmt::format("{:.3e}", worst));
    EXPECT_LT(worst, 1e-9);

    // Shapes at the probes, mass-normalized by both codes; ccx's sign is arbitrary per mode.
    const auto probes = freq["probe_nodes"].get<std::vector<Index>>();
    for (Index i = 0; i < 10; ++i) {
        const auto& shape = freq["modes"][static_cast<std::size_t>(i)];
        const double scale = modes.vectors.col(i).lpNorm<Eigen::Infinity>();
        double dot = 0;
        for (std::size_t k = 0; k < probes.size(); ++k)
            for (int d = 0; d < 3; ++d)
                dot += modes.vectors(3 * probes[k] + d, i) *
                       shape[k][static_cast<std::size_t>(d)].get<double>();
        const double sign = dot < 0 ? -1 : 1;
        for (std::size_t k = 0; k < probes.size(); ++k)
            for (int d = 0; d < 3; ++d)
                EXPECT_TRUE(matches_printed(sign * modes.vectors(3 * probes[k] + d, i),
                                            shape[k][static_cast<std::size_t>(d)], 1e-8 * scale))
                    << "mode " << i << " probe node " << probes[k] << " component " << d;
    }
}

// Implicit midpoint from rest under the held load is ccx's Newmark average-acceleration run
// (the file's note says how the deck makes ccx start from M a0 = f exactly).
TEST(CalculixDynamics, MidpointTransientAgreesAtTheProbes) {
    const nlohmann::json ref = read_reference("hex_dynamics");
    const Problem p = load_problem(ref);
    const auto& tr = ref["transient"];
    sim::DynamicsOptions o;
    o.dt = tr["dt"];
    o.steps = tr["steps"];
    const sim::TimeStepper stepper(p.K, p.M, p.conditions.bc, o);
    auto [s, load] = sim::initial_state(p.K, p.conditions.f, p.conditions.bc, Vector(), o);
    const auto probes = tr["probe_nodes"].get<std::vector<Index>>();
    double max_u = 0, max_v = 0;
    for (const auto* field : {"u", "v"})
        for (const auto& probe : tr[field])
            for (const auto& at : probe)
                for (const auto& c : at)
                    (field[0] == 'u' ? max_u : max_v) =
                        std::max(field[0] == 'u' ? max_u : max_v, std::abs(c.get<double>()));
    double worst_u = 0, worst_v = 0;
    Index off = 0;
    for (int n = 0; n < o.steps; ++n) {
        stepper.step(s, load);
        EXPECT_NEAR((n + 1) * o.dt, tr["times"][static_cast<std::size_t>(n)].get<double>(), 1e-12);
        for (std::size_t k = 0; k < probes.size(); ++k)
            for (int d = 0; d < 3; ++d) {
                const Index dof = 3 * probes[k] + d;
                const double u =
                    tr["u"][k][static_cast<std::size_t>(n)][static_cast<std::size_t>(d)];
                const double v =
                    tr["v"][k][static_cast<std::size_t>(n)][static_cast<std::size_t>(d)];
                worst_u = std::max(worst_u, std::abs(s.u[dof] - u) / max_u);
                worst_v = std::max(worst_v, std::abs(s.v[dof] - v) / max_v);
                off += !matches_printed(s.u[dof], u, 1e-12 * max_u);
                off += !matches_printed(s.v[dof], v, 1e-12 * max_v);
            }
    }
    RecordProperty("u_max_rel_difference", fmt::format("{:.3e}", worst_u));
    RecordProperty("v_max_rel_difference", fmt::format("{:.3e}", worst_v));
    EXPECT_LT(worst_u, 1e-6);
    EXPECT_LT(worst_v, 1e-6);
    EXPECT_EQ(off, 0) << "components off ccx's printed digits";
}
