#include "run_solve.hpp"

#include <omp.h>
#include <sys/resource.h>

#include <cstdio>
#include <filesystem>

#include <fmt/ranges.h>

#include "coarsegrain/fem/stress.hpp"
#include "coarsegrain/io/file_util.hpp"
#include "coarsegrain/io/vtu.hpp"

namespace coarsegrain::app {

namespace {

double peak_rss_mb() {
    rusage r{};
    getrusage(RUSAGE_SELF, &r);
    return static_cast<double>(r.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

std::vector<double> to_std(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

// Physical (not Mandel-scaled) tensor components for ParaView: xx yy zz yz xz xy / xx yy xy.
Matrix mandel_to_physical(const Matrix& m) {
    Matrix out = m;
    const int n = static_cast<int>(m.cols());
    const int first_shear = n == 6 ? 3 : 2;
    out.rightCols(n - first_shear) *= kInvSqrt2;
    return out;
}

Vector nodal_magnitude(const Vector& u, int dim) {
    return Eigen::Map<const Matrix>(u.data(), dim, u.size() / dim).colwise().norm().transpose();
}

}  // namespace

void run_solve(const scene::Scene& sc, const std::string& out_dir, const std::string& command,
               double read_seconds) {
    io::ensure_writable_dir(out_dir);
    Timings t;
    t.add("read", read_seconds);
    const scene::FineModel model = scene::build_fine_model(sc, &t);
    const scene::StaticSolution sol = scene::solve_static(model, sc.solver, &t);
    const int dim = model.mesh.dim();
    const std::vector<Eigen::VectorXd> probes = scene::probe_displacements(sc, model.mesh, sol.u);
    const Vector magnitude = nodal_magnitude(sol.u, dim);
    const double max_u = magnitude.maxCoeff();

    {
        const Phase phase("write", &t);
        const fem::ElementStress stress = fem::element_stress(model.mesh, model.materials, sol.u);
        io::VtuFields fields;
        fields.add_point_vector("displacement", sol.u, dim);
        fields.add_point_scalar("displacement_magnitude", magnitude);
        Vector E(model.mesh.num_elements());
        for (Index e = 0; e < model.mesh.num_elements(); ++e) E[e] = model.materials.of(e).E;
        fields.add_cell_scalar("E", E);
        fields.add_cell("stress", mandel_to_physical(stress.stress));
        fields.add_cell("strain", mandel_to_physical(stress.strain));
        fields.add_cell_scalar("von_mises", stress.von_mises);
        io::write_vtu((std::filesystem::path(out_dir) / "solution.vtu").string(), model.mesh, fields);
    }

    nlohmann::json probes_json = nlohmann::json::array();
    for (std::size_t i = 0; i < probes.size(); ++i)
        probes_json.push_back({{"point", to_std(sc.probes[i])}, {"u", to_std(probes[i])}});
    nlohmann::json timings;
    for (const auto& [phase, seconds] : t.entries()) timings[phase] = seconds;
    const nlohmann::json summary = {
        {"command", command},
        {"scene", sc.source},
        {"fine",
         {{"nodes", model.mesh.num_nodes()},
          {"elements", model.mesh.num_elements()},
          {"element", mesh::element_name(model.mesh.type)},
          {"dofs", model.mesh.num_dofs()},
          {"free_dofs", model.mesh.num_dofs() - static_cast<Index>(model.bc.dofs.size())},
          {"nonzeros", model.K.nonZeros()},
          {"timings", timings}}},
        {"solver", solve::backend_name(sc.solver.backend)},
        {"threads", omp_get_max_threads()},
        {"probes", probes_json},
        {"max_displacement", max_u},
        {"strain_energy", sol.strain_energy},
        {"compliance", model.f.dot(sol.u)},
        {"peak_memory_mb", peak_rss_mb()},
    };
    io::write_atomically((std::filesystem::path(out_dir) / "summary.json").string(),
                         [&](std::ostream& os) { os << summary.dump(2) << '\n'; });

    std::printf("coarsegrain %s: %s\n", command.c_str(), sc.source.c_str());
    std::printf("  mesh      %dD %s, %d nodes, %d elements, %d DOFs (%d free)\n", dim,
                mesh::element_name(model.mesh.type).c_str(), model.mesh.num_nodes(),
                model.mesh.num_elements(), model.mesh.num_dofs(),
                model.mesh.num_dofs() - static_cast<Index>(model.bc.dofs.size()));
    std::printf("  %-12s %9s\n", "phase", "seconds");
    for (const auto& [phase, seconds] : t.entries())
        std::printf("  %-12s %9.3f\n", phase.c_str(), seconds);
    std::printf("  max |u|       %.6g\n  strain energy %.6g\n", max_u, sol.strain_energy);
    for (std::size_t i = 0; i < probes.size(); ++i)
        std::printf("  u(%s) = (%s)\n", fmt::format("{:g}", fmt::join(sc.probes[i], ", ")).c_str(),
                    fmt::format("{:.6g}", fmt::join(probes[i], ", ")).c_str());
    std::printf("  wrote %s/solution.vtu and %s/summary.json (peak memory %.0f MB)\n",
                out_dir.c_str(), out_dir.c_str(), peak_rss_mb());
}

}  // namespace coarsegrain::app
