#include "run_solve.hpp"

#include <fmt/ranges.h>
#include <omp.h>

#include <cstdio>
#include <filesystem>
#include <optional>

#include "coarsegrain/fem/rs_warp.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "output.hpp"

namespace coarsegrain::app {

void run_solve(const scene::Scene& sc, const std::string& out_dir, double read_seconds) {
    const OutputFolder folder(out_dir);
    Timings t;
    t.add("read", read_seconds);
    const scene::FineModel model = scene::build_fine_model(sc, &t);
    print_warnings(model.warnings);
    const bool corotated = sc.kinematics == sim::Kinematics::Corotational;
    scene::StaticSolution sol = corotated
                                    ? scene::solve_corotated(model, sc, &t)
                                    : scene::solve_static(model, scene::fine_solver(sc, model), &t);
    const bool warped = sc.rs_warp && !corotated;
    std::optional<double> linear_max_u;
    if (warped) {
        linear_max_u = nodal_magnitude(sol.u, model.mesh.dim()).maxCoeff();
        const Phase phase("warp", &t);
        sol.u = fem::RsWarp(model.mesh, model.bc, scene::direct_solver(sc))(sol.u);
    }
    const int dim = model.mesh.dim();
    const std::vector<Eigen::VectorXd> probes = scene::probe_displacements(sc, model.mesh, sol.u);
    const double max_u = nodal_magnitude(sol.u, dim).maxCoeff();
    {
        const Phase phase("write", &t);
        io::write_vtu((std::filesystem::path(out_dir) / "solution_fine.vtu").string(), model.mesh,
                      solution_fields(model, sol.u));
    }
    nlohmann::json fine = fine_sizes(model);
    fine["timings"] = timings_json(t);
    nlohmann::json summary = {
        {"command", "solve"},
        {"scene", sc.source},
        {"fine", fine},
        {"solver", solve::backend_name(sc.solver.backend)},
        {"threads", omp_get_max_threads()},
        {"kinematics", sim::kinematics_name(sc.kinematics)},
        {"warp", warped ? "rs" : "none"},
        {"probes", probes_json(sc, probes)},
        {"warnings", model.warnings},
        {"max_displacement", max_u},
        {"strain_energy", sol.strain_energy},
        {"compliance", model.f.dot(sol.u)},
        {"peak_memory_mb", peak_resident_mb()},
    };
    if (sol.newton) summary["newton"] = newton_json(*sol.newton, sc.corotation);
    if (linear_max_u) summary["linear_max_displacement"] = *linear_max_u;
    write_summary(out_dir, summary);

    std::printf("coarsegrain solve: %s\n", sc.source.c_str());
    std::printf("  mesh      %dD %s, %d nodes, %d elements, %d DOFs (%d free)\n", dim,
                mesh::element_name(model.mesh.type).c_str(), model.mesh.num_nodes(),
                model.mesh.num_elements(), model.mesh.num_dofs(),
                model.mesh.num_dofs() - static_cast<Index>(model.bc.dofs.size()));
    std::printf("  %-12s %9s\n", "phase", "seconds");
    for (const auto& [phase, seconds] : t.entries())
        std::printf("  %-12s %9.3f\n", phase.c_str(), seconds);
    if (sol.newton)
        std::printf(
            "  corotated (%s frame): %d Newton iterations, %d load increments, "
            "relative residual %.2e\n",
            fem::corotation_frame_name(sc.corotation.frame).c_str(), sol.newton->iterations,
            sol.newton->increments, sol.newton->residual);
    std::printf("  max |u|       %.6g\n  strain energy %.6g\n", max_u, sol.strain_energy);
    for (std::size_t i = 0; i < probes.size(); ++i)
        std::printf("  u(%s) = (%s)\n", fmt::format("{:g}", fmt::join(sc.probes[i], ", ")).c_str(),
                    fmt::format("{:.6g}", fmt::join(probes[i], ", ")).c_str());
    std::printf("  wrote %s/solution_fine.vtu and %s/summary.json (peak memory %.0f MB)\n",
                out_dir.c_str(), out_dir.c_str(), peak_resident_mb());
}

}  // namespace coarsegrain::app
