#include "coarsegrain/mesh/point_locator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mesh {

namespace {

/// Relative tolerance of "inside": barycentric or reference coordinates may be off [0, 1] by
/// this much, i.e. the point may lie about 1e-10 element sizes outside the element.
constexpr double kInsideTolerance = 1e-10;

template <ElementType T>
struct Traits;
template <>
struct Traits<ElementType::Tri3> {
    static constexpr int dim = 2, nodes = 3;
    static constexpr bool simplex = true;
};
template <>
struct Traits<ElementType::Quad4> {
    static constexpr int dim = 2, nodes = 4;
    static constexpr bool simplex = false;
};
template <>
struct Traits<ElementType::Tet4> {
    static constexpr int dim = 3, nodes = 4;
    static constexpr bool simplex = true;
};
template <>
struct Traits<ElementType::Hex8> {
    static constexpr int dim = 3, nodes = 8;
    static constexpr bool simplex = false;
};

// Reference corners of Quad4 and Hex8 (see ElementType).
constexpr std::array<std::array<int, 3>, 4> kQuadCorners = {
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
constexpr std::array<std::array<int, 3>, 8> kHexCorners = {
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};

template <int D>
constexpr const std::array<int, 3>& q1_corner(int a) {
    if constexpr (D == 2)
        return kQuadCorners[a];
    else
        return kHexCorners[a];
}

template <int D>
using Vec = Eigen::Matrix<double, D, 1>;

// Bilinear/trilinear shape functions at xi and, optionally, their gradients (N by D).
template <int D>
void q1_shape(const Vec<D>& xi, Eigen::Matrix<double, (1 << D), 1>& N,
              Eigen::Matrix<double, (1 << D), D>* dN) {
    for (int a = 0; a < (1 << D); ++a) {
        const auto& c = q1_corner<D>(a);
        std::array<double, D> s{};
        for (int k = 0; k < D; ++k) s[k] = c[k] ? xi[k] : 1.0 - xi[k];
        double prod = 1.0;
        for (int k = 0; k < D; ++k) prod *= s[k];
        N[a] = prod;
        if (dN)
            for (int d = 0; d < D; ++d) {
                double g = c[d] ? 1.0 : -1.0;
                for (int k = 0; k < D; ++k)
                    if (k != d) g *= s[k];
                (*dN)(a, d) = g;
            }
    }
}

// One element's corner positions, N by D.
template <ElementType T>
Eigen::Matrix<double, Traits<T>::nodes, Traits<T>::dim> corners(const Mesh& mesh, Index e) {
    Eigen::Matrix<double, Traits<T>::nodes, Traits<T>::dim> X;
    for (int a = 0; a < Traits<T>::nodes; ++a)
        X.row(a) = mesh.rest_positions.row(mesh.elements(e, a));
    return X;
}

// Barycentric coordinates of p in a simplex (D + 1 values summing to 1).
template <int D>
Eigen::Matrix<double, D + 1, 1> barycentric(const Eigen::Matrix<double, D + 1, D>& X,
                                            const Vec<D>& p) {
    Eigen::Matrix<double, D, D> T;
    for (int k = 0; k < D; ++k) T.col(k) = (X.row(k + 1) - X.row(0)).transpose();
    const Vec<D> lambda = T.partialPivLu().solve(p - X.row(0).transpose());
    Eigen::Matrix<double, D + 1, 1> b;
    b[0] = 1.0 - lambda.sum();
    b.template tail<D>() = lambda;
    return b;
}

// Inverse of the bilinear/trilinear map by Newton's method from the element centre. Returns
// false if it does not converge (only possible for points well outside the element).
template <int D>
bool q1_inverse(const Eigen::Matrix<double, (1 << D), D>& X, const Vec<D>& p, Vec<D>& xi) {
    xi.setConstant(0.5);
    Eigen::Matrix<double, (1 << D), 1> N;
    Eigen::Matrix<double, (1 << D), D> dN;
    for (int it = 0; it < 30; ++it) {
        q1_shape<D>(xi, N, &dN);
        const Vec<D> r = X.transpose() * N - p;
        const Eigen::Matrix<double, D, D> J = X.transpose() * dN;
        const double det = J.determinant();
        if (!(std::abs(det) > 0)) return false;
        const Vec<D> step = J.inverse() * r;
        xi -= step;
        if (!xi.allFinite() || xi.cwiseAbs().maxCoeff() > 1e3) return false;
        if (step.cwiseAbs().maxCoeff() < 1e-15) return true;
    }
    // Quadratic convergence reaches 1e-15 in a handful of steps from inside the element; a
    // slow tail means p is outside, where the verdict is decided by the range test anyway.
    q1_shape<D>(xi, N, nullptr);
    return (X.transpose() * N - p).norm() <=
           1e-12 * (X.colwise().maxCoeff() - X.colwise().minCoeff()).norm();
}

template <class V>
Location make_location(Index e, const V& local, const Eigen::VectorXd& weights) {
    Location loc;
    loc.element = e;
    loc.local = local;
    loc.weights = weights;
    return loc;
}

// Local coordinates and weights of p in element e if it lies inside within kInsideTolerance.
template <ElementType T>
bool contains(const Mesh& mesh, Index e, const Vec<Traits<T>::dim>& p, Location* out) {
    constexpr int D = Traits<T>::dim;
    const auto X = corners<T>(mesh, e);
    if constexpr (Traits<T>::simplex) {
        const Eigen::Matrix<double, D + 1, 1> b = barycentric<D>(X, p);
        if (!(b.minCoeff() >= -kInsideTolerance)) return false;
        if (out) *out = make_location(e, b, b);
        return true;
    } else {
        Vec<D> xi;
        if (!q1_inverse<D>(X, p, xi)) return false;
        if (!(xi.minCoeff() >= -kInsideTolerance && xi.maxCoeff() <= 1.0 + kInsideTolerance))
            return false;
        if (out) {
            Eigen::Matrix<double, (1 << D), 1> N;
            q1_shape<D>(xi, N, nullptr);
            *out = make_location(e, xi, N);
        }
        return true;
    }
}

// Closest point of triangle (a, b, c) to p, as barycentric weights on a, b, c (Ericson,
// Real-Time Collision Detection, 5.1.5). Works in 2D and 3D.
template <int D>
Eigen::Vector3d closest_on_triangle(const Vec<D>& p, const Vec<D>& a, const Vec<D>& b,
                                    const Vec<D>& c) {
    const Vec<D> ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
    const Vec<D> bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        return {1 - v, v, 0};
    }
    const Vec<D> cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        return {1 - w, 0, w};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0, 1 - w, w};
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    return {1 - v - w, v, w};
}

// Nearest point of element e to p: squared distance, local coordinates and weights.
template <ElementType T>
double nearest_in_element(const Mesh& mesh, Index e, const Vec<Traits<T>::dim>& p, Location* out) {
    constexpr int D = Traits<T>::dim;
    constexpr int N = Traits<T>::nodes;
    const auto X = corners<T>(mesh, e);
    if constexpr (Traits<T>::simplex) {
        Eigen::Matrix<double, N, 1> w;
        if constexpr (D == 2) {
            w = closest_on_triangle<2>(p, X.row(0).transpose(), X.row(1).transpose(),
                                       X.row(2).transpose());
        } else {
            w = barycentric<3>(X, p);
            if (w.minCoeff() < 0) {
                // Outside: the nearest point is on one of the faces (the tet's own facets).
                static constexpr std::array<std::array<int, 3>, 4> faces = {
                    {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {0, 2, 1}}};
                double best = std::numeric_limits<double>::infinity();
                for (const auto& f : faces) {
                    const Eigen::Vector3d b =
                        closest_on_triangle<3>(p, X.row(f[0]).transpose(), X.row(f[1]).transpose(),
                                               X.row(f[2]).transpose());
                    const Vec<3> q = b[0] * X.row(f[0]) + b[1] * X.row(f[1]) + b[2] * X.row(f[2]);
                    const double d = (q - p).squaredNorm();
                    if (d < best) {
                        best = d;
                        w.setZero();
                        for (int k = 0; k < 3; ++k) w[f[k]] = b[k];
                    }
                }
            }
        }
        const Vec<D> q = X.transpose() * w;
        if (out) *out = make_location(e, w, w);
        return (q - p).squaredNorm();
    } else {
        // Projected Gauss-Newton on min |x(xi) - p|^2 over the box [0,1]^D, from the centre
        // (Bertsekas' projected Newton: coordinates at a bound whose gradient points outward
        // are held fixed, the step is projected back and halved until the distance decreases).
        Vec<D> xi = Vec<D>::Constant(0.5);
        Eigen::Matrix<double, N, 1> Nv;
        Eigen::Matrix<double, N, D> dN;
        q1_shape<D>(xi, Nv, &dN);
        Vec<D> r = X.transpose() * Nv - p;
        double f = r.squaredNorm();
        for (int it = 0; it < 50; ++it) {
            const Eigen::Matrix<double, D, D> J = X.transpose() * dN;
            const Vec<D> g = J.transpose() * r;
            Eigen::Matrix<double, D, D> H = J.transpose() * J;
            Vec<D> rhs = -g;
            for (int k = 0; k < D; ++k) {
                const bool fixed = (xi[k] <= 0 && g[k] > 0) || (xi[k] >= 1 && g[k] < 0);
                if (!fixed) continue;
                H.row(k).setZero();
                H.col(k).setZero();
                H(k, k) = 1;
                rhs[k] = 0;
            }
            const Vec<D> step = H.ldlt().solve(rhs);
            bool accepted = false;
            Vec<D> trial;
            for (double alpha = 1.0; alpha > 1e-12; alpha *= 0.5) {
                trial = (xi + alpha * step).cwiseMax(0.0).cwiseMin(1.0);
                q1_shape<D>(trial, Nv, &dN);
                const Vec<D> rt = X.transpose() * Nv - p;
                if (rt.squaredNorm() <= f) {
                    accepted = true;
                    r = rt;
                    f = rt.squaredNorm();
                    break;
                }
            }
            if (!accepted) break;
            const double moved = (trial - xi).cwiseAbs().maxCoeff();
            xi = trial;
            if (moved < 1e-14) break;
        }
        if (out) {
            q1_shape<D>(xi, Nv, nullptr);
            *out = make_location(e, xi, Nv);
        }
        return f;
    }
}

}  // namespace

struct PointLocator::Impl {
    const Mesh* mesh = nullptr;
    int dim = 0;
    std::vector<double> boxes;  // per element: lo (dim), hi (dim), enlarged by the tolerance
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Eigen::Vector3d cell = Eigen::Vector3d::Ones();  // bucket size per axis
    Eigen::Vector3i counts = Eigen::Vector3i::Ones();
    Eigen::Vector3d box_hi = Eigen::Vector3d::Zero();
    double margin = 0;         // how far outside the mesh box a point may still be inside
    std::vector<Index> start;  // CSR over buckets
    std::vector<Index> items;  // element indices per bucket

    Index bucket_index(const Eigen::Vector3i& c) const {
        return c[0] + counts[0] * (c[1] + counts[1] * c[2]);
    }

    Eigen::Vector3i bucket_of(const double* p) const {
        Eigen::Vector3i c = Eigen::Vector3i::Zero();
        for (int d = 0; d < dim; ++d) {
            const double t = std::floor((p[d] - origin[d]) / cell[d]);
            c[d] = static_cast<int>(std::clamp(t, 0.0, static_cast<double>(counts[d] - 1)));
        }
        return c;
    }

    bool in_box(Index e, const double* p) const {
        const double* b = &boxes[static_cast<size_t>(2 * dim) * e];
        for (int d = 0; d < dim; ++d)
            if (p[d] < b[d] || p[d] > b[dim + d]) return false;
        return true;
    }

    double box_distance2(Index e, const double* p) const {
        const double* b = &boxes[static_cast<size_t>(2 * dim) * e];
        double s = 0;
        for (int d = 0; d < dim; ++d) {
            const double t = std::max({b[d] - p[d], 0.0, p[d] - b[dim + d]});
            s += t * t;
        }
        return s;
    }

    template <ElementType T>
    std::optional<Location> locate(const Vec<Traits<T>::dim>& p) const {
        for (int d = 0; d < dim; ++d)
            if (!(p[d] >= origin[d] - margin && p[d] <= box_hi[d] + margin)) return std::nullopt;
        const Index b = bucket_index(bucket_of(p.data()));
        Location loc;
        for (Index i = start[b]; i < start[b + 1]; ++i) {
            const Index e = items[i];
            if (in_box(e, p.data()) && contains<T>(*mesh, e, p, &loc)) return loc;
        }
        return std::nullopt;
    }

    template <ElementType T>
    void build() {
        constexpr int D = Traits<T>::dim;
        const Mesh& m = *mesh;
        const Index ne = m.num_elements();
        dim = D;
        boxes.resize(static_cast<size_t>(2 * D) * ne);
#pragma omp parallel for schedule(static)
        for (Index e = 0; e < ne; ++e) {
            const auto X = corners<T>(m, e);
            const Vec<D> lo = X.colwise().minCoeff(), hi = X.colwise().maxCoeff();
            const double pad = kInsideTolerance * (hi - lo).maxCoeff();
            for (int d = 0; d < D; ++d) {
                boxes[2 * D * e + d] = lo[d] - pad;
                boxes[2 * D * e + D + d] = hi[d] + pad;
            }
        }
        const Matrix box = bounding_box(m);
        Eigen::Vector3d extent = Eigen::Vector3d::Ones();
        for (int d = 0; d < D; ++d) {
            origin[d] = box(0, d);
            box_hi[d] = box(1, d);
            extent[d] = box(1, d) - box(0, d);
        }
        const double diameter = extent.head(D).norm();
        margin = kInsideTolerance * diameter;
        // About one bucket per element: cubic (square) buckets of the average element volume.
        double volume = 1;
        for (int d = 0; d < D; ++d) volume *= std::max(extent[d], 1e-12 * diameter);
        const double h = std::pow(volume / static_cast<double>(ne), 1.0 / D);
        for (int d = 0; d < D; ++d) {
            const double n = std::clamp(std::ceil(extent[d] / h), 1.0, 1e6);
            counts[d] = static_cast<int>(n);
            cell[d] = extent[d] > 0 ? extent[d] / n : 1.0;
        }

        const auto bucket_range = [&](Index e, Eigen::Vector3i& lo, Eigen::Vector3i& hi) {
            lo = bucket_of(&boxes[2 * D * e]);
            hi = bucket_of(&boxes[2 * D * e + D]);
        };
        const Index nb = counts.prod();
        start.assign(static_cast<size_t>(nb) + 1, 0);
        Eigen::Vector3i lo, hi;
        for (int pass = 0; pass < 2; ++pass) {
            std::vector<Index> fill;
            if (pass == 1) {
                for (Index b = 0; b < nb; ++b) start[b + 1] += start[b];
                items.resize(static_cast<size_t>(start[nb]));
                fill.assign(start.begin(), start.end() - 1);
            }
            for (Index e = 0; e < ne; ++e) {
                bucket_range(e, lo, hi);
                for (int k = lo[2]; k <= hi[2]; ++k)
                    for (int j = lo[1]; j <= hi[1]; ++j)
                        for (int i = lo[0]; i <= hi[0]; ++i) {
                            const Index b = bucket_index(Eigen::Vector3i(i, j, k));
                            if (pass == 0)
                                ++start[b + 1];
                            else
                                items[fill[b]++] = e;
                        }
            }
        }
    }

    // Visits the buckets at Chebyshev distance ring from c, stopping when no closer element
    // can remain: a bucket ring r + 1 away from the bucket of q (p clamped to the mesh box)
    // is at least r * min(cell) from q, hence sqrt(|p - q|^2 + (r min(cell))^2) from p.
    template <ElementType T>
    Location nearest(const Vec<Traits<T>::dim>& p) const {
        constexpr int D = Traits<T>::dim;
        Vec<D> q;
        for (int d = 0; d < D; ++d) q[d] = std::clamp(p[d], origin[d], box_hi[d]);
        const double outside2 = (p - q).squaredNorm();
        const Eigen::Vector3i c = bucket_of(q.data());
        const double hmin = cell.head(D).minCoeff();
        const int max_ring = counts.head(D).maxCoeff();
        double best = std::numeric_limits<double>::infinity();
        Location best_loc, loc;
        for (int ring = 0; ring <= max_ring; ++ring) {
            Eigen::Vector3i lo = Eigen::Vector3i::Zero(), hi = Eigen::Vector3i::Zero();
            for (int d = 0; d < D; ++d) {
                lo[d] = std::max(c[d] - ring, 0);
                hi[d] = std::min(c[d] + ring, counts[d] - 1);
            }
            const auto visit = [&](int i, int j, int k) {
                const Index b = bucket_index(Eigen::Vector3i(i, j, k));
                for (Index s = start[b]; s < start[b + 1]; ++s) {
                    const Index e = items[s];
                    if (box_distance2(e, p.data()) >= best) continue;
                    const double d2 = nearest_in_element<T>(*mesh, e, p, &loc);
                    if (d2 < best || (d2 == best && e < best_loc.element)) {
                        best = d2;
                        best_loc = loc;
                    }
                }
            };
            for (int k = lo[2]; k <= hi[2]; ++k)
                for (int j = lo[1]; j <= hi[1]; ++j) {
                    if (std::max(std::abs(j - c[1]), std::abs(k - c[2])) == ring) {
                        for (int i = lo[0]; i <= hi[0]; ++i) visit(i, j, k);
                    } else {
                        if (c[0] - ring >= 0) visit(c[0] - ring, j, k);
                        if (ring > 0 && c[0] + ring < counts[0]) visit(c[0] + ring, j, k);
                    }
                }
            const double bound = ring * hmin;
            if (best <= outside2 + bound * bound) break;
        }
        return best_loc;
    }
};

PointLocator::PointLocator(const Mesh& mesh) : m_impl(std::make_unique<Impl>()) {
    CG_VERIFY(mesh.num_elements() > 0, "point locator: the {} mesh has no elements",
              element_name(mesh.type));
    CG_VERIFY(mesh.elements.cols() == nodes_per_element(mesh.type) &&
                  mesh.rest_positions.cols() == mesh.dim(),
              "point locator: a {} mesh needs {} nodes per element and {} coordinates, got {} "
              "and {}",
              element_name(mesh.type), nodes_per_element(mesh.type), mesh.dim(),
              mesh.elements.cols(), mesh.rest_positions.cols());
    m_impl->mesh = &mesh;
    switch (mesh.type) {
        case ElementType::Tri3:
            m_impl->build<ElementType::Tri3>();
            break;
        case ElementType::Quad4:
            m_impl->build<ElementType::Quad4>();
            break;
        case ElementType::Tet4:
            m_impl->build<ElementType::Tet4>();
            break;
        case ElementType::Hex8:
            m_impl->build<ElementType::Hex8>();
            break;
    }
}

PointLocator::~PointLocator() = default;
PointLocator::PointLocator(PointLocator&&) noexcept = default;
PointLocator& PointLocator::operator=(PointLocator&&) noexcept = default;

std::optional<Location> PointLocator::locate(const Eigen::VectorXd& p) const {
    const int dim = m_impl->dim;
    CG_VERIFY(p.size() == dim, "point locator: a point in a {}D mesh needs {} coordinates, got {}",
              dim, dim, p.size());
    CG_VERIFY(p.allFinite(), "point locator: the point has a non-finite coordinate");
    switch (m_impl->mesh->type) {
        case ElementType::Tri3:
            return m_impl->locate<ElementType::Tri3>(p);
        case ElementType::Quad4:
            return m_impl->locate<ElementType::Quad4>(p);
        case ElementType::Tet4:
            return m_impl->locate<ElementType::Tet4>(p);
        case ElementType::Hex8:
            return m_impl->locate<ElementType::Hex8>(p);
    }
    return std::nullopt;
}

Location PointLocator::locate_nearest(const Eigen::VectorXd& p) const {
    if (std::optional<Location> inside = locate(p)) return *std::move(inside);
    switch (m_impl->mesh->type) {
        case ElementType::Tri3:
            return m_impl->nearest<ElementType::Tri3>(p);
        case ElementType::Quad4:
            return m_impl->nearest<ElementType::Quad4>(p);
        case ElementType::Tet4:
            return m_impl->nearest<ElementType::Tet4>(p);
        case ElementType::Hex8:
            return m_impl->nearest<ElementType::Hex8>(p);
    }
    return {};
}

Eigen::VectorXd barycentric_coordinates(const Mesh& mesh, Index e, const Eigen::VectorXd& p) {
    CG_VERIFY(is_simplex(mesh.type), "barycentric coordinates need a simplex, got {}",
              element_name(mesh.type));
    const int dim = mesh.dim();
    const Eigen::VectorXd x0 = mesh.rest_positions.row(mesh.elements(e, 0)).transpose();
    Matrix D(dim, dim);
    for (int i = 0; i < dim; ++i)
        D.col(i) = mesh.rest_positions.row(mesh.elements(e, i + 1)).transpose() - x0;
    const Eigen::FullPivLU<Matrix> lu(D);
    CG_VERIFY(lu.isInvertible(), "element {} is degenerate", e);
    const Eigen::VectorXd t = lu.solve(p - x0);
    Eigen::VectorXd l(dim + 1);
    l[0] = 1.0 - t.sum();
    l.tail(dim) = t;
    return l;
}

Eigen::VectorXd interpolate(const Mesh& mesh, const Location& loc, const Vector& field,
                            int components) {
    CG_VERIFY(
        components >= 1 && field.size() == static_cast<Eigen::Index>(components) * mesh.num_nodes(),
        "interpolate: a field with {} components per node on {} nodes needs {} values, "
        "got {}",
        components, mesh.num_nodes(), static_cast<long>(components) * mesh.num_nodes(),
        field.size());
    CG_VERIFY(loc.element >= 0 && loc.element < mesh.num_elements() &&
                  loc.weights.size() == mesh.elements.cols(),
              "interpolate: location in element {} with {} weights does not fit a mesh of {} {} "
              "elements",
              loc.element, loc.weights.size(), mesh.num_elements(), element_name(mesh.type));
    Eigen::VectorXd value = Eigen::VectorXd::Zero(components);
    for (Index a = 0; a < mesh.elements.cols(); ++a)
        value += loc.weights[a] * field.segment(static_cast<Eigen::Index>(components) *
                                                    mesh.elements(loc.element, a),
                                                components);
    return value;
}

}  // namespace coarsegrain::mesh
