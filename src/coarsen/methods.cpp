#include <fmt/ranges.h>

#include <algorithm>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/mra/coarse_model.hpp"

namespace coarsegrain::coarsen {

namespace {

bool is_hierarchy(const std::string& method) { return method.starts_with("mra"); }

/// The hierarchy options of an mra method: the scene's, with the variant's refinement and
/// Dirichlet treatment.
mra::Options hierarchy_options(const scene::Scene& scene, const std::string& method) {
    mra::Options o = scene.coarse.mra;
    o.formulation = scene.formulation;  // that of the fine K
    if (method.starts_with("mra-linear")) o.refinement = mra::Refinement::Linear;
    if (method.starts_with("mra-dirac")) o.refinement = mra::Refinement::Dirac;
    if (method.ends_with("-blind")) o.dirichlet = mra::DirichletTreatment::Ignore;
    return o;
}

}  // namespace

const std::vector<std::string>& method_names() {
    static const std::vector<std::string> names = {
        "effective-tensor", "naive",          "voigt", "reuss", "mra", "mra-linear", "mra-dirac",
        "mra-linear-blind", "mra-dirac-blind"};
    return names;
}

std::vector<std::string> configured_methods(const scene::Scene& scene) {
    std::vector<std::string> methods;
    if (scene.coarse.mesh) methods = {"effective-tensor", "naive", "voigt", "reuss"};
    if (scene.coarse.hierarchy) {
        methods.push_back("mra-linear");
        methods.push_back("mra-dirac");
        if (scene.coarse.boundary_blind) {
            methods.push_back("mra-linear-blind");
            methods.push_back("mra-dirac-blind");
        }
    }
    CG_VERIFY_AS(InvalidScene, !methods.empty(),
                 "{}: the \"coarse\" block configures no method: expected coarse.mesh "
                 "(effective-tensor, naive, voigt, reuss) or coarse.levels (mra)",
                 scene.source);
    return methods;
}

void validate_method(const scene::Scene& scene, const std::string& method) {
    CG_VERIFY(
        std::find(method_names().begin(), method_names().end(), method) != method_names().end(),
        "unknown method '{}': expected one of {}", method, fmt::join(method_names(), ", "));
    if (!is_hierarchy(method)) {
        CG_VERIFY_AS(InvalidScene, scene.coarse.mesh.has_value(),
                     "{}: coarse.mesh: the {} method needs a coarse mesh", scene.source, method);
        return;
    }
    CG_VERIFY_AS(InvalidScene, scene.mesh.grid.has_value() || !scene.coarse.level_meshes.empty(),
                 "{}: mesh: the {} method needs a regular grid (mesh.grid) or the meshes of its "
                 "coarser levels (coarse.level_meshes); or coarsen with coarse.mesh "
                 "(effective-tensor)",
                 scene.source, method);
    try {
        if (scene.coarse.level_meshes.empty())
            mra::validate_grid(hierarchy_options(scene, method), scene.mesh.grid->cells,
                               scene.dimension);
        else
            mra::validate_level_meshes(scene.coarse.level_meshes, scene.mesh,
                                       hierarchy_options(scene, method));
    } catch (const Error& e) {
        CG_VERIFY_AS(InvalidScene, false, "{}: coarse.{}: {}", scene.source,
                     scene.coarse.level_meshes.empty() ? "levels" : "level_meshes", e.what());
    }
    for (const scene::BoxCondition& c : scene.dirichlet)
        CG_VERIFY_AS(InvalidScene, c.value.isZero(0.0),
                     "{}: {}.value: the {} method supports only zero prescribed displacements, "
                     "got [{}]",
                     scene.source, c.key, method, fmt::join(c.value, ", "));
}

bool uses_fine_factorization(const scene::Scene& scene, const scene::FineModel& fine,
                             const std::vector<std::string>& methods) {
    if (solve::is_iterative(scene.solver.backend)) return false;
    const Index free_dofs = fine.K.rows() - static_cast<Index>(fine.bc.dofs.size());
    return std::any_of(methods.begin(), methods.end(), [&](const std::string& method) {
        if (method == "effective-tensor")
            return scene.coarse.homogenize.mixed_boundary && mesh::is_simplex(fine.mesh.type);
        if (!is_hierarchy(method) || free_dofs > scene.coarse.mra_compare.max_spectrum_dofs)
            return false;
        const mra::Options o = hierarchy_options(scene, method);
        if (o.fine_operator == mra::Operator::Step) return false;  // no level diagnostics
        const mra::DirichletTreatment t = o.dirichlet;
        return t != mra::DirichletTreatment::Penalty &&
               t != mra::DirichletTreatment::DiagonalPenalty;
    });
}

CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                               const std::string& method,
                               const solve::SpdSolver* fine_factorization) {
    validate_method(scene, method);
    CoarseModel m =
        is_hierarchy(method)
            ? mra::build_coarse_model(hierarchy_options(scene, method), scene.coarse.mra_compare,
                                      fine, scene.coarse.level_meshes,
                                      scene.dynamics ? &*scene.dynamics : nullptr)
            : homogenize::build_coarse_model(scene, fine, method, fine_factorization);
    m.method = method;
    return m;
}

}  // namespace coarsegrain::coarsen
