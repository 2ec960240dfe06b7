#include "coarsegrain/mra/coarse_model.hpp"

#include <cmath>
#include <limits>

#include "../scene/json_reader.hpp"
#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mra {

namespace {

using Triplet = Eigen::Triplet<double, Index>;

double parse_radius(const scene::JsonReader& r) {
    if (r.json().is_string()) {
        r.fail_unless(r.string() == "inf", "expected a number >= 1 or \"inf\", got {}",
                      r.json().dump());
        return std::numeric_limits<double>::infinity();
    }
    const double v = r.number();
    r.fail_unless(v >= 1, "expected a number >= 1 or \"inf\", got {}", v);
    return v;
}

double density(const SparseMatrix& M) {
    const double size = static_cast<double>(M.rows()) * static_cast<double>(M.cols());
    return size > 0 ? static_cast<double>(M.nonZeros()) / size : 0.0;
}

}  // namespace

Options parse_options(const nlohmann::json& coarse, const std::string& source) {
    Options o;
    if (coarse.is_null()) return o;
    const scene::JsonReader r(coarse, "coarse", source);
    r.require_object();
    if (auto v = r.find("levels")) {
        o.levels = v->integer();
        v->fail_unless(o.levels >= 2, "expected an integer >= 2, got {}", o.levels);
    }
    if (auto v = r.find("refinement")) {
        const std::string s = v->string();
        v->fail_unless(s == "dirac" || s == "linear", "expected \"dirac\" or \"linear\", got \"{}\"",
                       s);
        o.refinement = s == "dirac" ? Refinement::Dirac : Refinement::Linear;
    }
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
    if (auto v = r.find("radius_grid")) {
        const std::string s = v->string();
        v->fail_unless(s == "fine" || s == "coarse", "expected \"fine\" or \"coarse\", got \"{}\"",
                       s);
        o.radius_grid = s == "fine" ? RadiusGrid::Fine : RadiusGrid::Coarse;
    }
    if (auto v = r.find("truncation")) {
        o.truncation = v->number();
        v->fail_unless(o.truncation >= 0 && o.truncation < 1, "expected a number in [0, 1), got {}",
                       o.truncation);
    }
    if (auto v = r.find("invariance")) {
        v->fail_unless(v->json().is_boolean(), "expected true or false, got {}", v->json().dump());
        o.invariance = v->json().get<bool>();
    }
    if (auto v = r.find("dirichlet")) {
        const std::string s = v->string();
        bool found = false;
        for (DirichletTreatment t :
             {DirichletTreatment::Constrain, DirichletTreatment::Eliminate,
              DirichletTreatment::Penalty, DirichletTreatment::DiagonalPenalty})
            if (dirichlet_name(t) == s) {
                o.dirichlet = t;
                found = true;
            }
        v->fail_unless(found,
                       "expected \"constrain\", \"eliminate\", \"penalty\" or "
                       "\"diagonal_penalty\", got \"{}\"",
                       s);
    }
    return o;
}

coarsen::CoarseModel coarse_model(const Hierarchy& h, const Vector& f_fine) {
    const Level& L1 = h.level(1);
    const int dim = h.dim;
    const Index nodes = grid_nodes(L1.cells, dim);
    const Index n = dim * nodes;
    coarsen::CoarseModel m;
    m.method = "mra";
    m.nodes = nodes;
    m.elements = L1.cells.head(dim).prod();

    // Coefficients of level 1 are the measurements C^1 ... C^{q-1} u of a fine displacement u;
    // a translation t measures s t with s the row sums of that chain (1 for Dirac, 4^(q-1) in
    // the interior of a 2D grid for the linear refinement). Coarse DOFs u_c = v / s make the
    // model's DOFs displacements of the coarse nodes (exactly for translations): with v = S u_c,
    // K = S A^1 S, f = S g^1 and to_fine = Φ^{1,T} S.
    Vector s = Vector::Ones(h.fine_dofs.size());
    for (int k = h.num_levels() - 1; k >= 1; --k) s = h.level(k).C * s;
    // P: present coarsest DOFs -> all grid DOFs, scaled by s.
    SparseMatrix P(n, L1.dofs.size());
    {
        std::vector<Triplet> t;
        for (Index i = 0; i < L1.dofs.size(); ++i) t.emplace_back(L1.dofs[i], i, s[i]);
        P.setFromTriplets(t.begin(), t.end());
    }
    m.K = P * L1.A * SparseMatrix(P.transpose());
    m.K.makeCompressed();
    m.f = P * coarse_grain(h, f_fine, 1);
    m.to_fine = SparseMatrix(L1.Phi.transpose()) * SparseMatrix(P.transpose());
    m.to_fine.makeCompressed();
    std::vector<Index> dropped(L1.dropped_dofs.data(), L1.dropped_dofs.data() + L1.dropped_dofs.size());
    if (!dropped.empty()) {
        m.bc.dofs = dropped;
        m.bc.values = Vector::Zero(static_cast<Index>(dropped.size()));
    }
    m.timings = h.timings;

    const Options& o = h.options;
    nlohmann::json radius = nlohmann::json::array();
    for (const double r : o.radius) radius.push_back(std::isinf(r) ? nlohmann::json("inf") : nlohmann::json(r));
    m.report["options"] = {{"levels", o.levels},
                           {"refinement", refinement_name(o.refinement)},
                           {"radius", radius},
                           {"radius_grid", radius_grid_name(o.radius_grid)},
                           {"truncation", o.truncation},
                           {"invariance", o.invariance},
                           {"dirichlet", dirichlet_name(o.dirichlet)}};
    nlohmann::json levels = nlohmann::json::array();
    for (const Level& L : h.levels) {
        levels.push_back({{"level", L.k},
                          {"cells", std::vector<int>(L.cells.data(), L.cells.data() + dim)},
                          {"nodes", grid_nodes(L.cells, dim)},
                          {"dofs", L.dofs.size()},
                          {"wavelets", L.W.rows()},
                          {"radius", std::isinf(L.radius) ? nlohmann::json("inf") : nlohmann::json(L.radius)},
                          {"build_seconds", L.build_seconds},
                          {"C_nnz", L.C_adapted.nonZeros()},
                          {"C_density", density(L.C_adapted)},
                          {"A_nnz", L.A.nonZeros()},
                          {"A_density", density(L.A)},
                          {"B_nnz", L.B.nonZeros()},
                          {"B_density", density(L.B)},
                          {"Phi_bytes", storage_bytes(L.Phi)},
                          {"Psi_bytes", storage_bytes(L.Psi)}});
    }
    m.report["levels"] = levels;
    m.report["fine_dofs"] = h.fine_dofs.size();
    return m;
}

coarsen::CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine) {
    const Options options = parse_options(scene.coarse, scene.source);
    for (std::size_t k = 0; k < fine.bc.dofs.size(); ++k)
        CG_VERIFY_AS(InvalidScene, fine.bc.values[static_cast<Index>(k)] == 0.0,
                     "{}: dirichlet: the mra method supports only zero prescribed displacements, "
                     "but DOF {} is prescribed {}",
                     scene.source, fine.bc.dofs[k], fine.bc.values[static_cast<Index>(k)]);
    CG_VERIFY_AS(InvalidScene, fine.mesh.grid.has_value(),
                 "{}: mesh: the mra method needs a regular grid (mesh.grid)", scene.source);
    const int dim = fine.mesh.dim();
    const int factor = 1 << (options.levels - 1);
    for (int d = 0; d < dim; ++d)
        CG_VERIFY_AS(InvalidScene, fine.mesh.grid->cells[d] % factor == 0,
                     "{}: coarse.levels: {} levels need cells per axis divisible by 2^{} = {}, "
                     "but the grid has {} cells along axis {}",
                     scene.source, options.levels, options.levels - 1, factor,
                     fine.mesh.grid->cells[d], d);
    const Hierarchy h = build_hierarchy(fine.mesh, fine.K, fine.bc.dofs, options);
    return coarse_model(h, fine.f);
}

}  // namespace coarsegrain::mra
