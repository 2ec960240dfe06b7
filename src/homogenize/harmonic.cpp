#include "coarsegrain/homogenize/harmonic.hpp"

#include <algorithm>
#include <array>
#include <limits>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/solve/spd_solver.hpp"
#include "simplex_util.hpp"

namespace coarsegrain::homogenize {

using detail::Small;
using detail::SmallVec;

namespace {

constexpr std::array<std::pair<int, int>, 6> kPairs3 = {
    {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}}};
constexpr std::array<std::pair<int, int>, 3> kPairs2 = {{{0, 0}, {1, 1}, {0, 1}}};

/// Rigid modes about centre c (ndofs by 3 or 6): translations, then rotations about the axes
/// (2D: one rotation).
Matrix rigid_modes(const Matrix& X, const Eigen::VectorXd& c) {
    const int dim = static_cast<int>(X.cols());
    const Index nv = static_cast<Index>(X.rows());
    const int r = dim == 2 ? 3 : 6;
    Matrix R = Matrix::Zero(dim * nv, r);
    for (Index v = 0; v < nv; ++v) {
        const Eigen::VectorXd x = X.row(v).transpose() - c;
        for (int d = 0; d < dim; ++d) R(dim * v + d, d) = 1.0;
        if (dim == 2) {
            R(2 * v, 2) = -x[1];
            R(2 * v + 1, 2) = x[0];
        } else {
            // rotation about axis k: u = e_k × x
            R(3 * v + 1, 3) = -x[2];
            R(3 * v + 2, 3) = x[1];
            R(3 * v + 0, 4) = x[2];
            R(3 * v + 2, 4) = -x[0];
            R(3 * v + 0, 5) = -x[1];
            R(3 * v + 1, 5) = x[0];
        }
    }
    return R;
}

/// Six (three in 2D) DOFs that remove the rigid motions: all components of the node farthest
/// from the centre, the components of the node farthest from it that are not along their
/// joining line's dominant axis, and (3D) the component of a third node, farthest from that
/// line, that the rotation about the line moves most (3-2-1 pinning).
std::vector<Index> rigid_pins(const Matrix& X, const Eigen::VectorXd& c) {
    const int dim = static_cast<int>(X.cols());
    Index a = 0, b = 0, p = 0;
    (X.rowwise() - c.transpose()).rowwise().squaredNorm().maxCoeff(&a);
    (X.rowwise() - X.row(a)).rowwise().squaredNorm().maxCoeff(&b);
    const Eigen::VectorXd d = (X.row(b) - X.row(a)).transpose();
    int k = 0;
    d.cwiseAbs().maxCoeff(&k);
    std::vector<Index> pins;
    for (int i = 0; i < dim; ++i) pins.push_back(dim * a + i);
    for (int i = 0; i < dim; ++i)
        if (i != k) pins.push_back(dim * b + i);
    if (dim == 3) {
        const Eigen::Vector3d dn = d.normalized();
        Eigen::VectorXd dist(X.rows());
        for (Index v = 0; v < X.rows(); ++v)
            dist[v] = dn.cross(Eigen::Vector3d(X.row(v) - X.row(a))).squaredNorm();
        dist.maxCoeff(&p);
        const Eigen::Vector3d m = dn.cross(Eigen::Vector3d(X.row(p) - X.row(a)));
        int j = 0;
        m.cwiseAbs().maxCoeff(&j);
        pins.push_back(3 * p + j);
    }
    std::sort(pins.begin(), pins.end());
    return pins;
}

/// Lumped nodal measures w_i = sum over incident simplices of |T| / (dim + 1).
Vector nodal_measures(const mesh::Mesh& m) {
    Vector w = Vector::Zero(m.num_nodes());
    const Index npe = static_cast<Index>(m.elements.cols());
    for (Index e = 0; e < m.num_elements(); ++e) {
        const double vol = mesh::element_measure(m, e);
        for (Index a = 0; a < npe; ++a) w[m.elements(e, a)] += vol / static_cast<double>(npe);
    }
    return w;
}

/// Closest point to p on the facet with corners P (dim rows of dim coordinates).
Eigen::VectorXd closest_on_facet(const Eigen::VectorXd& p, const Small& P) {
    if (P.cols() == 2) {
        const Eigen::Vector2d a = P.row(0).transpose(), b = P.row(1).transpose();
        const Eigen::Vector2d ab = b - a;
        const double t = std::clamp((Eigen::Vector2d(p) - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        return a + t * ab;
    }
    // Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions of the triangle.
    const Eigen::Vector3d a = P.row(0).transpose(), b = P.row(1).transpose(),
                          c = P.row(2).transpose(), q = p;
    const Eigen::Vector3d ab = b - a, ac = c - a, ap = q - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Eigen::Vector3d bp = q - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
    const Eigen::Vector3d cp = q - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

/// Parameter t >= -tol at which the ray c + t n meets the facet with corners P (rows), or
/// +infinity if it misses (edges in 2D, triangles in 3D, Möller-Trumbore).
double ray_hit(const Eigen::VectorXd& c, const Eigen::VectorXd& n, const Small& P, double tol) {
    const int dim = static_cast<int>(P.cols());
    Small M(dim, dim);  // [edges | -n] (s, t) = c - P0
    for (int i = 1; i < dim; ++i) M.col(i - 1) = (P.row(i) - P.row(0)).transpose();
    M.col(dim - 1) = -n;
    const Eigen::FullPivLU<Small> lu(M);
    if (!lu.isInvertible()) return std::numeric_limits<double>::infinity();  // parallel
    const SmallVec st = lu.solve(c - P.row(0).transpose());
    const double eps = 1e-12;
    const double t = st[dim - 1];
    const double s_sum = st.head(dim - 1).sum();
    if (t < -tol || (st.head(dim - 1).array() < -eps).any() || s_sum > 1 + eps)
        return std::numeric_limits<double>::infinity();
    return t;
}

}  // namespace

std::pair<int, int> mandel_pair(int dim, int J) {
    CG_VERIFY((dim == 2 || dim == 3) && J >= 0 && J < mandel_size(dim),
              "mandel_pair: component {} does not exist in {}D", J, dim);
    return dim == 2 ? kPairs2[J] : kPairs3[J];
}

std::string harmonic_name(int dim, int J) {
    const auto [a, b] = mandel_pair(dim, J);
    const char* axes = "xyz";
    return std::string("h_") + axes[a] + axes[b];
}

double mandel_weight(int dim, int J) {
    const auto [a, b] = mandel_pair(dim, J);
    return a == b ? 1.0 : kSqrt2;
}

Matrix harmonic_displacements(const mesh::Mesh& mesh, const mesh::Boundary& b,
                              const SparseMatrix& K, const Matrix& normals,
                              const std::vector<Index>& fixed_dofs,
                              const solve::SpdSolver* factorization) {
    detail::verify_simplicial(mesh, "harmonic displacements");
    const int dim = mesh.dim(), n = mandel_size(dim);
    const Index ndofs = mesh.num_dofs();
    CG_VERIFY(K.rows() == ndofs && K.cols() == ndofs,
              "harmonic displacements: K is {}x{}, the mesh has {} DOFs", K.rows(), K.cols(),
              ndofs);
    CG_VERIFY(normals.rows() == b.size() && normals.cols() == dim,
              "harmonic displacements: {}x{} normals for {} boundary facets in {}D", normals.rows(),
              normals.cols(), b.size(), dim);

    // Eq. 6 Neumann data: nodal forces of the traction E^{ab} N on the outer boundary.
    Matrix F = Matrix::Zero(ndofs, n);
    for (Index f = 0; f < b.size(); ++f) {
        if (b.component[f] != 0) continue;
        const double share = b.areas[f] / static_cast<double>(b.facets.cols());
        for (int J = 0; J < n; ++J) {
            const auto [p, q] = mandel_pair(dim, J);
            Eigen::VectorXd t = Eigen::VectorXd::Zero(dim);
            t[p] += 0.5 * normals(f, q);
            t[q] += 0.5 * normals(f, p);
            for (Eigen::Index a = 0; a < b.facets.cols(); ++a)
                F.block(dim * b.facets(f, a), J, dim, 1) += share * t;
        }
    }

    const bool neumann = fixed_dofs.empty();
    Matrix R, W_R;
    Eigen::LDLT<Matrix> moments;
    fem::Dirichlet bc;
    if (neumann) {
        const Vector w = nodal_measures(mesh);
        const Eigen::VectorXd centre = (mesh.rest_positions.transpose() * w) / w.sum();
        R = rigid_modes(mesh.rest_positions, centre);
        W_R = R;
        for (Index v = 0; v < mesh.num_nodes(); ++v) W_R.middleRows(dim * v, dim) *= w[v];
        moments.compute(R.transpose() * W_R);
        F -= W_R * moments.solve(R.transpose() * F);  // equilibrate (inertia relief)
        bc.dofs = rigid_pins(mesh.rest_positions, centre);
    } else {
        bc.dofs = fixed_dofs;
    }
    bc.values = Vector::Zero(static_cast<Index>(bc.dofs.size()));
    const fem::ReducedSystem sys = fem::reduce(K, Vector::Zero(ndofs), bc);
    CG_VERIFY(!factorization || (!neumann && factorization->rows() == sys.K.rows()),
              "harmonic displacements: a factorization of {} rows for {} free DOFs{}",
              factorization ? factorization->rows() : 0, sys.K.rows(),
              neumann ? " (pure Neumann: its own operator)" : "");
    solve::SpdSolver own;
    try {
        if (!factorization) own.compute(sys.K);
    } catch (const NotPositiveDefinite& e) {
        CG_VERIFY_AS(NotPositiveDefinite, false,
                     "harmonic displacements: the fine stiffness is singular {} ({}); is the "
                     "fine mesh made of disconnected parts{}?",
                     neumann ? "with the rigid motions removed" : "with the fixed DOFs held",
                     e.what(), neumann ? "" : ", some of them without fixed nodes");
    }
    Matrix rhs(sys.free_dofs.size(), n);
    for (Index i = 0; i < sys.free_dofs.size(); ++i) rhs.row(i) = F.row(sys.free_dofs[i]);
    const Matrix h_free = (factorization ? *factorization : own).solve(rhs);
    Matrix h = Matrix::Zero(ndofs, n);
    for (Index i = 0; i < sys.free_dofs.size(); ++i) h.row(sys.free_dofs[i]) = h_free.row(i);
    if (neumann) h -= R * moments.solve(W_R.transpose() * h);  // zeroth and first moments
    return h;
}

Matrix coarse_boundary_normals(const mesh::Mesh& fine, const mesh::Boundary& fb,
                               const mesh::Mesh& coarse) {
    detail::verify_simplicial(fine, "coarse boundary normals (fine mesh)");
    detail::verify_simplicial(coarse, "coarse boundary normals (coarse mesh)");
    CG_VERIFY(fine.dim() == coarse.dim(), "coarse boundary normals: a {}D fine and {}D coarse mesh",
              fine.dim(), coarse.dim());
    const int dim = fine.dim();
    const mesh::Boundary cb = mesh::boundary(coarse);
    CG_VERIFY(cb.size() > 0, "coarse boundary normals: the coarse mesh has no boundary");
    // Coarse boundary facets by node (CSR).
    std::vector<Index> start(coarse.num_nodes() + 1, 0);
    for (Index f = 0; f < cb.size(); ++f)
        for (Eigen::Index a = 0; a < cb.facets.cols(); ++a) ++start[cb.facets(f, a) + 1];
    for (Index v = 0; v < coarse.num_nodes(); ++v) start[v + 1] += start[v];
    std::vector<Index> by_node(start.back()), fill(start.begin(), start.end() - 1);
    for (Index f = 0; f < cb.size(); ++f)
        for (Eigen::Index a = 0; a < cb.facets.cols(); ++a) by_node[fill[cb.facets(f, a)]++] = f;
    const Matrix box = mesh::bounding_box(coarse);
    const double tol = 1e-12 * (box.row(1) - box.row(0)).norm();
    const mesh::PointLocator locator(coarse);

    Matrix N = fb.normals;
#pragma omp parallel for schedule(dynamic, 256)
    for (Index f = 0; f < fb.size(); ++f) {
        if (fb.component[f] != 0) continue;
        Eigen::VectorXd c = Eigen::VectorXd::Zero(dim);
        for (Eigen::Index a = 0; a < fb.facets.cols(); ++a)
            c += fine.rest_positions.row(fb.facets(f, a)).transpose();
        c /= static_cast<double>(fb.facets.cols());
        const mesh::Location loc = locator.locate_nearest(c);
        std::vector<Index> candidates;
        for (Eigen::Index a = 0; a < coarse.elements.cols(); ++a) {
            const Index v = coarse.elements(loc.element, a);
            candidates.insert(candidates.end(), by_node.begin() + start[v],
                              by_node.begin() + start[v + 1]);
        }
        if (candidates.empty()) {
            candidates.resize(cb.size());
            for (Index g = 0; g < cb.size(); ++g) candidates[g] = g;
        }
        const Eigen::VectorXd n = fb.normals.row(f).transpose();
        double best_hit = std::numeric_limits<double>::infinity();
        double best_dist = std::numeric_limits<double>::infinity();
        Index hit = -1, nearest = -1;
        for (Index g : candidates) {
            Small P(dim, dim);
            for (int a = 0; a < dim; ++a) P.row(a) = coarse.rest_positions.row(cb.facets(g, a));
            const double t = ray_hit(c, n, P, tol);
            if (t < best_hit) {
                best_hit = t;
                hit = g;
            }
            const double d = (closest_on_facet(c, P) - c).norm();
            if (d < best_dist) {
                best_dist = d;
                nearest = g;
            }
        }
        const Index chosen = hit >= 0 ? hit : nearest;
        N.row(f) = cb.normals.row(chosen);
    }
    return N;
}

std::vector<Mandel6> mollifiers(const mesh::Mesh& mesh, const Matrix& h) {
    detail::verify_simplicial(mesh, "mollifiers");
    const int dim = mesh.dim(), n = mandel_size(dim);
    CG_VERIFY(h.rows() == mesh.num_dofs() && h.cols() == n,
              "mollifiers: harmonic fields are {}x{}, expected {}x{}", h.rows(), h.cols(),
              mesh.num_dofs(), n);
    std::vector<Mandel6> G(static_cast<std::size_t>(mesh.num_elements()), Mandel6::Zero());
#pragma omp parallel for schedule(static)
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        const Small g = detail::p1_gradients(mesh, e);
        for (int J = 0; J < n; ++J) {
            Small F = Small::Zero(dim, dim);  // F_ik = d h_i / d x_k
            for (int a = 0; a <= dim; ++a)
                F += h.block(dim * mesh.elements(e, a), J, dim, 1) * g.row(a);
            G[e].col(J).head(n) = mandel_weight(dim, J) * detail::mandel_strain(F);
        }
    }
    return G;
}

Matrix sample_harmonic(const mesh::Mesh& fine, const mesh::PointLocator& locator, const Matrix& h,
                       const Matrix& points, Vector* distance) {
    detail::verify_simplicial(fine, "sample harmonic fields");
    const int dim = fine.dim();
    CG_VERIFY(points.cols() == dim, "sample harmonic fields: {}D points on a {}D mesh",
              points.cols(), dim);
    CG_VERIFY(h.rows() == fine.num_dofs(), "sample harmonic fields: {} rows for {} DOFs", h.rows(),
              fine.num_dofs());
    const Index np = static_cast<Index>(points.rows());
    Matrix H(dim * np, h.cols());
    if (distance) distance->setZero(np);
#pragma omp parallel for schedule(dynamic, 16)
    for (Index i = 0; i < np; ++i) {
        const Eigen::VectorXd p = points.row(i).transpose();
        Index e = -1;
        SmallVec w;
        if (const auto loc = locator.locate(p)) {
            e = loc->element;
            w = loc->weights;
        } else {
            const mesh::Location near = locator.locate_nearest(p);
            e = near.element;
            Eigen::VectorXd x = Eigen::VectorXd::Zero(dim);
            for (int a = 0; a <= dim; ++a)
                x += near.weights[a] * fine.rest_positions.row(fine.elements(e, a)).transpose();
            if (distance) (*distance)[i] = (x - p).norm();
            w = mesh::barycentric_coordinates(fine, e, p);  // extrapolation: negative ones allowed
        }
        H.middleRows(dim * i, dim).setZero();
        for (int a = 0; a <= dim; ++a)
            H.middleRows(dim * i, dim) += w[a] * h.middleRows(dim * fine.elements(e, a), dim);
    }
    return H;
}

}  // namespace coarsegrain::homogenize
