// Uses the installed library the way the guide shows: a scene from JSON (a 2 x 1 x 1 cantilever
// of two hexes, clamped at x = 0, under gravity), its fine model, a CHOLMOD solve. Checks the
// solution against identities that hold for any correct solve, and prints the tip deflection.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include <nlohmann/json.hpp>

#include "coarsegrain/scene/scene.hpp"

namespace cg = coarsegrain;

namespace {

int fail(const char* what, double value) {
    std::fprintf(stderr, "consumer: FAILED: %s (%g)\n", what, value);
    return 1;
}

}  // namespace

int main() try {
    const nlohmann::json j = {
        {"mesh", {{"grid", {{"min", {0, 0, 0}}, {"max", {2, 1, 1}}, {"cells", {2, 1, 1}},
                             {"element", "hex"}}}}},
        {"materials", {{"0", {{"E", 1e5}, {"nu", 0.3}, {"density", 1}}}}},
        {"dirichlet", {{{"box", {{"min", {-0.1, -0.1, -0.1}}, {"max", {0.1, 1.1, 1.1}}}}}}},
        {"loads", {{"gravity", {0, 0, -9.81}}}},
        {"solver", {{"backend", "cholmod"}}},
    };
    const cg::scene::Scene scene = cg::scene::parse_scene(j, "consumer", ".");
    const cg::scene::FineModel model = cg::scene::build_fine_model(scene);
    const cg::scene::StaticSolution sol = cg::scene::solve_static(model, scene.solver);

    const cg::mesh::Mesh& mesh = model.mesh;
    if (mesh.num_nodes() != 12) return fail("expected 12 nodes", double(mesh.num_nodes()));
    if (sol.u.size() != mesh.num_dofs()) return fail("displacement size", double(sol.u.size()));

    // Mean vertical displacement of the four tip nodes (x = 2); the clamped nodes do not move.
    double tip = 0, clamped = 0;
    for (cg::Index v = 0; v < mesh.num_nodes(); ++v) {
        const double x = mesh.rest_positions(v, 0);
        if (x > 1.99) tip += sol.u(3 * v + 2) / 4;
        if (x < 0.01) clamped = std::max(clamped, sol.u.segment(3 * v, 3).cwiseAbs().maxCoeff());
    }
    // The beam under its own weight sags: downward, and less than a free body falls (bounded
    // by the Euler-Bernoulli deflection q L^4 / (8 E I) = 2.35e-3 times 10: a coarse trilinear
    // model is stiffer than the beam, never 10 times softer).
    const double beam = 9.81 * 16 / (8 * 1e5 / 12.0);
    if (!std::isfinite(tip) || !(tip < 0)) return fail("tip deflection must be finite, < 0", tip);
    if (!(-tip < 10 * beam)) return fail("tip deflection beyond 10x the beam bound", tip);
    if (clamped != 0) return fail("clamped nodes moved", clamped);

    // With homogeneous conditions the strain energy is u.K.u / 2 = f.u / 2, and K u = f on the
    // free DOFs (the clamped ones carry the reactions).
    const double energy_Ku = 0.5 * sol.u.dot(model.K * sol.u);
    const double energy_fu = 0.5 * model.f.dot(sol.u);
    if (!(sol.strain_energy > 0)) return fail("strain energy must be > 0", sol.strain_energy);
    if (std::abs(energy_Ku - sol.strain_energy) > 1e-9 * sol.strain_energy)
        return fail("u.K.u / 2 differs from the strain energy", energy_Ku - sol.strain_energy);
    if (std::abs(energy_fu - sol.strain_energy) > 1e-9 * sol.strain_energy)
        return fail("f.u / 2 differs from the strain energy", energy_fu - sol.strain_energy);

    std::printf("consumer: tip deflection %.6e (Euler-Bernoulli beam %.6e), strain energy %.6e\n",
                tip, -beam, sol.strain_energy);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: FAILED: %s\n", e.what());
    return 1;
}
