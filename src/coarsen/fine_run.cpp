#include "coarsegrain/coarsen/fine_run.hpp"

#include <utility>

namespace coarsegrain::coarsen {

FineRun solve_fine(const scene::Scene& sc, scene::FineModel model,
                   const std::vector<std::string>& methods, Timings timings) {
    FineRun f;
    f.model = std::move(model);
    f.timings = std::move(timings);
    solve_fine(sc, f, methods);
    return f;
}

void solve_fine(const scene::Scene& sc, FineRun& f, const std::vector<std::string>& methods) {
    const bool keep = uses_fine_factorization(sc, f.model, methods);
    if (sc.kinematics == sim::Kinematics::Corotational) {
        f.solution = scene::solve_corotated(f.model, sc, &f.timings);
        const Phase phase("linear solve", &f.timings);
        f.linear = scene::solve_static(f.model, scene::fine_solver(sc, f.model), nullptr, keep);
    } else {
        f.solution =
            scene::solve_static(f.model, scene::fine_solver(sc, f.model), &f.timings, keep);
    }
    if (sc.rs_warp && sc.kinematics == sim::Kinematics::Linear) {
        f.linear = f.solution;
        const fem::RsWarp& warp = fine_warp(sc, f);
        const Phase phase("warp", &f.timings);
        f.solution.u = warp(f.solution.u);
    }
    f.probes = scene::probe_displacements(sc, f.model.mesh, f.solution.u);
}

const fem::RsWarp& fine_warp(const scene::Scene& sc, FineRun& f) {
    if (!f.warp) {
        const Phase phase("warp", &f.timings);
        f.warp =
            std::make_shared<const fem::RsWarp>(f.model.mesh, f.model.bc, scene::direct_solver(sc));
    }
    return *f.warp;
}

bool solves_corotated(const CoarseModel& model, const scene::Scene& sc) {
    return sc.kinematics == sim::Kinematics::Corotational && model.element_model.has_value();
}

CoarseSolution solve_coarse_for_scene(const CoarseModel& model, const scene::Scene& sc,
                                      Timings* timings) {
    return solves_corotated(model, sc)
               ? solve_coarse_corotated(model, sc.corotation, scene::direct_solver(sc), timings)
               : solve_coarse(model, scene::direct_solver(sc), timings);
}

void warp_coarse_solution(CoarseSolution& s, const scene::Scene& sc, FineRun& f, Timings* timings) {
    if (!sc.rs_warp || s.newton) return;  // only a linear solution is post-warped
    const fem::RsWarp& warp = fine_warp(sc, f);
    const Phase phase("warp", timings);
    s.u_fine = warp(s.u_fine);
}

MethodRun run_method(const scene::Scene& sc, FineRun& f, const std::string& method,
                     Timings* timings) {
    MethodRun r;
    r.model = build_coarse_model(sc, f.model, method, f.linear_solution().factorization.get());
    r.solution = solve_coarse_for_scene(r.model, sc, timings);
    warp_coarse_solution(r.solution, sc, f, timings);
    r.errors = compare(f.model, f.solution.u, r.solution.u_fine);
    return r;
}

}  // namespace coarsegrain::coarsen
