#include "coarsegrain/coarsen/summary_json.hpp"

#include <sys/resource.h>

namespace coarsegrain::coarsen {

double peak_rss_mb() {
    rusage r{};
    getrusage(RUSAGE_SELF, &r);
    return static_cast<double>(r.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

std::vector<double> to_std(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

nlohmann::json timings_json(const Timings& timings) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [phase, seconds] : timings.entries()) j[phase] = seconds;
    return j;
}

nlohmann::json fine_sizes(const scene::FineModel& model) {
    return {{"nodes", model.mesh.num_nodes()},
            {"elements", model.mesh.num_elements()},
            {"element", mesh::element_name(model.mesh.type)},
            {"dofs", model.mesh.num_dofs()},
            {"free_dofs", model.mesh.num_dofs() - static_cast<Index>(model.bc.dofs.size())},
            {"nonzeros", model.K.nonZeros()}};
}

}  // namespace coarsegrain::coarsen
