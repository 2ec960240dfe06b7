#include <fmt/ranges.h>

#include <algorithm>

#include "../scene/json_reader.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/mra/coarse_model.hpp"

namespace coarsegrain::coarsen {

const std::vector<std::string>& method_names() {
    static const std::vector<std::string> names = {
        "effective-tensor", "naive",          "voigt", "reuss", "mra", "mra-linear", "mra-dirac",
        "mra-linear-blind", "mra-dirac-blind"};
    return names;
}

std::vector<std::string> configured_methods(const scene::Scene& scene) {
    std::vector<std::string> methods;
    if (scene.coarse_mesh) methods = {"effective-tensor", "naive", "voigt", "reuss"};
    if (scene.coarse.is_object() && scene.coarse.contains("levels")) {
        methods.push_back("mra-linear");
        methods.push_back("mra-dirac");
        const scene::JsonReader r(scene.coarse, "coarse", scene.source);
        if (auto v = r.find("boundary_blind")) {
            v->fail_unless(v->json().is_boolean(), "expected true or false, got {}",
                           v->json().dump());
            if (v->json().get<bool>()) {
                methods.push_back("mra-linear-blind");
                methods.push_back("mra-dirac-blind");
            }
        }
    }
    CG_VERIFY(!methods.empty(),
              "{}: the \"coarse\" block configures no method: expected coarse.mesh "
              "(effective-tensor, naive, voigt, reuss) or coarse.levels (mra)",
              scene.source);
    return methods;
}

CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                               const std::string& method) {
    CG_VERIFY(
        std::find(method_names().begin(), method_names().end(), method) != method_names().end(),
        "unknown method '{}': expected one of {}", method, fmt::join(method_names(), ", "));
    CoarseModel m;
    if (method == "mra") {
        m = mra::build_coarse_model(scene, fine);
    } else if (method.starts_with("mra-")) {
        scene::Scene variant = scene;
        std::string refinement = method.substr(4);
        if (refinement.ends_with("-blind")) {
            variant.coarse["dirichlet"] = "ignore";
            refinement.resize(refinement.size() - std::string_view("-blind").size());
        }
        variant.coarse["refinement"] = refinement;
        m = mra::build_coarse_model(variant, fine);
    } else {
        m = homogenize::build_coarse_model(scene, fine, method);
    }
    m.method = method;
    return m;
}

}  // namespace coarsegrain::coarsen
