// The "dynamics" block of a scene (scene.hpp, Scene::dynamics), parsed and validated before the
// mesh is read.
#include "coarsegrain/scene/scene.hpp"
#include "json_reader.hpp"

namespace coarsegrain::scene {

sim::DynamicsOptions parse_dynamics_options(const nlohmann::json& dynamics,
                                            const std::string& source) {
    const JsonReader r(dynamics, "dynamics", source);
    r.allow_only({"integrator", "dt", "steps", "output_every", "start", "initial_velocity",
                  "damping", "mass"});
    sim::DynamicsOptions o;
    if (auto v = r.find("integrator"))
        o.integrator = v->choice({"midpoint", "implicit_euler"}) == 0
                           ? sim::Integrator::Midpoint
                           : sim::Integrator::ImplicitEuler;
    o.dt = r.at("dt").positive();
    o.steps = static_cast<int>(r.at("steps").integer(1, sim::kMaxSteps));
    if (auto v = r.find("output_every")) o.output_every = static_cast<int>(v->integer(1, o.steps));
    if (auto v = r.find("start"))
        o.start = v->choice({"rest", "static"}) == 0 ? sim::Start::Rest : sim::Start::Static;
    if (auto v = r.find("initial_velocity")) {
        const std::size_t n = v->array_size();
        v->fail_unless(n == 2 || n == 3, "expected 2 or 3 numbers (one per axis), got {}",
                       v->json().dump());
        o.initial_velocity = v->vector(static_cast<int>(n));
    }
    if (auto d = r.find("damping")) {
        d->allow_only({"rayleigh"});
        const JsonReader rayleigh = d->at("rayleigh");
        const Eigen::VectorXd ab = rayleigh.vector(2);
        rayleigh.fail_unless(ab.minCoeff() >= 0,
                             "expected [alpha, beta] >= 0 (C = alpha M + beta K), got [{}, {}]",
                             ab[0], ab[1]);
        o.rayleigh_mass = ab[0];
        o.rayleigh_stiffness = ab[1];
    }
    if (auto v = r.find("mass"))
        o.mass = v->choice({"consistent", "lumped"}) == 0 ? fem::MassType::Consistent
                                                          : fem::MassType::Lumped;
    return o;
}

}  // namespace coarsegrain::scene
