#include "coarsegrain/fem/rs_warp.hpp"

#include <algorithm>
#include <array>
#include <numeric>
#include <string>

#include "coarsegrain/common/error.hpp"
#include "element_kernels.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem {

namespace {

template <int D>
using Square = Eigen::Matrix<double, D, D>;

/// Cay(A) - I = 4 / (4 + θ²) (A + A²/2) of a skew A, θ² = -tr(A²)/2 = |A|_F²/2 (the squared
/// angle of the infinitesimal rotation A in 2D and 3D). Kept apart from I so that RS loses no
/// digits to cancellation when the rotation is small.
template <int D>
Square<D> cayley_minus_identity(const Square<D>& A) {
    const Square<D> A2 = A * A;
    return (4.0 / (4.0 - 0.5 * A2.trace())) * (A + 0.5 * A2);
}

/// RS(G) = Cay(W)(I + E) - I = E + C + C E with W, E the skew and symmetric parts of G and
/// C = Cay(W) - I: exact for a symmetric G (C = 0).
template <int D>
Square<D> rs_of(const Square<D>& G) {
    const Square<D> E = 0.5 * (G + G.transpose());
    const Square<D> C = cayley_minus_identity<D>(0.5 * (G - G.transpose()));
    Square<D> RS = E + C;
    RS.noalias() += C * E;
    return RS;
}

/// Quadrature points per element: those of the stiffness matrix (2^dim Gauss points on Q1, the
/// centroid on P1).
template <class S>
inline constexpr int kPoints = S::simplex ? 1 : (S::dim == 2 ? 4 : 8);

template <class S>
kernels::Rule<S::dim, kPoints<S>> warp_rule() {
    if constexpr (S::simplex) {
        kernels::Rule<S::dim, 1> rule;
        rule.points[0] = S::centre();
        rule.weights[0] = S::reference_measure();
        return rule;
    } else {
        return S::stiffness_rule();
    }
}

const char* component_name(int i) { return i == 0 ? "x" : i == 1 ? "y" : "z"; }

/// Connected parts of the mesh (nodes sharing an element): part[v] = smallest node of v's part.
/// A node in no element is a part of its own.
std::vector<Index> connected_parts(const mesh::Mesh& mesh) {
    const Index nv = mesh.num_nodes();
    std::vector<Index> parent(static_cast<std::size_t>(nv));
    std::iota(parent.begin(), parent.end(), 0);
    const auto root = [&](Index v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    for (Index e = 0; e < mesh.num_elements(); ++e)
        for (Index a = 1; a < mesh.elements.cols(); ++a) {
            const Index r = root(mesh.elements(e, a)), s = root(mesh.elements(e, 0));
            if (r != s) parent[std::max(r, s)] = std::min(r, s);
        }
    for (Index v = 0; v < nv; ++v) parent[v] = root(v);
    return parent;
}

/// Components whose prescribed nodes are the same share one factorization.
struct WarpGroup {
    std::vector<int> components;
    IndexVector free_nodes;  ///< ascending
    Matrix offset;           ///< free_nodes x components: -L_fd v_d, the prescribed values' part
    solve::SpdSolver solver;
};

/// Everything a warp keeps from its construction.
struct WarpData {
    mesh::ElementType type = mesh::ElementType::Tet4;
    int dim = 3;
    Index num_nodes = 0;
    IndexMatrix elements;
    /// Physical shape gradients (npe x dim, column major; at gradient_offset) and weights
    /// (reference weight times det J) of every (element, point), or of one element if `shared`.
    /// Stored rather than recomputed per warp: on the distorted 64x16x16 hexes (26 MB of them)
    /// the RS phase took 10.6 ms on one thread against 14.6 ms recomputing the Jacobians from
    /// the corners, and 23.5 ms through a sparse gradient operator (G = D U, b = Dᵀ RS with
    /// Eigen's sparse products; bench/bench_rs_warp.cpp). The loop is compute bound: a regular
    /// grid's one shared set is no faster than per-element data.
    std::vector<double> gradients;
    std::vector<double> weights;
    bool shared = false;
    detail::NodeElements incidence;
    Vector prescribed;  ///< num_dofs: bc's values on its DOFs, 0 elsewhere
    std::vector<WarpGroup> groups;
    mutable std::vector<double> element_rhs;  ///< scratch: npe x dim per element
};

/// Offset of the gradients of quadrature point q of slot (element, or 0 if shared).
template <class S>
std::size_t gradient_offset(Index slot, int q) {
    return (static_cast<std::size_t>(slot) * kPoints<S> + q) * S::npe * S::dim;
}

/// Fills the gradients and weights of every quadrature point (of one cell on a regular grid).
template <class S>
void quadrature_data(const mesh::Mesh& mesh, WarpData& w) {
    constexpr int D = S::dim, npe = S::npe, nq = kPoints<S>;
    const auto rule = warp_rule<S>();
    const auto fill = [&](const kernels::Coords<S>& X, Index slot) {
        for (int q = 0; q < nq; ++q) {
            double detJ = 0;
            Eigen::Map<Eigen::Matrix<double, npe, D>>(w.gradients.data() +
                                                      gradient_offset<S>(slot, q)) =
                kernels::physical_gradients<S>(X, rule.points[q], detJ);
            w.weights[slot * nq + q] = rule.weights[q] * detJ;
        }
    };
    w.shared = false;
    if constexpr (!S::simplex) w.shared = mesh.grid.has_value();
    const Index slots = w.shared ? 1 : mesh.num_elements();
    w.gradients.resize(static_cast<std::size_t>(slots) * nq * npe * D);
    w.weights.resize(static_cast<std::size_t>(slots) * nq);
    if constexpr (!S::simplex) {
        if (w.shared) {
            fill(kernels::grid_cell<S>(*mesh.grid), 0);
            return;
        }
    }
    detail::parallel_for(slots, [&](Index e) {
        detail::for_element(e, [&] { fill(kernels::element_coords<S>(mesh, e), e); });
    });
}

/// The scalar Laplacian L_ab = Σ_q w_q ∇N_a · ∇N_b (num_nodes square, both triangles). Each
/// node's column is gathered from its incident elements, their column of the element matrix
/// computed on the spot from the stored gradients (race free, no element matrices kept).
template <class S>
void laplacian(const mesh::Mesh& mesh, const WarpData& w, SparseMatrix& L) {
    constexpr int D = S::dim, npe = S::npe, nq = kPoints<S>;
    const Index nv = mesh.num_nodes();
    const detail::NodeGraph graph = detail::node_graph(mesh, w.incidence);
    detail::block_pattern(graph, 1, true, true, L);
    const Index* outer = L.outerIndexPtr();
    double* values = L.valuePtr();
#pragma omp parallel if (nv >= detail::kMinParallel)
    {
        std::vector<Index> position(static_cast<std::size_t>(nv), 0);
#pragma omp for schedule(static)
        for (Index v = 0; v < nv; ++v) {
            for (Index p = graph.ptr[v]; p < graph.ptr[v + 1]; ++p)
                position[graph.adj[p]] = p - graph.ptr[v];
            for (Index k = w.incidence.ptr[v]; k < w.incidence.ptr[v + 1]; ++k) {
                const Index e = w.incidence.element[k], slot = w.shared ? 0 : e;
                const int b = w.incidence.local[k];
                Eigen::Matrix<double, npe, 1> column = Eigen::Matrix<double, npe, 1>::Zero();
                for (int q = 0; q < nq; ++q) {
                    const Eigen::Map<const Eigen::Matrix<double, npe, D>> G(
                        w.gradients.data() + gradient_offset<S>(slot, q));
                    column.noalias() += (w.weights[slot * nq + q] * G) * G.row(b).transpose();
                }
                for (int a = 0; a < npe; ++a)
                    values[outer[v] + position[mesh.elements(e, a)]] += column[a];
            }
        }
    }
}

/// b_e = Σ_q w_q ∇N RS(∇u)ᵀ (npe x dim, row a = node a's right-hand side) of every element.
template <class S>
void element_right_hand_sides(const WarpData& w, const Vector& u) {
    constexpr int D = S::dim, npe = S::npe, nq = kPoints<S>;
    const Index ne = static_cast<Index>(w.elements.rows());
    w.element_rhs.resize(static_cast<std::size_t>(ne) * npe * D);
#pragma omp parallel for schedule(static) if (ne >= detail::kMinParallel)
    for (Index e = 0; e < ne; ++e) {
        Eigen::Matrix<double, npe, D> U;
        for (int a = 0; a < npe; ++a) U.row(a) = u.segment<D>(D * w.elements(e, a)).transpose();
        const Index slot = w.shared ? 0 : e;
        Eigen::Map<Eigen::Matrix<double, npe, D>> b(w.element_rhs.data() +
                                                    static_cast<std::size_t>(e) * npe * D);
        b.setZero();
        for (int q = 0; q < nq; ++q) {
            const Eigen::Map<const Eigen::Matrix<double, npe, D>> G(w.gradients.data() +
                                                                    gradient_offset<S>(slot, q));
            const Square<D> grad_u = U.transpose() * G;  // (i, k) = du_i / dx_k
            const Square<D> RS = w.weights[slot * nq + q] * rs_of<D>(grad_u);
            b.noalias() += G * RS.transpose();
        }
    }
}

/// B (num_nodes x dim) = the element right-hand sides gathered per node.
template <class S>
Matrix gather_right_hand_sides(const WarpData& w) {
    constexpr int D = S::dim, npe = S::npe;
    Eigen::Matrix<double, Eigen::Dynamic, D, Eigen::RowMajor> B(w.num_nodes, D);
#pragma omp parallel for schedule(static) if (w.num_nodes >= detail::kMinParallel)
    for (Index v = 0; v < w.num_nodes; ++v) {
        Eigen::Matrix<double, 1, D> sum = Eigen::Matrix<double, 1, D>::Zero();
        for (Index k = w.incidence.ptr[v]; k < w.incidence.ptr[v + 1]; ++k) {
            const Eigen::Map<const Eigen::Matrix<double, npe, D>> b(
                w.element_rhs.data() + static_cast<std::size_t>(w.incidence.element[k]) * npe * D);
            sum += b.row(w.incidence.local[k]);
        }
        B.row(v) = sum;
    }
    return B;
}

}  // namespace

struct RsWarp::Impl : WarpData {};

Matrix cayley(const Matrix& A) {
    const Index n = A.rows();
    CG_VERIFY((n == 2 || n == 3) && A.cols() == n, "cayley: A is {}x{}, expected 2x2 or 3x3",
              A.rows(), A.cols());
    CG_VERIFY((A + A.transpose()).norm() <= 1e-12 * (1.0 + A.norm()),
              "cayley: A is not skew (|A + Aᵀ| = {:.3g}); Cay maps skew matrices to rotations",
              (A + A.transpose()).norm());
    if (n == 2) return Square<2>::Identity() + cayley_minus_identity<2>(A);
    return Square<3>::Identity() + cayley_minus_identity<3>(A);
}

Matrix rs_transform(const Matrix& G) {
    const Index n = G.rows();
    CG_VERIFY((n == 2 || n == 3) && G.cols() == n, "rs_transform: G is {}x{}, expected 2x2 or 3x3",
              G.rows(), G.cols());
    if (n == 2) return rs_of<2>(G);
    return rs_of<3>(G);
}

RsWarp::RsWarp(const mesh::Mesh& mesh, const Dirichlet& bc, const solve::SolverOptions& options,
               Timings* timings)
    : m_impl(std::make_unique<Impl>()) {
    Impl& w = *m_impl;
    w.type = mesh.type;
    w.dim = mesh.dim();
    w.num_nodes = mesh.num_nodes();
    const int dim = w.dim;
    const Index n = mesh.num_dofs();
    CG_VERIFY(mesh.rest_positions.cols() == dim && w.num_nodes > 0,
              "RsWarp: the mesh has {} nodes with {} coordinates, expected at least one with {}",
              mesh.rest_positions.rows(), mesh.rest_positions.cols(), dim);
    CG_VERIFY(mesh.elements.cols() == mesh::nodes_per_element(mesh.type),
              "RsWarp: the mesh's elements have {} nodes, a {} has {}", mesh.elements.cols(),
              mesh::element_name(mesh.type), mesh::nodes_per_element(mesh.type));
    CG_VERIFY(mesh.num_elements() == 0 ||
                  (mesh.elements.minCoeff() >= 0 && mesh.elements.maxCoeff() < w.num_nodes),
              "RsWarp: an element refers to a node outside 0..{}", w.num_nodes - 1);
    CG_VERIFY(static_cast<std::size_t>(bc.values.size()) == bc.dofs.size(),
              "RsWarp: {} Dirichlet DOFs but {} values", bc.dofs.size(), bc.values.size());
    try {
        free_dofs(n, bc);  // validates bc: sorted, unique, in range
    } catch (const Error& error) {
        error.rethrow_with(fmt::format("RsWarp: {}", error.what()));
    }
    CG_VERIFY(bc.values.allFinite(), "RsWarp: a Dirichlet value is not finite");
    w.elements = mesh.elements;
    w.prescribed = Vector::Zero(n);
    std::vector<char> fixed(static_cast<std::size_t>(n), 0);
    for (std::size_t k = 0; k < bc.dofs.size(); ++k) {
        w.prescribed[bc.dofs[k]] = bc.values[static_cast<Index>(k)];
        fixed[bc.dofs[k]] = 1;
    }

    // A component's Laplacian is singular on a connected part where it is prescribed nowhere.
    const std::vector<Index> part = connected_parts(mesh);
    for (int i = 0; i < dim; ++i) {
        std::vector<char> held(static_cast<std::size_t>(w.num_nodes), 0);
        for (Index v = 0; v < w.num_nodes; ++v)
            if (fixed[dim * v + i]) held[part[v]] = 1;
        Index v = 0;
        while (v < w.num_nodes && held[part[v]]) ++v;
        CG_VERIFY(v == w.num_nodes,
                  "RsWarp: no node of the connected part of the mesh containing node {} ({} "
                  "nodes) has its {} component prescribed, so the warp's Laplacian is singular "
                  "there; prescribe it at one node of every part at least",
                  v, std::count(part.begin(), part.end(), part[v]), component_name(i));
    }

    SparseMatrix L;
    {
        const Phase phase("assemble", timings);
        w.incidence = detail::node_elements(mesh);
        try {
            kernels::dispatch(mesh.type, [&](auto shape) {
                using S = decltype(shape);
                quadrature_data<S>(mesh, w);
                laplacian<S>(mesh, w, L);
            });
        } catch (const Error& error) {
            error.rethrow_with(fmt::format("RsWarp: {}", error.what()));
        }
    }

    // Group the components by their prescribed nodes.
    std::vector<std::vector<int>> groups;
    for (int i = 0; i < dim; ++i) {
        const auto same = [&](const std::vector<int>& g) {
            for (Index v = 0; v < w.num_nodes; ++v)
                if (fixed[dim * v + g[0]] != fixed[dim * v + i]) return false;
            return true;
        };
        const auto it = std::find_if(groups.begin(), groups.end(), same);
        if (it == groups.end())
            groups.push_back({i});
        else
            it->push_back(i);
    }
    solve::SolverOptions scalar = options;
    scalar.node_dofs = 1;
    scalar.keep_order = false;
    scalar.lower_triangle = false;
    for (const std::vector<int>& components : groups) {
        const int c0 = components[0];
        Dirichlet held;
        for (Index v = 0; v < w.num_nodes; ++v)
            if (fixed[dim * v + c0]) held.dofs.push_back(v);
        if (static_cast<Index>(held.dofs.size()) == w.num_nodes) continue;  // nothing free
        held.values = Vector::Zero(static_cast<Index>(held.dofs.size()));
        Phase assemble("assemble", timings);
        const ReducedSystem sys = reduce(L, Vector::Zero(w.num_nodes), held);
        WarpGroup g{components, sys.free_dofs,
                    Matrix::Zero(sys.free_dofs.size(), static_cast<Index>(components.size())),
                    solve::SpdSolver(scalar)};
        // offset = -L_fd v_d, read from the prescribed nodes' columns.
        std::vector<Index> reduced(static_cast<std::size_t>(w.num_nodes), -1);
        for (Index r = 0; r < g.free_nodes.size(); ++r) reduced[g.free_nodes[r]] = r;
        for (const Index d : held.dofs) {
            for (SparseMatrix::InnerIterator it(L, d); it; ++it) {
                const Index r = reduced[it.row()];
                if (r < 0) continue;
                for (std::size_t j = 0; j < components.size(); ++j)
                    g.offset(r, static_cast<Index>(j)) -=
                        it.value() * w.prescribed[dim * d + components[j]];
            }
        }
        assemble.stop();
        try {
            {
                const Phase phase("analyze", timings);
                g.solver.analyze(sys.K);
            }
            const Phase phase("factorize", timings);
            g.solver.factorize(sys.K);
        } catch (const Error& error) {
            error.rethrow_with(fmt::format("RsWarp: the Laplacian of component {}: {}",
                                           component_name(c0), error.what()));
        }
        w.groups.push_back(std::move(g));
    }
}

RsWarp::~RsWarp() = default;
RsWarp::RsWarp(RsWarp&&) noexcept = default;
RsWarp& RsWarp::operator=(RsWarp&&) noexcept = default;

Vector RsWarp::operator()(const Vector& u, Timings* timings) const {
    const Impl& w = *m_impl;
    CG_VERIFY(u.size() == num_dofs(), "RsWarp: u has {} entries, the mesh has {} DOFs", u.size(),
              num_dofs());
    CG_VERIFY(u.allFinite(), "RsWarp: u has a non-finite entry");
    Matrix B;
    {
        const Phase phase("rs", timings);
        kernels::dispatch(w.type, [&](auto shape) {
            using S = decltype(shape);
            element_right_hand_sides<S>(w, u);
            B = gather_right_hand_sides<S>(w);
        });
    }
    const Phase phase("solve", timings);
    Vector result = w.prescribed;
    for (const WarpGroup& g : w.groups) {
        const Index nf = g.free_nodes.size();
        Matrix rhs = g.offset;
        for (std::size_t j = 0; j < g.components.size(); ++j)
            for (Index r = 0; r < nf; ++r)
                rhs(r, static_cast<Index>(j)) += B(g.free_nodes[r], g.components[j]);
        const Matrix x = g.solver.solve(rhs);
        for (std::size_t j = 0; j < g.components.size(); ++j)
            for (Index r = 0; r < nf; ++r)
                result[w.dim * g.free_nodes[r] + g.components[j]] = x(r, static_cast<Index>(j));
    }
    return result;
}

Index RsWarp::num_dofs() const { return m_impl->dim * m_impl->num_nodes; }

int RsWarp::num_factorizations() const { return static_cast<int>(m_impl->groups.size()); }

std::vector<Index> RsWarp::factorization_sizes() const {
    std::vector<Index> sizes;
    for (const WarpGroup& g : m_impl->groups) sizes.push_back(g.free_nodes.size());
    return sizes;
}

std::vector<solve::FactorStats> RsWarp::factor_stats() const {
    std::vector<solve::FactorStats> stats;
    for (const WarpGroup& g : m_impl->groups) stats.push_back(g.solver.factor_stats());
    return stats;
}

}  // namespace coarsegrain::fem
