// The "coarse" block of a scene: every coarsening method's options, parsed and validated in one
// place (scene.hpp, CoarseOptions).

#include <algorithm>
#include <cmath>
#include <limits>

#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "json_reader.hpp"

namespace coarsegrain::scene {

namespace {

double parse_radius(const JsonReader& r) {
    if (r.json().is_string()) {
        r.fail_unless(r.string() == "inf", "expected a number >= 1 or \"inf\", got {}",
                      r.json().dump());
        return std::numeric_limits<double>::infinity();
    }
    const double v = r.number();
    r.fail_unless(v >= 1, "expected a number >= 1 or \"inf\", got {}", v);
    return v;
}

homogenize::Options parse_homogenize(const JsonReader& r) {
    homogenize::Options o;
    if (auto v = r.find("normals")) o.coarse_normals = v->choice({"coarse", "fine"}) == 0;
    if (auto v = r.find("boundary")) o.mixed_boundary = v->choice({"neumann", "mixed"}) == 1;
    if (auto v = r.find("map")) o.harmonic_map = v->choice({"barycentric", "harmonic"}) == 1;
    if (auto v = r.find("mass"))
        o.mass =
            static_cast<homogenize::CoarseMass>(v->choice({"lumped", "consistent", "galerkin"}));
    return o;
}

mra::Options parse_mra(const JsonReader& r) {
    using namespace mra;
    Options o;
    if (auto v = r.find("levels")) o.levels = static_cast<int>(v->integer(2, kMaxLevels));
    if (auto v = r.find("level_meshes")) {  // one mesh per level but the finest
        const std::size_t n = v->json().is_array() ? v->array_size() : 0;
        v->fail_unless(n >= 1 && static_cast<int>(n) < kMaxLevels,
                       "expected an array of 1 to {} mesh files, coarsest first", kMaxLevels - 1);
        if (r.has("levels"))
            v->fail_unless(
                static_cast<int>(n) + 1 == o.levels,
                "{} meshes for coarse.levels = {}: expected levels - 1 (the fine mesh is "
                "the finest level)",
                n, o.levels);
        o.levels = static_cast<int>(n) + 1;
    }
    if (auto v = r.find("refinement"))
        o.refinement = v->choice({"dirac", "linear"}) == 0 ? Refinement::Dirac : Refinement::Linear;
    if (auto v = r.find("radius")) {
        if (v->json().is_array()) {
            const std::size_t n = v->array_size();
            v->fail_unless(static_cast<int>(n) == o.levels - 1,
                           "expected levels - 1 = {} radii (one per step, coarsest first), got {}",
                           o.levels - 1, n);
            o.radius.clear();
            for (std::size_t i = 0; i < n; ++i) o.radius.push_back(parse_radius(v->at(i)));
        } else {
            o.radius = {parse_radius(*v)};
        }
    }
    if (auto v = r.find("radius_grid"))
        o.radius_grid = v->choice({"fine", "coarse"}) == 0 ? RadiusGrid::Fine : RadiusGrid::Coarse;
    if (auto v = r.find("localization"))
        o.localization = v->choice({"node", "cell"}) == 0 ? Localization::Node : Localization::Cell;
    if (auto v = r.find("measurement"))
        o.measurement = v->choice({"canonical", "stiffness"}) == 0 ? Measurement::Canonical
                                                                   : Measurement::Stiffness;
    if (auto v = r.find("operator"))
        o.fine_operator =
            v->choice({"stiffness", "step"}) == 0 ? Operator::Stiffness : Operator::Step;
    if (auto v = r.find("defect_tolerance")) {
        o.defect_tolerance = v->number();
        v->fail_unless(o.defect_tolerance >= 0, "expected a number >= 0 (0: fixed radius), got {}",
                       o.defect_tolerance);
    }
    if (auto v = r.find("relaxation")) {
        o.relaxation = v->number();
        v->fail_unless(o.relaxation >= 0, "expected a number >= 0 (0: exact measurements), got {}",
                       o.relaxation);
    }
    if (auto v = r.find("max_radius")) {
        o.max_radius = v->number();
        v->fail_unless(o.max_radius >= 1, "expected a number >= 1, got {}", o.max_radius);
    }
    if (auto v = r.find("patch")) o.patch = static_cast<int>(v->integer(1, 1 << 16));
    if (auto v = r.find("patch_clip")) o.patch_clip = v->boolean();
    if (auto v = r.find("truncation")) {
        o.truncation = v->number();
        v->fail_unless(o.truncation >= 0 && o.truncation < 1, "expected a number in [0, 1), got {}",
                       o.truncation);
    }
    if (auto v = r.find("invariance")) o.invariance = v->boolean();
    if (auto v = r.find("dirichlet")) {
        constexpr DirichletTreatment treatments[] = {
            DirichletTreatment::Constrain, DirichletTreatment::Eliminate,
            DirichletTreatment::Penalty, DirichletTreatment::DiagonalPenalty,
            DirichletTreatment::Ignore};
        o.dirichlet = treatments[v->choice(
            {"constrain", "eliminate", "penalty", "diagonal_penalty", "ignore"})];
    }
    try {
        validate(o);  // the combinations; each key's range is checked above
    } catch (const Error& e) {
        r.fail("{}", e.what());
    }
    if (auto v = r.find("level_meshes")) {
        try {
            validate_level_mesh_options(o);
        } catch (const Error& e) {
            v->fail("{}", e.what());
        }
    }
    return o;
}

}  // namespace

CoarseOptions parse_coarse_options(const nlohmann::json& coarse, const std::string& source) {
    CoarseOptions o;
    if (coarse.is_null()) return o;
    const JsonReader r(coarse, "coarse", source);
    // One list for every method, so that one scene can be coarsened by each of them.
    r.allow_only({"mesh",
                  "normals",
                  "boundary",
                  "map",
                  "mass",
                  "levels",
                  "level_meshes",
                  "refinement",
                  "radius",
                  "radius_grid",
                  "patch",
                  "patch_clip",
                  "truncation",
                  "invariance",
                  "dirichlet",
                  "spectrum_max_dofs",
                  "cell_tensors",
                  "localization",
                  "measurement",
                  "operator",
                  "defect_tolerance",
                  "max_radius",
                  "relaxation",
                  "boundary_blind"});
    o.homogenize = parse_homogenize(r);
    o.hierarchy = r.has("levels") || r.has("level_meshes");
    o.mra = parse_mra(r);
    if (auto v = r.find("boundary_blind")) o.boundary_blind = v->boolean();
    if (auto v = r.find("spectrum_max_dofs"))
        o.mra_compare.max_spectrum_dofs =
            static_cast<Index>(v->integer(0, std::numeric_limits<Index>::max()));
    if (auto v = r.find("cell_tensors")) o.mra_compare.cell_tensors = v->boolean();
    return o;
}

}  // namespace coarsegrain::scene
