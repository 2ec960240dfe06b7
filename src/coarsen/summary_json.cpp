#include "coarsegrain/coarsen/summary_json.hpp"

namespace coarsegrain::coarsen {

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
