// simulate() and modes(): the dynamic runs of the command-line tool (coarsen/dynamics_run.hpp),
// computed in memory and handed out as arrays.
//
// Copies: each run's frames on the fine mesh are gathered into one matrix per run as the run
// goes (the fine frames move there frame by frame, the run's own copy freed as it goes), which
// the arrays then take over without a copy; probe series, frequencies and the coarse frames are
// copied (they are small).
#include <pybind11/stl.h>

#include <map>

#include "bindings.hpp"
#include "coarsegrain/coarsen/dynamics_run.hpp"

namespace coarsegrain::python {

namespace {

/// Gathers the frames on the fine mesh of every run but "fine" (the result holds those) as the
/// columns of one matrix per run, if asked.
class FrameCollector : public coarsen::RunObserver {
  public:
    FrameCollector(bool keep, Index dofs) : m_keep(keep), m_dofs(dofs) {}
    void fine_stepped(const sim::Trajectory& fine) override { m_count = fine.times.size(); }
    void frame(const std::string& name, std::size_t i, double /*time*/, const Vector& u,
               const Vector* /*reference*/) override {
        if (!m_keep || name == "fine") return;
        Matrix& frames = m_frames[name];
        if (frames.size() == 0) frames.resize(m_dofs, static_cast<Index>(m_count));
        frames.col(static_cast<Index>(i)) = u;
    }
    /// The frames of run `name` (dofs x saved times), moved out; empty if none were kept.
    Matrix take(const std::string& name) {
        auto it = m_frames.find(name);
        if (it == m_frames.end()) return {};
        Matrix m = std::move(it->second);
        m_frames.erase(it);
        return m;
    }

  private:
    bool m_keep;
    Index m_dofs;
    std::size_t m_count = 0;
    std::map<std::string, Matrix> m_frames;
};

/// #times x #probes x dim.
py::array_t<double> probes_array(const coarsen::ProbeSeries& s, std::size_t probes, int dim) {
    py::array_t<double> a({static_cast<py::ssize_t>(s.size()), static_cast<py::ssize_t>(probes),
                           static_cast<py::ssize_t>(dim)});
    auto o = a.mutable_unchecked<3>();
    for (std::size_t i = 0; i < s.size(); ++i)
        for (std::size_t p = 0; p < probes; ++p)
            for (int d = 0; d < dim; ++d)
                o(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(p), d) = s[i][p][d];
    return a;
}

/// #times x n of frames over n DOFs, or None if there are none.
py::object frames_array(Matrix&& frames) {
    if (frames.size() == 0) return py::none();
    return owned_matrix(std::move(frames), true);
}

/// Frames given as vectors, moved into one matrix (each vector freed once copied).
Matrix gather(std::vector<Vector>& u) {
    Matrix m(u.empty() ? 0 : u.front().size(), static_cast<Index>(u.size()));
    for (std::size_t i = 0; i < u.size(); ++i) {
        m.col(static_cast<Index>(i)) = u[i];
        u[i] = Vector();
    }
    return m;
}

/// The Python CoarseModel of a kept coarse model (its mass already computed).
std::shared_ptr<PyCoarse> python_coarse(coarsen::CoarseDynamics&& c,
                                        const std::shared_ptr<PyFine>& fine) {
    auto out = std::make_shared<PyCoarse>();
    out->fine = fine;
    out->model = std::move(c.model);
    out->model.K.makeCompressed();
    std::call_once(out->mass_once, [&] { out->M = compressed(std::move(c.M)); });
    return out;
}

/// The scene for a run: overrides applied, the method (if any) checked.
std::shared_ptr<const scene::Scene> run_scene(const PyScene& s,
                                              const std::optional<std::string>& method,
                                              const std::string& overrides) {
    std::shared_ptr<const scene::Scene> scene = with_overrides(s.scene, overrides);
    if (method) coarsen::validate_method(*scene, *method);
    return scene;
}

std::vector<std::string> method_list(const std::optional<std::string>& method) {
    return method ? std::vector<std::string>{*method} : std::vector<std::string>{};
}

py::dict simulate(const PyScene& s, const std::optional<std::string>& method,
                  const std::string& overrides, bool keep_frames) {
    coarsen::check_dynamics(*s.scene);
    const std::shared_ptr<const scene::Scene> scene = run_scene(s, method, overrides);
    const scene::Scene& sc = *scene;
    std::shared_ptr<PyFine> fine = build_fine(s.scene);
    const scene::FineModel& model = fine->run->model;
    coarsen::check_frames_fit(sc, model);
    FrameCollector collector(keep_frames, model.mesh.num_dofs());
    coarsen::SimulateResult result;
    nlohmann::json summary;
    Matrix fine_frames;
    run_interruptible([&] {
        coarsen::FineDynamics dynamics =
            coarsen::fine_dynamics(model, sc.dynamics->mass, fine->run->timings);
        result = coarsen::simulate_models(
            sc, dynamics, method_list(method),
            [&](const std::string& m) { return coarsen::build_coarse_dynamics(sc, dynamics, m); },
            collector, true);
        summary = coarsen::simulate_summary(sc, dynamics, result);
        if (keep_frames) fine_frames = gather(result.fine.u);
    });
    const std::size_t probes = sc.probes.size();
    const int dim = model.mesh.dim();
    py::dict out;
    out["summary"] = json_to_python(summary);
    out["times"] = py::array_t<double>(static_cast<py::ssize_t>(result.fine.times.size()),
                                       result.fine.times.data());
    out["fine_model"] = fine;
    py::dict f;
    f["probes"] = probes_array(result.fine_probes, probes, dim);
    f["frames"] = frames_array(std::move(fine_frames));
    out["fine"] = f;
    out["fine_linear"] = py::none();
    if (result.fine_linear) {
        py::dict l;
        l["probes"] = probes_array(result.fine_linear->probes, probes, dim);
        l["frames"] = frames_array(collector.take("fine-linear"));
        out["fine_linear"] = l;
    }
    out["coarse"] = py::none();
    if (!result.methods.empty()) {
        coarsen::ModelDynamics& r = result.methods.front();
        py::dict c;
        c["probes"] = probes_array(r.probes, probes, dim);
        c["frames"] = frames_array(collector.take(r.name));
        c["coarse_frames"] = frames_array(gather(r.u));
        c["coarse_model"] = python_coarse(std::move(*r.coarse), fine);
        out["coarse"] = c;
    }
    return out;
}

py::dict modes(const PyScene& s, const std::optional<std::string>& method, int count,
               const std::string& overrides) {
    const std::shared_ptr<const scene::Scene> scene = run_scene(s, method, overrides);
    const scene::Scene& sc = *scene;
    std::shared_ptr<PyFine> fine = build_fine(s.scene);
    const scene::FineModel& model = fine->run->model;
    const fem::MassType mass = sc.dynamics ? sc.dynamics->mass : fem::MassType::Consistent;
    coarsen::RunObserver observer;
    coarsen::ModesResult result;
    nlohmann::json summary;
    run_interruptible([&] {
        coarsen::FineDynamics dynamics = coarsen::fine_dynamics(model, mass, fine->run->timings);
        result = coarsen::modes_models(sc, dynamics, method_list(method), count, observer, true);
        summary = coarsen::modes_summary(sc, dynamics, result);
    });
    const auto vector_array = [](const Vector& v) {
        return py::array_t<double>(v.size(), v.data());
    };
    py::dict out;
    out["summary"] = json_to_python(summary);
    out["fine_model"] = fine;
    py::dict f;
    f["frequencies_hz"] = vector_array(result.fine.frequencies_hz);
    f["eigenvalues"] = vector_array(result.fine.eigenvalues);
    f["shapes"] = owned_matrix(std::move(result.fine.vectors));
    out["fine"] = f;
    out["coarse"] = py::none();
    if (!result.methods.empty()) {
        coarsen::ModesMethod& r = result.methods.front();
        py::dict c;
        c["frequencies_hz"] = vector_array(r.modes.frequencies_hz);
        c["eigenvalues"] = vector_array(r.modes.eigenvalues);
        c["shapes"] = owned_matrix(std::move(r.modes.vectors));
        c["shapes_fine"] = owned_matrix(std::move(r.carried));
        std::vector<Index> pairs;
        std::vector<double> mac;
        for (const sim::ModePair& p : r.pairs) {
            pairs.push_back(p.coarse);
            mac.push_back(p.mac);
        }
        c["pairs"] = py::array_t<Index>(static_cast<py::ssize_t>(pairs.size()), pairs.data());
        c["mac"] = py::array_t<double>(static_cast<py::ssize_t>(mac.size()), mac.data());
        c["coarse_model"] = python_coarse(std::move(*r.coarse), fine);
        out["coarse"] = c;
    }
    return out;
}

}  // namespace

void bind_dynamics(py::module_& m) {
    m.def("_simulate", &simulate, py::arg("scene"), py::arg("method"), py::arg("overrides_json"),
          py::arg("frames"),
          "simulate(scene, method, frames, **options) without the options' conversion to JSON: "
          "a dict of arrays and the summary.");
    m.def("_modes", &modes, py::arg("scene"), py::arg("method"), py::arg("count"),
          py::arg("overrides_json"),
          "modes(scene, method, count, **options) without the options' conversion to JSON: a "
          "dict of arrays and the summary.");
}

}  // namespace coarsegrain::python
