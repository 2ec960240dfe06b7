#include <fmt/ranges.h>

#include <algorithm>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/mra/coarse_model.hpp"

namespace coarsegrain::coarsen {

const std::vector<std::string>& method_names() {
    static const std::vector<std::string> names = {"effective-tensor", "naive", "voigt", "reuss",
                                                   "mra"};
    return names;
}

CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                               const std::string& method) {
    CG_VERIFY(
        std::find(method_names().begin(), method_names().end(), method) != method_names().end(),
        "unknown method '{}': expected one of {}", method, fmt::join(method_names(), ", "));
    CoarseModel m = method == "mra" ? mra::build_coarse_model(scene, fine)
                                    : homogenize::build_coarse_model(scene, fine, method);
    m.method = method;
    return m;
}

}  // namespace coarsegrain::coarsen
