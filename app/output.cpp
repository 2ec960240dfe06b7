#include "output.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/stress.hpp"
#include "coarsegrain/io/file_util.hpp"

namespace coarsegrain::app {

Vector nodal_magnitude(const Vector& u, int dim) {
    return Eigen::Map<const Matrix>(u.data(), dim, u.size() / dim).colwise().norm().transpose();
}

io::VtuFields solution_fields(const scene::FineModel& model, const Vector& u) {
    const int dim = model.mesh.dim();
    const fem::ElementStress stress = fem::element_stress(model.mesh, model.materials, u);
    io::VtuFields fields;
    fields.add_point_vector("displacement", u, dim);
    fields.add_point_scalar("displacement_magnitude", nodal_magnitude(u, dim));
    Vector E(model.mesh.num_elements());
    for (Index e = 0; e < model.mesh.num_elements(); ++e) E[e] = model.materials.of(e).E;
    fields.add_cell_scalar("E", E);
    fields.add_cell("stress", fem::mandel_to_physical(stress.stress));
    fields.add_cell("strain", fem::mandel_to_physical(stress.strain));
    fields.add_cell_scalar("von_mises", stress.von_mises);
    return fields;
}

nlohmann::json newton_json(const sim::NewtonReport& report, const sim::CorotationOptions& options) {
    nlohmann::json history = nlohmann::json::array();
    for (const sim::NewtonIteration& it : report.history)
        history.push_back(
            {{"load_factor", it.load_factor}, {"residual", it.residual}, {"step", it.step}});
    return {{"frame", fem::corotation_frame_name(options.frame)},
            {"tangent", sim::tangent_name(options.tangent)},
            {"tolerance", options.tolerance},
            {"iterations", report.iterations},
            {"increments", report.increments},
            {"bisections", report.bisections},
            {"residual", report.residual},
            {"history", history}};
}

void print_warnings(const std::vector<std::string>& warnings) {
    for (const std::string& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
}

nlohmann::json probes_json(const scene::Scene& scene, const std::vector<Eigen::VectorXd>& u,
                           const std::vector<Eigen::VectorXd>* fine) {
    nlohmann::json j = nlohmann::json::array();
    for (std::size_t i = 0; i < u.size(); ++i) {
        nlohmann::json p = {{"point", to_std(scene.probes[i])}, {"u", to_std(u[i])}};
        if (fine) p["u_fine"] = to_std((*fine)[i]);
        j.push_back(p);
    }
    return j;
}

void check_methods(const scene::Scene& scene, const std::vector<std::string>& methods) {
    if (methods.size() == 1) return coarsen::validate_method(scene, methods.front());
    bool any_runnable = methods.empty();
    std::string first_error;
    for (const std::string& method : methods) {
        try {
            coarsen::validate_method(scene, method);
            any_runnable = true;
        } catch (const Error& e) {
            if (first_error.empty()) first_error = e.what();
        }
    }
    CG_VERIFY(any_runnable, "no method can run on this scene: {}", first_error);
}

void write_summary(const std::string& out_dir, const nlohmann::json& summary) {
    io::write_atomically((std::filesystem::path(out_dir) / "summary.json").string(),
                         [&](std::ostream& os) { os << summary.dump(2) << '\n'; });
}

namespace {

constexpr const char* kManifest = ".coarsegrain_outputs";

std::set<std::string> entries(const std::filesystem::path& dir) {
    std::set<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        names.insert(e.path().filename().string());
    return names;
}

}  // namespace

OutputFolder::OutputFolder(std::string dir) : dir_(std::move(dir)) {
    namespace fs = std::filesystem;
    io::ensure_writable_dir(dir_);
    const fs::path manifest = fs::path(dir_) / kManifest;
    std::ifstream in(manifest);
    for (std::string name; std::getline(in, name);) {
        // Only plain names of this folder's entries (never a path that leaves it).
        if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos)
            continue;
        std::error_code ec;
        fs::remove_all(fs::path(dir_) / name, ec);
        CG_VERIFY(!ec, "cannot remove {} (an output of the previous run in {}): {}", name, dir_,
                  ec.message());
    }
    fs::remove(manifest);
    before_ = entries(dir_);
}

OutputFolder::~OutputFolder() {
    try {
        std::string list;
        for (const std::string& name : entries(dir_))
            if (!before_.count(name) && name != kManifest) list += name + "\n";
        if (list.empty()) return;  // a run that wrote nothing leaves nothing
        io::write_atomically((std::filesystem::path(dir_) / kManifest).string(),
                             [&](std::ostream& os) { os << list; });
    } catch (const std::exception&) {
        // A folder that can no longer be listed or written keeps its files; nothing to undo.
    }
}

}  // namespace coarsegrain::app
