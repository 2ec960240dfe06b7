// coarsen::simulate_models / modes_models (the dynamic runs of `simulate` and `modes`, in
// memory): what the observer sees, the errors against the frames it saw, a failing method among
// several, interrupts, and the summaries.
#include <gtest/gtest.h>

#include <map>

#include "coarsegrain/coarsen/dynamics_run.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/progress.hpp"

namespace coarsegrain {
namespace {

/// The demo beam at scale 0.25 (16x4x4 hexes) stepped 10 times, a frame every other step.
scene::Scene stepped_beam(int levels = 3) {
    nlohmann::json j = scene::demo_scene(0.25);
    j["dynamics"] = {{"integrator", "midpoint"}, {"dt", 0.01}, {"steps", 10}, {"output_every", 2}};
    j["coarse"]["levels"] = levels;
    return scene::parse_scene(j, "beam", "");
}

/// Records what a run hands out; keeps each run's frames and the squared differences to the
/// reference frames.
class Recorder : public coarsen::RunObserver {
  public:
    void fine_stepped(const sim::Trajectory& fine) override { stepped = fine.times.size(); }
    void frame(const std::string& name, std::size_t i, double time, const Vector& u,
               const Vector* reference) override {
        Run& r = runs[name];
        r.indices.push_back(i);
        r.times.push_back(time);
        if (reference) {
            r.diff2 += (u - *reference).squaredNorm();
            r.norm2 += reference->squaredNorm();
        }
        r.with_reference += reference != nullptr;
    }
    void run_done(const std::string& name) override { done.push_back(name); }
    void coarse_built(const std::string& method, const coarsen::CoarseDynamics& c) override {
        built[method] = c.M.rows();
    }
    void method_failed(const std::string& method, const std::string& message) override {
        failed[method] = message;
    }

    struct Run {
        std::vector<std::size_t> indices;
        std::vector<double> times;
        double diff2 = 0, norm2 = 0;
        std::size_t with_reference = 0;
    };
    std::size_t stepped = 0;
    std::map<std::string, Run> runs;
    std::vector<std::string> done;
    std::map<std::string, Index> built;
    std::map<std::string, std::string> failed;
};

coarsen::CoarseSource builder(const scene::Scene& sc, const coarsen::FineDynamics& fine) {
    return
        [&](const std::string& method) { return coarsen::build_coarse_dynamics(sc, fine, method); };
}

TEST(DynamicsRun, ObserverSeesEveryFrameOfEveryRun) {
    const scene::Scene sc = stepped_beam();
    const scene::FineModel model = scene::build_fine_model(sc);
    coarsen::FineDynamics fine = coarsen::fine_dynamics(model, sc.dynamics->mass);
    Recorder rec;
    const std::vector<std::string> methods = {"naive", "effective-tensor"};
    const coarsen::SimulateResult result =
        coarsen::simulate_models(sc, fine, methods, builder(sc, fine), rec, true);
    // 10 steps, a frame every other one and at t = 0
    ASSERT_EQ(result.fine.times.size(), 6u);
    EXPECT_EQ(rec.stepped, 6u);
    EXPECT_EQ(rec.done, (std::vector<std::string>{"fine", "naive", "effective-tensor"}));
    EXPECT_TRUE(rec.failed.empty());
    EXPECT_EQ(result.failed, 0);
    EXPECT_FALSE(result.fine_linear.has_value());  // linear kinematics
    for (const auto& [name, run] : rec.runs) {
        EXPECT_EQ(run.indices, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5})) << name;
        EXPECT_EQ(run.times, result.fine.times) << name;
        EXPECT_EQ(run.with_reference, name == "fine" ? 0u : 6u) << name;
    }
    ASSERT_EQ(result.methods.size(), 2u);
    for (std::size_t k = 0; k < methods.size(); ++k) {
        const coarsen::ModelDynamics& r = result.methods[k];
        EXPECT_EQ(r.name, methods[k]);
        EXPECT_TRUE(r.error.empty());
        ASSERT_TRUE(r.coarse.has_value());  // keep_models
        EXPECT_EQ(rec.built.at(r.name), r.coarse->model.K.rows());
        ASSERT_EQ(r.u.size(), 6u);
        EXPECT_EQ(r.u.front().size(), r.coarse->model.K.rows());
        EXPECT_EQ(r.probes.size(), 6u);
        // the error is that of the frames the observer saw (the same sums, in the same order)
        const Recorder::Run& seen = rec.runs.at(r.name);
        EXPECT_DOUBLE_EQ(r.trajectory_l2_rel, std::sqrt(seen.diff2 / seen.norm2));
        EXPECT_GT(r.trajectory_l2_rel, 0);
        EXPECT_EQ(r.entry.at("errors").at("trajectory_l2_rel").get<double>(), r.trajectory_l2_rel);
    }
    const nlohmann::json summary = coarsen::simulate_summary(sc, fine, result, {{"pvd", "x"}});
    EXPECT_EQ(summary.at("command"), "simulate");
    EXPECT_EQ(summary.at("pvd"), "x");
    EXPECT_EQ(summary.at("failed_methods"), 0);
    ASSERT_EQ(summary.at("methods").size(), 2u);
    for (const nlohmann::json& e : summary.at("methods"))
        EXPECT_EQ(e.at("timings").at("fine"), summary.at("timings").at("fine"));
    EXPECT_EQ(summary.at("times").get<std::vector<double>>(), result.fine.times);
}

TEST(DynamicsRun, OneFailingMethodAmongSeveralIsReported) {
    const scene::Scene sc = stepped_beam(4);  // 4 cells across: not divisible by 2^3
    const scene::FineModel model = scene::build_fine_model(sc);
    coarsen::FineDynamics fine = coarsen::fine_dynamics(model, sc.dynamics->mass);
    Recorder rec;
    const coarsen::SimulateResult result =
        coarsen::simulate_models(sc, fine, {"mra", "naive"}, builder(sc, fine), rec);
    EXPECT_EQ(result.failed, 1);
    ASSERT_EQ(rec.failed.count("mra"), 1u);
    EXPECT_NE(rec.failed.at("mra").find("coarse.levels"), std::string::npos);
    const coarsen::ModelDynamics& failed = result.methods.front();
    EXPECT_EQ(failed.error, rec.failed.at("mra"));
    EXPECT_EQ(failed.entry, (nlohmann::json{{"method", "mra"}, {"error", failed.error}}));
    EXPECT_TRUE(result.methods.back().error.empty());
    EXPECT_FALSE(result.methods.back().coarse.has_value());  // not kept
    const nlohmann::json summary = coarsen::simulate_summary(sc, fine, result);
    EXPECT_EQ(summary.at("failed_methods"), 1);
    // alone, the method's failure is thrown
    Recorder alone;
    EXPECT_THROW(coarsen::simulate_models(sc, fine, {"mra"}, builder(sc, fine), alone),
                 InvalidScene);
    EXPECT_TRUE(alone.failed.empty());
}

TEST(DynamicsRun, InterruptIsThrownNotReportedAsAFailure) {
    const scene::Scene sc = stepped_beam();
    const scene::FineModel model = scene::build_fine_model(sc);
    coarsen::FineDynamics fine = coarsen::fine_dynamics(model, sc.dynamics->mass);
    Recorder rec;
    const auto interrupting = [&](const std::string& method) {
        request_interrupt();  // the build's first phase throws
        return coarsen::build_coarse_dynamics(sc, fine, method);
    };
    EXPECT_THROW(coarsen::simulate_models(sc, fine, {"naive", "reuss"}, interrupting, rec),
                 Interrupted);
    clear_interrupt();
    EXPECT_TRUE(rec.failed.empty());
}

TEST(DynamicsRun, StepLoopStopsBeforeTheNextStepOnAnInterrupt) {
    sim::DynamicsOptions o;
    o.steps = 10;
    const SparseMatrix M = Matrix::Identity(2, 2).sparseView();
    sim::State start;
    start.u = start.v = Vector::Zero(2);
    int steps = 0;
    const auto step = [&](sim::State&) {
        if (++steps == 3) request_interrupt();
        return sim::StepSolves{1, 0, 0};
    };
    EXPECT_THROW(sim::run_steps(
                     start, o, M, step, [](const sim::State&) { return 0.0; }, "t"),
                 Interrupted);
    clear_interrupt();
    EXPECT_EQ(steps, 3);
}

TEST(DynamicsRun, ModesPairEveryFineMode) {
    const scene::Scene sc = stepped_beam();
    const scene::FineModel model = scene::build_fine_model(sc);
    coarsen::FineDynamics fine = coarsen::fine_dynamics(model, sc.dynamics->mass);
    Recorder rec;
    const coarsen::ModesResult result =
        coarsen::modes_models(sc, fine, {"effective-tensor"}, 4, rec);
    ASSERT_EQ(result.fine.eigenvalues.size(), 4);
    ASSERT_EQ(result.methods.size(), 1u);
    const coarsen::ModesMethod& m = result.methods.front();
    EXPECT_EQ(m.pairs.size(), 4u);
    EXPECT_EQ(m.carried.rows(), model.K.rows());
    EXPECT_EQ(m.carried.cols(), m.modes.vectors.cols());
    for (std::size_t i = 0; i < m.pairs.size(); ++i) {
        EXPECT_EQ(m.entry.at("mac")[i].get<double>(), m.pairs[i].mac);
        EXPECT_EQ(m.entry.at("mac_pairs")[i].get<double>(), static_cast<double>(m.pairs[i].coarse));
    }
    EXPECT_EQ(rec.built.count("effective-tensor"), 1u);
    const nlohmann::json summary = coarsen::modes_summary(sc, fine, result);
    EXPECT_EQ(summary.at("count"), 4);
    EXPECT_EQ(summary.at("method"), "effective-tensor");  // one method: its keys at the top
    EXPECT_EQ(summary.at("fine").at("frequencies_hz").size(), 4u);
}

}  // namespace
}  // namespace coarsegrain
