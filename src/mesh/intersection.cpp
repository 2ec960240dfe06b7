#include "coarsegrain/mesh/intersection.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mesh/bvh.hpp"

namespace coarsegrain::mesh {

namespace {

/// A point within kOnPlane * H of a clipping plane lies on it (H: the larger bounding-box
/// extent of the two simplices). Signed distances are computed in coordinates centred on the
/// clipped simplex, from unit normals: their round-off is a few ulps of H (about 1e-15 H), so
/// 1e-14 H absorbs it, while the snapping moves a measure by at most 1e-14 H times a facet.
constexpr double kOnPlane = 1e-14;
/// A clipped measure below kNegligible times the smaller simplex's measure is the round-off
/// left of a lower-dimensional contact (edge or vertex), whose noise is O(1e-16) relative.
constexpr double kNegligible = 1e-13;
/// A simplex is degenerate when its measure is at most kDegenerate h^D (as mesh::validate).
constexpr double kDegenerate = 1e-12;

template <int D>
using Vec = Eigen::Matrix<double, D, 1>;
template <int D>
using Corners = std::array<Vec<D>, D + 1>;

constexpr double factorial(int d) { return d <= 1 ? 1.0 : d * factorial(d - 1); }

/// A simplex with what clipping needs: positively oriented corners, the inward unit normal of
/// each facet (facet i is opposite corner i), its measure and bounding-box extent.
template <int D>
struct Simplex {
    Corners<D> x;
    Corners<D> normal;
    double measure = 0;
    double extent = 0;

    bool degenerate() const { return !(measure > kDegenerate * std::pow(extent, D)); }
};

template <int D>
Simplex<D> make_simplex(const Corners<D>& corners) {
    Simplex<D> s;
    s.x = corners;
    Eigen::Matrix<double, D, D> T;  // edges from corner 0
    for (int k = 0; k < D; ++k) T.col(k) = s.x[k + 1] - s.x[0];
    const double det = T.determinant();
    if (det < 0) {
        std::swap(s.x[1], s.x[2]);
        T.col(0).swap(T.col(1));
    }
    s.measure = std::abs(det) / factorial(D);
    Vec<D> lo = s.x[0], hi = s.x[0];
    for (int k = 1; k <= D; ++k) {
        lo = lo.cwiseMin(s.x[k]);
        hi = hi.cwiseMax(s.x[k]);
    }
    s.extent = (hi - lo).maxCoeff();
    // Row k of T^{-1} is the gradient of barycentric coordinate k+1, and the gradient of
    // coordinate 0 is minus their sum: each points into the simplex, normal to its facet.
    const Eigen::Matrix<double, D, D> G = T.inverse();
    s.normal[0] = -G.colwise().sum().transpose();
    for (int k = 0; k < D; ++k) s.normal[k + 1] = G.row(k).transpose();
    for (auto& n : s.normal) n.normalize();
    return s;
}

template <int D>
Simplex<D> element_simplex(const Mesh& mesh, Index e) {
    Corners<D> x;
    for (int k = 0; k <= D; ++k) x[k] = mesh.rest_positions.row(mesh.elements(e, k)).transpose();
    return make_simplex<D>(x);
}

enum class ClipResult { Unchanged, Clipped, Empty };

/// Signed distances of points to a plane, snapped to 0 within tol; returns their min and max.
template <int D, std::size_t N>
std::pair<double, double> signed_distances(const std::array<Vec<D>, N>& points, int n,
                                           const Vec<D>& normal, double offset, double tol,
                                           std::array<double, N>& s) {
    double smin = std::numeric_limits<double>::infinity(), smax = -smin;
    for (int v = 0; v < n; ++v) {
        s[v] = normal.dot(points[v]) + offset;
        if (std::abs(s[v]) <= tol) s[v] = 0;
        smin = std::min(smin, s[v]);
        smax = std::max(smax, s[v]);
    }
    return {smin, smax};
}

/// The point where the segment from p (distance sp > 0) to q (distance sq < 0) crosses the plane.
template <int D>
Vec<D> crossing(const Vec<D>& p, double sp, const Vec<D>& q, double sq) {
    return p + (sp / (sp - sq)) * (q - p);
}

template <int D>
class Polytope;

/// Convex polygon as a counter-clockwise ring, clipped Sutherland-Hodgman style.
template <>
class Polytope<2> {
  public:
    explicit Polytope(const Corners<2>& x) : m_n(3) { std::copy(x.begin(), x.end(), m_v.begin()); }

    /// Keeps the part where normal . x + offset >= 0.
    ClipResult clip(const Vec<2>& normal, double offset, double tol) {
        std::array<double, kCapacity> s;
        const auto [smin, smax] = signed_distances<2>(m_v, m_n, normal, offset, tol, s);
        if (smin >= 0) return ClipResult::Unchanged;
        if (smax <= 0) return ClipResult::Empty;
        std::array<Vec<2>, kCapacity> out;
        int m = 0;
        for (int i = 0; i < m_n; ++i) {
            const int j = (i + 1) % m_n;
            if (s[i] >= 0) out[m++] = m_v[i];
            if (s[i] > 0 && s[j] < 0) out[m++] = crossing<2>(m_v[i], s[i], m_v[j], s[j]);
            if (s[i] < 0 && s[j] > 0) out[m++] = crossing<2>(m_v[j], s[j], m_v[i], s[i]);
        }
        CG_ASSERT(m <= kCapacity, "Polytope<2>: vertex buffer overflow");
        m_v = out;
        m_n = m;
        return ClipResult::Clipped;
    }

    /// Area by the shoelace formula.
    double measure() const {
        double twice = 0;
        for (int i = 0; i < m_n; ++i) {
            const Vec<2>& p = m_v[i];
            const Vec<2>& q = m_v[(i + 1) % m_n];
            twice += p.x() * q.y() - p.y() * q.x();
        }
        return 0.5 * twice;
    }

  private:
    // A clip keeps k of n vertices and adds one per sign change, at most 2 min(k, n - k), so
    // n grows by at most a factor 1.5 per clip: 3 -> 4 -> 6 -> 9 after the three planes.
    static constexpr int kCapacity = 12;
    std::array<Vec<2>, kCapacity> m_v;
    int m_n;
};

/// Convex polyhedron as a graph of degree-3 vertices with a consistent rotation (each vertex's
/// three neighbours in the same order around it), clipped as in r3d (Powell & Abel 2015): new
/// vertices on the edges that cross the plane are linked by walking the faces. The
/// representation stays valid for any sign pattern, so degenerate input only creates
/// zero-length edges and zero-area faces.
template <>
class Polytope<3> {
  public:
    /// @param[in] x  corners of a positively oriented tet
    explicit Polytope(const Corners<3>& x) : m_n(4) {
        std::copy(x.begin(), x.end(), m_pos.begin());
        m_nbr[0] = {1, 3, 2};
        m_nbr[1] = {2, 3, 0};
        m_nbr[2] = {0, 3, 1};
        m_nbr[3] = {1, 2, 0};
    }

    /// Keeps the part where normal . x + offset >= 0.
    ClipResult clip(const Vec<3>& normal, double offset, double tol) {
        std::array<double, kCapacity> s;
        const auto [smin, smax] = signed_distances<3>(m_pos, m_n, normal, offset, tol, s);
        if (smin >= 0) return ClipResult::Unchanged;
        if (smax <= 0) return ClipResult::Empty;
        // A new vertex on every edge from a kept vertex u (s >= 0) to a clipped one w (s < 0);
        // it takes w's place among u's neighbours, and u is its neighbour 0.
        const int old = m_n;
        for (int u = 0; u < old; ++u) {
            if (s[u] < 0) continue;
            for (int k = 0; k < 3; ++k) {
                const int w = m_nbr[u][k];
                if (s[w] >= 0) continue;
                CG_ASSERT(m_n < kCapacity, "Polytope<3>: vertex buffer overflow");
                m_pos[m_n] = crossing<3>(m_pos[u], s[u], m_pos[w], s[w]);
                m_nbr[m_n] = {u, -1, -1};
                m_nbr[u][k] = m_n++;
            }
        }
        // Walk from each new vertex along the face through its kept neighbour until the next
        // new vertex: that one follows it around the cap face.
        for (int start = old; start < m_n; ++start) {
            int cur = start, next = m_nbr[start][0];
            do {
                const int k = slot(next, cur);
                cur = next;
                next = m_nbr[cur][(k + 1) % 3];
            } while (cur < old);
            m_nbr[start][2] = cur;
            m_nbr[cur][1] = start;
        }
        // Drop the clipped vertices and renumber.
        std::array<int, kCapacity> index;
        int m = 0;
        for (int v = 0; v < m_n; ++v)
            if (v >= old || s[v] >= 0) {
                index[v] = m;
                m_pos[m] = m_pos[v];
                m_nbr[m] = m_nbr[v];
                ++m;
            }
        m_n = m;
        for (int v = 0; v < m_n; ++v)
            for (int& w : m_nbr[v]) w = index[w];
        return ClipResult::Clipped;
    }

    /// Volume by the divergence theorem: a fan of tets from the origin over a fan of triangles
    /// on each face.
    double measure() const {
        std::array<std::array<bool, 3>, kCapacity> done{};
        double six = 0;
        for (int start = 0; start < m_n; ++start)
            for (int k0 = 0; k0 < 3; ++k0) {
                if (done[start][k0]) continue;
                // Face through the edge start -> m_nbr[start][k0]: from a vertex reached from
                // `prev`, the face continues to the neighbour after `prev` in the rotation.
                done[start][k0] = true;
                int cur = m_nbr[start][k0], prev = start;
                while (cur != start) {
                    const int k = (slot(cur, prev) + 1) % 3;
                    done[cur][k] = true;
                    const int next = m_nbr[cur][k];
                    if (next != start) six += m_pos[start].dot(m_pos[next].cross(m_pos[cur]));
                    prev = cur;
                    cur = next;
                }
            }
        return six / 6.0;
    }

  private:
    // A clip keeps k of n vertices and adds one per crossing edge, at most 3 min(k, n - k):
    // at most 2n after compaction (4 -> 8 -> 16 -> 32 after three planes) and 2.5n before it
    // (80 during the fourth).
    static constexpr int kCapacity = 80;

    /// Position of w among v's neighbours.
    int slot(int v, int w) const { return m_nbr[v][0] == w ? 0 : m_nbr[v][1] == w ? 1 : 2; }

    std::array<Vec<3>, kCapacity> m_pos;
    std::array<std::array<int, 3>, kCapacity> m_nbr;
    int m_n;
};

/// Lexicographic order of the corners, to break ties between simplices of equal measure.
template <int D>
bool corners_less(const Simplex<D>& p, const Simplex<D>& q) {
    for (int k = 0; k <= D; ++k)
        for (int d = 0; d < D; ++d)
            if (p.x[k][d] != q.x[k][d]) return p.x[k][d] < q.x[k][d];
    return false;
}

/// |p ∩ q|: the smaller simplex (ties broken by corners_less, so that the result does not
/// depend on the argument order) clipped by the half-spaces of the other.
template <int D>
double clip_measure(const Simplex<D>& p, const Simplex<D>& q) {
    const bool swap = q.measure < p.measure || (q.measure == p.measure && corners_less(q, p));
    const Simplex<D>& a = swap ? q : p;  // clipped
    const Simplex<D>& b = swap ? p : q;  // clipper
    Vec<D> o = Vec<D>::Zero();
    for (const auto& x : a.x) o += x;
    o /= D + 1;
    Corners<D> local;
    for (int k = 0; k <= D; ++k) local[k] = a.x[k] - o;
    Polytope<D> poly(local);
    const double tol = kOnPlane * std::max(a.extent, b.extent);
    bool clipped = false;
    for (int i = 0; i <= D; ++i) {
        // Facet i of b passes through corner i+1: distance n . (x - x_{i+1}) in local coordinates.
        const Vec<D>& n = b.normal[i];
        switch (poly.clip(n, n.dot(o - b.x[(i + 1) % (D + 1)]), tol)) {
            case ClipResult::Empty:
                return 0.0;
            case ClipResult::Clipped:
                clipped = true;
                break;
            case ClipResult::Unchanged:
                break;
        }
    }
    const double m = clipped ? poly.measure() : a.measure;
    return m > kNegligible * a.measure ? m : 0.0;
}

template <int D>
double simplex_measure_impl(const Matrix& a, const Matrix& b) {
    Corners<D> xa, xb;
    for (int k = 0; k <= D; ++k) {
        xa[k] = a.row(k).transpose();
        xb[k] = b.row(k).transpose();
    }
    const Simplex<D> sa = make_simplex<D>(xa), sb = make_simplex<D>(xb);
    for (const auto* s : {&sa, &sb})
        CG_VERIFY(!s->degenerate(),
                  "simplex_intersection_measure: simplex {} is degenerate (measure {:.3g} at "
                  "extent {:.3g})",
                  s == &sa ? "a" : "b", s->measure, s->extent);
    return clip_measure<D>(sa, sb);
}

/// Index of the first degenerate element among those flagged, or -1.
Index first_flagged(const std::vector<char>& flags) {
    const auto it = std::find(flags.begin(), flags.end(), char{1});
    return it == flags.end() ? -1 : static_cast<Index>(it - flags.begin());
}

template <int D>
std::vector<Overlap> intersect_impl(const Mesh& fine, const Mesh& coarse) {
    // The tree goes over the mesh with fewer elements; the other one is looped over in
    // parallel, each element computed once and tested against its candidates.
    const bool tree_is_coarse = coarse.num_elements() <= fine.num_elements();
    const Mesh& tree_mesh = tree_is_coarse ? coarse : fine;
    const Mesh& loop_mesh = tree_is_coarse ? fine : coarse;
    const char* tree_name = tree_is_coarse ? "coarse" : "fine";
    const char* loop_name = tree_is_coarse ? "fine" : "coarse";

    const Index nt = tree_mesh.num_elements(), nl = loop_mesh.num_elements();
    std::vector<Simplex<D>> tree_simplices(static_cast<std::size_t>(nt));
    std::vector<char> tree_bad(static_cast<std::size_t>(nt)),
        loop_bad(static_cast<std::size_t>(nl));
#pragma omp parallel for schedule(static)
    for (Index e = 0; e < nt; ++e) {
        tree_simplices[e] = element_simplex<D>(tree_mesh, e);
        tree_bad[e] = tree_simplices[e].degenerate();
    }
    const Index bad_tree = first_flagged(tree_bad);
    CG_VERIFY(bad_tree < 0, "intersect: element {} of the {} mesh is degenerate (measure {:.3g})",
              bad_tree, tree_name, tree_simplices[bad_tree].measure);
    const AabbTree<D> tree(element_boxes<D>(tree_mesh));

    std::vector<Overlap> found;
#pragma omp parallel
    {
        std::vector<Overlap> local;
#pragma omp for schedule(dynamic, 256) nowait
        for (Index e = 0; e < nl; ++e) {
            const Simplex<D> s = element_simplex<D>(loop_mesh, e);
            if (s.degenerate()) {
                loop_bad[e] = 1;
                continue;
            }
            Box<D> box;
            for (const auto& x : s.x) box.extend(x);
            tree.for_each_overlap(box, [&](Index t) {
                const double m = clip_measure<D>(s, tree_simplices[t]);
                if (m > 0) local.push_back(tree_is_coarse ? Overlap{e, t, m} : Overlap{t, e, m});
            });
        }
#pragma omp critical(coarsegrain_intersect_gather)
        found.insert(found.end(), local.begin(), local.end());
    }
    const Index bad_loop = first_flagged(loop_bad);
    CG_VERIFY(bad_loop < 0, "intersect: element {} of the {} mesh is degenerate (measure {:.3g})",
              bad_loop, loop_name, element_measure(loop_mesh, bad_loop));

    // Counting sort by coarse element, then each coarse element's overlaps by fine element.
    const Index nc = coarse.num_elements();
    std::vector<std::size_t> start(static_cast<std::size_t>(nc) + 1, 0);
    for (const Overlap& o : found) ++start[static_cast<std::size_t>(o.coarse) + 1];
    for (Index c = 0; c < nc; ++c) start[c + 1] += start[c];
    std::vector<Overlap> sorted(found.size());
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (const Overlap& o : found) sorted[next[o.coarse]++] = o;
#pragma omp parallel for schedule(dynamic, 16)
    for (Index c = 0; c < nc; ++c)
        std::sort(sorted.begin() + static_cast<std::ptrdiff_t>(start[c]),
                  sorted.begin() + static_cast<std::ptrdiff_t>(start[c + 1]),
                  [](const Overlap& x, const Overlap& y) { return x.fine < y.fine; });
    return sorted;
}

void check_simplicial(const Mesh& mesh, const char* name) {
    CG_VERIFY(is_simplex(mesh.type),
              "intersect: the {} mesh has {} elements; intersection measures need simplices "
              "(tri or tet)",
              name, element_name(mesh.type));
    CG_VERIFY(mesh.rest_positions.cols() == mesh.dim() &&
                  mesh.elements.cols() == nodes_per_element(mesh.type),
              "intersect: the {} mesh has {} coordinates per node and {} nodes per element, "
              "expected {} and {} for {} elements",
              name, mesh.rest_positions.cols(), mesh.elements.cols(), mesh.dim(),
              nodes_per_element(mesh.type), element_name(mesh.type));
}

}  // namespace

double simplex_intersection_measure(const Matrix& a, const Matrix& b) {
    const bool tri = a.rows() == 3 && a.cols() == 2, tet = a.rows() == 4 && a.cols() == 3;
    CG_VERIFY((tri || tet) && b.rows() == a.rows() && b.cols() == a.cols(),
              "simplex_intersection_measure: corners must be 3x2 (triangles) or 4x3 (tets) for "
              "both simplices, got {}x{} and {}x{}",
              a.rows(), a.cols(), b.rows(), b.cols());
    CG_VERIFY(a.allFinite() && b.allFinite(),
              "simplex_intersection_measure: a corner coordinate is not finite");
    return tri ? simplex_measure_impl<2>(a, b) : simplex_measure_impl<3>(a, b);
}

std::vector<Overlap> intersect(const Mesh& fine, const Mesh& coarse) {
    check_simplicial(fine, "fine");
    check_simplicial(coarse, "coarse");
    CG_VERIFY(fine.dim() == coarse.dim(),
              "intersect: the fine mesh is {}D ({}) but the coarse mesh is {}D ({})", fine.dim(),
              element_name(fine.type), coarse.dim(), element_name(coarse.type));
    return fine.dim() == 2 ? intersect_impl<2>(fine, coarse) : intersect_impl<3>(fine, coarse);
}

}  // namespace coarsegrain::mesh
