// The "corotation" block of a scene (scene.hpp, Scene::corotation), parsed and validated before
// the mesh is read.
#include "coarsegrain/scene/scene.hpp"
#include "json_reader.hpp"

namespace coarsegrain::scene {

sim::CorotationOptions parse_corotation_options(const nlohmann::json& corotation,
                                                const std::string& source) {
    const JsonReader r(corotation, "corotation", source);
    r.allow_only({"frame", "tangent", "tolerance", "max_iterations", "max_bisections", "step",
                  "linear_solve"});
    sim::CorotationOptions o;
    if (auto v = r.find("frame"))
        o.frame = v->choice({"de_veubeke", "polar"}) == 0 ? fem::CorotationFrame::DeVeubeke
                                                          : fem::CorotationFrame::Polar;
    if (auto v = r.find("tangent"))
        o.tangent = v->choice({"consistent", "fixed_frame"}) == 0 ? sim::Tangent::Consistent
                                                                  : sim::Tangent::FixedFrame;
    if (auto v = r.find("tolerance")) {
        o.tolerance = v->positive();
        v->fail_unless(o.tolerance < 1, "expected a relative residual in (0, 1), got {}",
                       o.tolerance);
    }
    if (auto v = r.find("max_iterations"))
        o.max_iterations = static_cast<int>(v->integer(1, 100'000));
    if (auto v = r.find("max_bisections")) o.max_bisections = static_cast<int>(v->integer(0, 40));
    if (auto v = r.find("step"))
        o.step = v->choice({"newton", "linearized"}) == 0 ? sim::StepIterations::Newton
                                                          : sim::StepIterations::Linearized;
    if (auto v = r.find("linear_solve")) {
        constexpr sim::LinearSolve solves[] = {sim::LinearSolve::Factorize,
                                               sim::LinearSolve::RestKrylov,
                                               sim::LinearSolve::LaggedKrylov};
        o.linear_solve = solves[v->choice({"factorize", "rest_krylov", "lagged_krylov"})];
    }
    return o;
}

}  // namespace coarsegrain::scene
