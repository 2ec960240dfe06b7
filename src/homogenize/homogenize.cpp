#include "coarsegrain/homogenize/homogenize.hpp"

#include <fmt/ranges.h>

#include <algorithm>
#include <optional>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/homogenize/coarse_maps.hpp"
#include "coarsegrain/homogenize/harmonic.hpp"
#include "coarsegrain/io/material_fields.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/simplex_split.hpp"
#include "simplex_util.hpp"

namespace coarsegrain::homogenize {

namespace {

std::string point_string(const Eigen::VectorXd& p) {
    return fmt::format("({:.4g})", fmt::join(p, ", "));
}

Eigen::VectorXd centroid(const mesh::Mesh& m, Index e) {
    return m.element_positions(e).colwise().mean().transpose();
}

std::string box_string(const mesh::Mesh& m) {
    const Matrix b = mesh::bounding_box(m);
    return fmt::format("[{:.4g}] .. [{:.4g}]", fmt::join(b.row(0), ", "),
                       fmt::join(b.row(1), ", "));
}

/// Bounding-box diagonal of a mesh.
double box_diagonal(const mesh::Mesh& m) {
    const Matrix b = mesh::bounding_box(m);
    return (b.row(1) - b.row(0)).norm();
}

/// Scale sanity: a coarse mesh may stick out of the fine one by at most half a coarse edge
/// (verify_node_distances), so its bounding box cannot be 10 times larger (or smaller, then it
/// misses most of the object) unless the two meshes are in different units.
void verify_scale(const Coarsening& c, const std::string& source) {
    const double ratio = box_diagonal(c.coarse) / box_diagonal(c.fine);
    CG_VERIFY(ratio < 10 && ratio > 0.1,
              "{}: coarse.mesh is {:.3g} times the size of the fine mesh (bounding-box diagonals; "
              "fine bounding box {}, coarse bounding box {}); are both meshes in the same units?",
              source, ratio, box_string(c.fine), box_string(c.coarse));
}

/// Overlap sanity: the coarse mesh must meet the fine mesh, cover all of it, and hold fine
/// material in every element.
void verify_overlaps(const Coarsening& c, const std::string& source) {
    CG_VERIFY(!c.overlaps.empty(),
              "{}: coarse.mesh does not overlap the fine mesh at all (fine bounding box {}, "
              "coarse bounding box {}); are both meshes in the same units and place?",
              source, box_string(c.fine), box_string(c.coarse));
    const Index nf = c.fine.num_elements();
    Vector covered = Vector::Zero(nf);
    for (const mesh::Overlap& o : c.overlaps) covered[o.fine] += o.measure;
    double fine_total = 0, missing = 0;
    Index first = -1, count = 0;
    for (Index p = 0; p < nf; ++p) {
        const double vol = mesh::element_measure(c.fine, p);
        fine_total += vol;
        // 1e-8: the overlaps of a covered element sum to its measure up to round-off (~1e-15).
        if (covered[p] < (1 - 1e-8) * vol) {
            missing += vol - covered[p];
            if (first < 0) first = p;
            ++count;
        }
    }
    CG_VERIFY(count == 0,
              "{}: coarse.mesh misses part of the object: {} fine elements are not (fully) "
              "covered, {:.3g}% of the fine {}, e.g. fine element {} at {}; the coarse mesh must "
              "enclose the fine one",
              source, count, 100 * missing / fine_total, c.fine.dim() == 3 ? "volume" : "area",
              first, point_string(centroid(c.fine, first)));
    std::vector<char> has(static_cast<std::size_t>(c.coarse.num_elements()), 0);
    for (const mesh::Overlap& o : c.overlaps) has[o.coarse] = 1;
    for (Index q = 0; q < c.coarse.num_elements(); ++q)
        CG_VERIFY(has[q],
                  "{}: coarse element {} at {} contains no fine material (it lies outside the "
                  "object or in a cavity); the coarse mesh must not extend beyond the object",
                  source, q, point_string(centroid(c.coarse, q)));
}

/// Every coarse node lies inside the fine mesh or at most half its longest coarse edge outside.
/// Returns the distances.
Vector verify_node_distances(const Coarsening& c, const mesh::PointLocator& fine_locator,
                             const std::string& source) {
    const Index nv = c.coarse.num_nodes();
    Vector dist = Vector::Zero(nv), reach = Vector::Zero(nv);
    for (Index q = 0; q < c.coarse.num_elements(); ++q) {
        const double h = detail::longest_edge(c.coarse, q);
        for (Eigen::Index a = 0; a < c.coarse.elements.cols(); ++a)
            reach[c.coarse.elements(q, a)] = std::max(reach[c.coarse.elements(q, a)], h);
    }
#pragma omp parallel for schedule(dynamic, 64)
    for (Index v = 0; v < nv; ++v) {
        const Eigen::VectorXd p = c.coarse.rest_positions.row(v).transpose();
        const mesh::Location loc = fine_locator.locate_nearest(p);
        Eigen::VectorXd x = Eigen::VectorXd::Zero(p.size());
        for (Eigen::Index a = 0; a < c.fine.elements.cols(); ++a)
            x += loc.weights[a] *
                 c.fine.rest_positions.row(c.fine.elements(loc.element, a)).transpose();
        dist[v] = (x - p).norm();
    }
    for (Index v = 0; v < nv; ++v)
        CG_VERIFY(dist[v] <= 0.5 * reach[v],
                  "{}: coarse node {} at {} lies {:.4g} outside the fine mesh, more than half its "
                  "longest coarse edge ({:.4g}); is the coarse mesh in the same units and place as "
                  "the fine one (fine bounding box {}, coarse {})?",
                  source, v, point_string(c.coarse.rest_positions.row(v).transpose()), dist[v],
                  reach[v], box_string(c.fine), box_string(c.coarse));
    return dist;
}

/// The fine harmonic problem of Eq. 6 on the simplicial fine mesh: its stiffness, boundary and
/// the normals of the Neumann data. The fine model's own K and boundary serve when the fine mesh
/// is simplicial already; a split hex/quad mesh gets its own.
struct FineProblem {
    SparseMatrix K_split;
    mesh::Boundary b_split;
    const SparseMatrix* K = nullptr;
    const mesh::Boundary* b = nullptr;
    Matrix normals;
    /// A factorization of K without the scene's Dirichlet DOFs (mixed boundary), if there is one.
    const solve::SpdSolver* mixed_factorization = nullptr;
};

void setup_fine_problem(FineProblem& p, const Coarsening& c, const scene::FineModel& fine,
                        const solve::SpdSolver* fine_factorization) {
    if (mesh::is_simplex(fine.mesh.type)) {
        p.K = &fine.K;
        p.b = &fine.boundary;
        p.mixed_factorization = fine_factorization;  // of fine.K without fine.bc.dofs
    } else {
        p.K_split = fem::stiffness_matrix(c.fine, c.fine_materials);
        p.b_split = mesh::boundary(c.fine);
        p.K = &p.K_split;
        p.b = &p.b_split;
    }
    p.normals =
        c.options.coarse_normals ? coarse_boundary_normals(c.fine, *p.b, c.coarse) : p.b->normals;
}

struct HarmonicPart {
    Matrix h, H;
    std::vector<Mandel6> G_fine, G_coarse, A;
};

HarmonicPart harmonic_part(const Coarsening& c, const FineProblem& p,
                           const std::vector<Index>& fixed_dofs, const mesh::PointLocator& locator,
                           Timings* timings) {
    HarmonicPart r;
    {
        const Phase phase("harmonic", timings);
        r.h = harmonic_displacements(c.fine, *p.b, *p.K, p.normals, fixed_dofs,
                                     fixed_dofs.empty() ? nullptr : p.mixed_factorization);
    }
    const Phase phase("tensors", timings);
    r.G_fine = mollifiers(c.fine, r.h);
    r.H = sample_harmonic(c.fine, locator, r.h, c.coarse.rest_positions);
    r.G_coarse = mollifiers(c.coarse, r.H);
    r.A = energy_averages(c.fine.dim(), r.G_fine, c.fine_materials, c.overlaps, c.coarse_measures);
    return r;
}

Vector element_measures(const mesh::Mesh& m) {
    Vector v(m.num_elements());
    for (Index e = 0; e < m.num_elements(); ++e) v[e] = mesh::element_measure(m, e);
    return v;
}

}  // namespace

Coarsening coarsening(const scene::Scene& scene, const scene::FineModel& fine,
                      const std::string& method, const solve::SpdSolver* fine_factorization) {
    const bool effective = method == "effective-tensor";
    CG_VERIFY_AS(InvalidScene,
                 effective || method == "naive" || method == "voigt" || method == "reuss",
                 "unknown coarsening method \"{}\"; expected \"effective-tensor\", \"naive\", "
                 "\"voigt\" or \"reuss\"",
                 method);
    Coarsening c;
    c.method = method;
    c.options = scene.coarse.homogenize;
    CG_VERIFY_AS(InvalidScene, scene.coarse.mesh.has_value(),
                 "{}: coarse.mesh: the {} method needs a coarse mesh", scene.source, method);
    const int dim = fine.mesh.dim();
    CG_VERIFY_AS(InvalidScene, scene.coarse.mesh->dim() == dim,
                 "{}: coarse.mesh is {}D, the fine mesh {}D", scene.source,
                 scene.coarse.mesh->dim(), dim);
    const std::string where = scene.source + ": coarse.mesh";
    mesh::Mesh coarse = *scene.coarse.mesh;
    coarse.material_ids.setZero(coarse.num_elements());  // ignored: coarse elements get tensors
    mesh::validate(coarse, where);
    c.coarse = mesh::simplex_split(coarse);
    c.fine = mesh::simplex_split(fine.mesh);
    c.fine_materials = fine.materials;
    if (!mesh::is_simplex(fine.mesh.type)) {
        const int per = mesh::simplices_per_element(fine.mesh.type);
        c.fine_materials.index.resize(c.fine.num_elements());
        for (Index s = 0; s < c.fine.num_elements(); ++s)
            c.fine_materials.index[s] = fine.materials.index[s / per];
    }
    c.coarse_measures = element_measures(c.coarse);

    std::optional<mesh::PointLocator> fine_locator;
    Vector outside;
    {
        const Phase phase("intersect", &c.timings);
        verify_scale(c, scene.source);
        fine_locator.emplace(c.fine);
        c.overlaps = mesh::intersect(c.fine, c.coarse);
        verify_overlaps(c, scene.source);
        outside = verify_node_distances(c, *fine_locator, where);
        c.element_mass =
            coarse_element_masses(c.fine_materials, c.overlaps, c.coarse.num_elements());
    }
    c.report.fine_simplices = c.fine.num_elements();
    c.report.coarse_simplices = c.coarse.num_elements();
    c.report.overlaps = static_cast<Index>(c.overlaps.size());
    // Nodes on the fine boundary are reconstructed from barycentric weights to round-off of the
    // coordinates' size: only distances above that count as outside.
    const double round_off = 1e-12 * box_diagonal(c.fine);
    c.report.coarse_nodes_outside = (outside.array() > round_off).count();
    c.report.coarse_nodes_max_outside_distance = outside.size() ? outside.maxCoeff() : 0.0;
    double fine_mass = 0;
    for (Index p = 0; p < c.fine.num_elements(); ++p)
        fine_mass += c.fine_materials.of(p).density * mesh::element_measure(c.fine, p);
    c.report.fine_mass = fine_mass;
    c.report.coarse_mass = c.element_mass.sum();

    if (!effective) {
        const Phase phase("tensors", &c.timings);
        const Average kind = method == "naive"   ? Average::Naive
                             : method == "voigt" ? Average::Voigt
                                                 : Average::Reuss;
        c.C = average_tensors(kind, c.fine_materials, c.overlaps, c.coarse.num_elements());
        return c;
    }

    CG_VERIFY_AS(InvalidScene, !c.options.mixed_boundary || !fine.bc.empty(),
                 "{}: coarse.boundary: \"mixed\" needs fixed nodes, but the scene has no "
                 "dirichlet boxes",
                 scene.source);
    FineProblem problem;
    {
        const Phase phase("harmonic", &c.timings);
        setup_fine_problem(problem, c, fine, fine_factorization);
    }
    const std::vector<Index> no_fixed;
    HarmonicPart part = harmonic_part(
        c, problem, c.options.mixed_boundary ? fine.bc.dofs : no_fixed, *fine_locator, &c.timings);
    c.h = std::move(part.h);
    c.H = std::move(part.H);
    c.G_fine = std::move(part.G_fine);
    c.G_coarse = std::move(part.G_coarse);
    c.A = std::move(part.A);

    const double scale = mollifier_scale(dim, c.G_fine, element_measures(c.fine));
    std::vector<Index> singular;
    for (Index q = 0; q < c.coarse.num_elements(); ++q)
        if (mollifier_singular(dim, c.G_coarse[q], scale)) singular.push_back(q);
    if (c.options.mixed_boundary && !singular.empty()) {
        HarmonicPart neumann = harmonic_part(c, problem, no_fixed, *fine_locator, &c.timings);
        for (Index q : singular) {
            c.G_coarse[q] = neumann.G_coarse[q];
            c.A[q] = neumann.A[q];
        }
        c.fallback = singular;
        c.h_neumann = std::move(neumann.h);
        c.H_neumann = std::move(neumann.H);
        c.G_fine_neumann = std::move(neumann.G_fine);
        const double scale_n = mollifier_scale(dim, c.G_fine_neumann, element_measures(c.fine));
        singular.clear();
        for (Index q : c.fallback)
            if (mollifier_singular(dim, c.G_coarse[q], scale_n)) singular.push_back(q);
    }
    CG_VERIFY(singular.empty(),
              "{}: the coarse mollifier of coarse element {} at {} is singular ({} element(s) "
              "in all): the harmonic displacements sampled at its nodes do not span its strains "
              "(a sliver element, or nodes extrapolated far from the fine mesh)",
              where, singular.empty() ? 0 : singular[0],
              singular.empty() ? "" : point_string(centroid(c.coarse, singular[0])),
              singular.size());
    {
        const Phase phase("tensors", &c.timings);
        c.C = effective_tensors(dim, c.A, c.G_coarse);
    }
    double cmin = std::numeric_limits<double>::infinity(), cmax = 0;
    for (const Mandel6& G : c.G_coarse) {
        const double k = condition_number(dim, G);
        cmin = std::min(cmin, k);
        cmax = std::max(cmax, k);
    }
    c.report.harmonic_map = c.options.harmonic_map;
    c.report.effective_tensor = EffectiveTensorReport{
        c.options.coarse_normals, c.options.mixed_boundary, cmin, cmax, c.fallback};
    return c;
}

namespace {

/// The coarse mass of CoarseMass `type` for the model's coarse-to-fine map P (CoarseModel::mass).
/// T (empty: none) maps the model's DOFs w to the coarse mesh's, u = T w, when DOFs are held in
/// combination; the consistent mass of the coarse mesh is then Tᵀ M_c T.
std::function<SparseMatrix(const SparseMatrix&)> coarse_mass(
    CoarseMass type, SparseMatrix P, const SparseMatrix& T, const mesh::Mesh& coarse,
    const material::ElementMaterials& mats) {
    switch (type) {
        case CoarseMass::Lumped:
            return [P = std::move(P)](const SparseMatrix& M) -> SparseMatrix {
                const Vector m = P.transpose() * (M * Vector::Ones(M.cols()));
                SparseMatrix D(m.size(), m.size());
                D.setIdentity();
                D.diagonal() = m;
                return D;
            };
        case CoarseMass::Consistent: {
            SparseMatrix Mc = fem::mass_matrix(coarse, mats, fem::MassType::Consistent);
            if (T.size() > 0) Mc = SparseMatrix(T.transpose()) * Mc * T;
            return [Mc = std::move(Mc)](const SparseMatrix&) { return Mc; };
        }
        case CoarseMass::Galerkin:
            return [P = std::move(P)](const SparseMatrix& M) -> SparseMatrix {
                SparseMatrix Mc = SparseMatrix(P.transpose()) * (M * P);
                Mc.makeCompressed();
                return Mc;
            };
    }
    return {};
}

}  // namespace

coarsen::CoarseModel coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                                  Coarsening c) {
    const int dim = c.coarse.dim();
    const bool effective = c.method == "effective-tensor";
    coarsen::CoarseModel m;
    m.method = c.method;
    m.nodes = c.coarse.num_nodes();
    m.elements = c.coarse.num_elements();
    m.timings = c.timings;
    m.report = c.report;

    material::ElementMaterials mats;
    mats.dim = dim;
    mats.index.resize(m.elements);
    {
        const Phase phase("assemble", &m.timings);
        for (Index q = 0; q < m.elements; ++q) {
            const int n = mandel_size(dim);
            try {
                mats.table.push_back(material::anisotropic(
                    dim, c.C[q].topLeftCorner(n, n), c.element_mass[q] / c.coarse_measures[q]));
            } catch (const Error& e) {
                CG_VERIFY(false, "{}: coarse.mesh: the {} tensor of coarse element {} at {}: {}",
                          scene.source, c.method, q, point_string(centroid(c.coarse, q)), e.what());
            }
            mats.index[q] = q;
        }
        m.K = fem::stiffness_matrix(c.coarse, mats);
    }
    {
        const Phase phase("maps", &m.timings);
        const mesh::PointLocator locator(c.coarse);
        const std::vector<mesh::Location> loc = locate_points(locator, fine.mesh.rest_positions);
        SparseMatrix embedding = barycentric_embedding(c.coarse, loc);
        // The fine conditions and load carried by the coarse-to-fine map P: P u_coarse takes the
        // fine Dirichlet values (carry_dirichlet: coarse DOFs fixed, or held in combination where
        // fixing them would hold more than the fine nodes), and f_c = P^T f is the load that does
        // the fine load's work on every coarse displacement (exact total force, and moment for a
        // P that reproduces rigid motions). The conditions follow the linear shape functions of
        // the coarse mesh whatever the map: the harmonic map's rows mix all nodes of the carrying
        // element and would hold interior coarse nodes.
        const CarriedConditions carried = carry_dirichlet(fine.bc, embedding);
        SparseMatrix P = embedding;
        if (effective && c.options.harmonic_map) {
            std::vector<Index> carrier(loc.size());
            for (std::size_t i = 0; i < loc.size(); ++i) carrier[i] = loc[i].element;
            // Fallback elements have singular mixed fields; the pure-Neumann ones span the same
            // strains elsewhere up to the clamp's local effect (Eq. 8 depends only on the span).
            const bool neumann = !c.fallback.empty();
            const HarmonicMap map(c.coarse, neumann ? c.H_neumann : c.H, fine.mesh.rest_positions,
                                  neumann ? c.h_neumann : c.h, carrier);
            P = map.linearized();
        }
        m.f = P.transpose() * fine.f;
        m.bc = carried.bc;
        if (carried.constrained > 0) {
            // Coarse DOFs u = T w: the model's DOFs are w.
            const SparseMatrix& T = carried.T;
            const SparseMatrix KT = SparseMatrix(T.transpose()) * m.K * T;
            m.K = 0.5 * (KT + SparseMatrix(KT.transpose()));
            m.K.makeCompressed();
            m.f = T.transpose() * m.f;
            P = P * T;
        }
        m.to_fine = P;
        auto& report = std::get<Report>(m.report);
        report.fixed_dofs = carried.fixed;
        report.constrained_dofs = carried.constrained;
        report.combinations = carried.combinations;
        m.element_model = coarsen::ElementModel{
            c.coarse, mats, carried.constrained > 0 ? carried.T : SparseMatrix()};
        m.mass = coarse_mass(c.options.mass, std::move(P),
                             carried.constrained > 0 ? carried.T : SparseMatrix(), c.coarse, mats);
    }

    coarsen::VtuOutput model{"coarse_model.vtu", c.coarse, {}};
    io::add_element_material_fields(model.fields, mats);
    const char* axes[] = {"E_x", "E_y", "E_z"};
    for (int d = 0; d < dim; ++d) {
        Vector E(m.elements);
        for (Index q = 0; q < m.elements; ++q)
            E[q] = material::directional_young(material::tensor(mats.of(q), dim),
                                               Eigen::VectorXd::Unit(dim, d));
        model.fields.add_cell_scalar(axes[d], E);
    }
    if (effective) {
        Vector cond(m.elements);
        for (Index q = 0; q < m.elements; ++q) cond[q] = condition_number(dim, c.G_coarse[q]);
        model.fields.add_cell_scalar("G_condition", cond);
        if (c.options.mixed_boundary) {
            Vector fb = Vector::Zero(m.elements);
            for (Index q : c.fallback) fb[q] = 1;
            model.fields.add_cell_scalar("fallback", fb);
        }
    }
    m.outputs.push_back(std::move(model));
    if (effective) {
        coarsen::VtuOutput harmonic{"harmonic.vtu", fine.mesh, {}};
        for (int J = 0; J < mandel_size(dim); ++J)
            harmonic.fields.add_point_vector(harmonic_name(dim, J), c.h.col(J), dim);
        m.outputs.push_back(std::move(harmonic));
    }
    return m;
}

coarsen::CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                                        const std::string& method,
                                        const solve::SpdSolver* fine_factorization) {
    return coarse_model(scene, fine, coarsening(scene, fine, method, fine_factorization));
}

}  // namespace coarsegrain::homogenize
