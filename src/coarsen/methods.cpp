#include <fmt/ranges.h>

#include <algorithm>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/mra/automatic_levels.hpp"
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

/// The scene's automatic level meshes (mra::automatic_level_meshes with coarse.levels).
/// @throws InvalidScene naming coarse.levels if a level cannot be made
std::vector<mesh::Mesh> automatic_levels(const scene::Scene& scene) {
    try {
        return mra::automatic_level_meshes(scene.mesh, scene.coarse.mra.levels);
    } catch (const Error& e) {
        throw InvalidScene(
            fmt::format("{}: coarse.levels: {} (coarse.level_meshes)", scene.source, e.what()));
    }
}

/// The model of an mra method: the hierarchy on nested grids or on level meshes, given or
/// automatic (made here unless with_automatic_levels made them). Automatic levels add their
/// phase and their files (build_coarse_model), and the hierarchy's errors on them name
/// coarse.levels.
CoarseModel hierarchy_model(const scene::Scene& scene, const scene::FineModel& fine,
                            const std::string& method) {
    Timings made_timings;
    std::vector<mesh::Mesh> made;
    if (uses_automatic_levels(scene, method)) {
        const Phase phase("automatic levels", &made_timings);
        made = automatic_levels(scene);
    }
    const std::vector<mesh::Mesh>& levels = made.empty() ? scene.coarse.level_meshes : made;
    const std::optional<double> seconds =
        made.empty() ? scene.coarse.automatic_levels_seconds : made_timings["automatic levels"];
    CoarseModel m;
    try {
        m = mra::build_coarse_model(hierarchy_options(scene, method), scene.coarse.mra_compare,
                                    fine, levels, scene.dynamics ? &*scene.dynamics : nullptr);
    } catch (const Interrupted&) {
        throw;
    } catch (const Error& e) {
        if (!seconds) throw;
        e.rethrow_with(
            fmt::format("{}: coarse.levels: {} (on the automatic level meshes: use fewer "
                        "levels or give coarse.level_meshes)",
                        scene.source, e.what()));
    }
    if (!seconds) return m;
    m.timings.add("automatic levels", *seconds);
    auto& report = std::get<mra::HierarchyReport>(m.report);
    for (std::size_t k = 1; k <= levels.size(); ++k) {
        const std::string file = fmt::format("level_{}.vtu", k);
        m.outputs.push_back({file, levels[k - 1], {}});
        report.levels[k - 1].mesh_file = file;
    }
    return m;
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
    const bool automatic = uses_automatic_levels(scene, method);
    CG_VERIFY_AS(InvalidScene,
                 scene.mesh.grid.has_value() || !scene.coarse.level_meshes.empty() || automatic,
                 "{}: mesh: the {} method needs a regular grid (mesh.grid), a simplicial mesh "
                 "(triangles or tetrahedra, whose coarser levels it makes itself) or the meshes "
                 "of its coarser levels (coarse.level_meshes), got {} elements; or coarsen with "
                 "coarse.mesh (effective-tensor)",
                 scene.source, method, mesh::element_name(scene.mesh.type));
    const mra::Options options = hierarchy_options(scene, method);
    try {
        if (automatic)
            mra::validate_automatic_levels(scene.mesh, options);
        else if (scene.coarse.level_meshes.empty())
            mra::validate_grid(options, scene.mesh.grid->cells, scene.dimension);
        else
            mra::validate_level_meshes(scene.coarse.level_meshes, scene.mesh, options);
    } catch (const Error& e) {
        const bool given = !scene.coarse.level_meshes.empty() &&
                           !scene.coarse.automatic_levels_seconds.has_value();
        CG_VERIFY_AS(InvalidScene, false, "{}: coarse.{}: {}", scene.source,
                     given ? "level_meshes" : "levels", e.what());
    }
    for (const scene::BoxCondition& c : scene.dirichlet)
        CG_VERIFY_AS(InvalidScene, c.value.isZero(0.0),
                     "{}: {}.value: the {} method supports only zero prescribed displacements, "
                     "got [{}]",
                     scene.source, c.key, method, fmt::join(c.value, ", "));
}

bool uses_automatic_levels(const scene::Scene& scene, const std::string& method) {
    return is_hierarchy(method) && !scene.mesh.grid.has_value() &&
           scene.coarse.level_meshes.empty() && mesh::is_simplex(scene.mesh.type);
}

scene::Scene with_automatic_levels(scene::Scene scene, const std::vector<std::string>& methods) {
    // A method that cannot run on the scene fails on its own, later (check_methods lets the
    // others of a comparison run).
    const auto needs_levels = [&](const std::string& method) {
        if (!uses_automatic_levels(scene, method)) return false;
        try {
            validate_method(scene, method);
            return true;
        } catch (const Error&) {
            return false;
        }
    };
    if (std::none_of(methods.begin(), methods.end(), needs_levels)) return scene;
    Timings timings;
    {
        const Phase phase("automatic levels", &timings);
        scene.coarse.level_meshes = automatic_levels(scene);
    }
    scene.coarse.automatic_levels_seconds = timings["automatic levels"];
    return scene;
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
    CoarseModel m = is_hierarchy(method)
                        ? hierarchy_model(scene, fine, method)
                        : homogenize::build_coarse_model(scene, fine, method, fine_factorization);
    m.method = method;
    return m;
}

}  // namespace coarsegrain::coarsen
