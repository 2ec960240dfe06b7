#include "coarsegrain/fem/corotation.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <limits>

#include "coarsegrain/common/error.hpp"
#include "element_kernels.hpp"
#include "gather.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem {

namespace {

/// Node positions relative to their barycentre (npe x dim).
Matrix centred(const Matrix& X) { return X.rowwise() - X.colwise().mean(); }

/// The rotation factor of A (square): U diag(1, .., det(U Vᵀ)) Vᵀ from A = U Σ Vᵀ, the rotation
/// closest to A (maximizing tr(Rᵀ A)).
template <class SquareMatrix>
SquareMatrix rotation_factor(const SquareMatrix& A) {
    const Eigen::JacobiSVD<SquareMatrix> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    SquareMatrix U = svd.matrixU();
    const SquareMatrix V = svd.matrixV();
    if ((U * V.transpose()).determinant() < 0) U.col(U.cols() - 1) *= -1;  // smallest σ
    return U * V.transpose();
}

/// v with each dim-block of an interleaved vector multiplied by R.
Vector rotate_blocks(const Matrix& R, const Vector& v) {
    const Index dim = R.rows();
    Vector out(v.size());
    for (Index a = 0; a < v.size() / dim; ++a)
        out.segment(a * dim, dim) = R * v.segment(a * dim, dim);
    return out;
}

}  // namespace

std::string corotation_frame_name(CorotationFrame frame) {
    return frame == CorotationFrame::DeVeubeke ? "de_veubeke" : "polar";
}

Matrix corotation_frame(const Matrix& X, const Matrix& x, CorotationFrame frame) {
    CG_VERIFY(X.rows() == x.rows() && X.cols() == x.cols() && (X.cols() == 2 || X.cols() == 3) &&
                  X.rows() > X.cols(),
              "corotation: rest corners {}x{} and current corners {}x{} must be one npe x dim "
              "shape with dim 2 or 3 and npe > dim",
              X.rows(), X.cols(), x.rows(), x.cols());
    const Matrix X0 = centred(X);
    const Matrix A = centred(x).transpose() * X0;  // Σ_a (x_a - b)(X_a - b_0)ᵀ
    if (frame == CorotationFrame::DeVeubeke) return rotation_factor(A);
    const Matrix J = X0.transpose() * X0;
    return rotation_factor<Matrix>(A * J.inverse());  // F = A J^{-1}
}

CorotatedElement corotate(const Matrix& X, const Matrix& x, const Matrix& Ke,
                          CorotationFrame frame) {
    const Index n = X.rows() * X.cols();
    CG_VERIFY(Ke.rows() == n && Ke.cols() == n,
              "corotation: element stiffness {}x{} for {} nodes of dimension {}", Ke.rows(),
              Ke.cols(), X.rows(), X.cols());
    CorotatedElement e;
    e.R = corotation_frame(X, x, frame);
    const Index dim = X.cols();
    const Matrix u_hat = centred(x) * e.R - centred(X);  // rows: Rᵀ(x_a - b) - (X_a - b_0)
    e.u_hat.resize(n);
    for (Index a = 0; a < X.rows(); ++a) e.u_hat.segment(a * dim, dim) = u_hat.row(a).transpose();
    const Vector Ku = Ke * e.u_hat;
    e.energy = 0.5 * e.u_hat.dot(Ku);
    e.force = rotate_blocks(e.R, Ku);
    Matrix Rb = Matrix::Zero(n, n);  // block diagonal R
    for (Index a = 0; a < X.rows(); ++a) Rb.block(a * dim, a * dim, dim, dim) = e.R;
    e.tangent = Rb * Ke * Rb.transpose();
    return e;
}

namespace {

template <class S>
using Frame = Eigen::Matrix<double, S::dim, S::dim>;
template <class S>
using ElementVector = Eigen::Matrix<double, S::npe * S::dim, 1>;

/// An element's corners relative to their barycentre: at rest, X_a - b_0, and displaced,
/// x_a - b = (X_a - b_0) + (u_a - ū). The displaced ones are never formed from the absolute
/// positions X_a + u_a: rounding those (of the object's size) would put noise of ε |X| into û,
/// which is small (of the strain's size), where this leaves ε |u - ū|.
template <class S>
struct CentredCorners {
    kernels::Coords<S> rest, current;

    CentredCorners(const mesh::Mesh& mesh, Index e, const Vector& u) {
        const kernels::Coords<S> X = kernels::element_coords<S>(mesh, e);
        kernels::Coords<S> U;
        for (int a = 0; a < S::npe; ++a)
            U.row(a) = u.template segment<S::dim>(S::dim * mesh.elements(e, a)).transpose();
        rest = X.rowwise() - X.colwise().mean();
        current = rest + (U.rowwise() - U.colwise().mean());
    }
};

}  // namespace

struct CorotatedModel::Impl {
    mesh::Mesh mesh;
    CorotationFrame frame;
    SparseMatrix dof_map;                      ///< empty: identity
    std::vector<Matrix> stiffness;             ///< distinct K^e
    std::vector<std::size_t> stiffness_index;  ///< #E into stiffness
    std::vector<Matrix> inverse_moment;        ///< Polar: J^{-1} per element (else empty)
    detail::NodeElements incidence;
    detail::NodeGraph graph;
    SparseMatrix pattern;  ///< the tangent's pattern (values unset)

    const Matrix& Ke(Index e) const {
        return stiffness[stiffness_index[static_cast<std::size_t>(e)]];
    }

    /// Mesh displacement of model DOFs w.
    Vector mesh_displacement(const Vector& w) const {
        return dof_map.size() == 0 ? w : Vector(dof_map * w);
    }

    template <class S>
    State evaluate(const Vector& u) const;
    template <class S>
    void tangent(const State& state, SparseMatrix& T) const;
    template <class S>
    void jacobian(const State& state, SparseMatrix& J) const;

    /// Tᵀ A T with the DOF map (A itself without).
    SparseMatrix mapped(SparseMatrix A) const {
        if (dof_map.size() == 0) return A;
        SparseMatrix reduced = SparseMatrix(dof_map.transpose()) * A * dof_map;
        reduced.makeCompressed();
        return reduced;
    }
};

template <class S>
CorotatedModel::State CorotatedModel::Impl::evaluate(const Vector& u) const {
    constexpr int dim = S::dim, npe = S::npe;
    const Index ne = mesh.num_elements(), nv = mesh.num_nodes();
    State state;
    state.frames.resize(static_cast<std::size_t>(ne * dim * dim));
    std::vector<ElementVector<S>> element_force(static_cast<std::size_t>(ne));
    Vector energy(ne), round_off(ne);
    detail::parallel_for(ne, [&](Index e) {
        const CentredCorners<S> c(mesh, e, u);
        Frame<S> A = c.current.transpose() * c.rest;  // Σ_a (x_a - b)(X_a - b_0)ᵀ
        if (frame == CorotationFrame::Polar)
            A *= Eigen::Map<const Frame<S>>(inverse_moment[static_cast<std::size_t>(e)].data());
        const Frame<S> R = rotation_factor(A);
        Eigen::Map<Frame<S>>(state.frames.data() + e * dim * dim) = R;
        // û row by row: Rᵀ(x_a - b) - (X_a - b_0)
        const kernels::Coords<S> rows = c.current * R - c.rest;
        ElementVector<S> u_hat;
        for (int a = 0; a < npe; ++a) u_hat.template segment<dim>(dim * a) = rows.row(a);
        const Eigen::Map<const Eigen::Matrix<double, npe * dim, npe * dim>> K(Ke(e).data());
        const ElementVector<S> Ku = K * u_hat;
        energy[e] = 0.5 * u_hat.dot(Ku);
        round_off[e] = K.norm() * c.current.norm();
        ElementVector<S>& f = element_force[static_cast<std::size_t>(e)];
        for (int a = 0; a < npe; ++a)
            f.template segment<dim>(dim * a) = R * Ku.template segment<dim>(dim * a);
    });
    state.energy = energy.sum();
    state.round_off = std::numeric_limits<double>::epsilon() * round_off.norm();
    Vector force(dim * nv);
#pragma omp parallel for schedule(static) if (nv >= detail::kMinParallel)
    for (Index v = 0; v < nv; ++v) {
        Eigen::Matrix<double, dim, 1> sum = Eigen::Matrix<double, dim, 1>::Zero();
        for (Index k = incidence.ptr[v]; k < incidence.ptr[v + 1]; ++k)
            sum +=
                element_force[static_cast<std::size_t>(incidence.element[k])].template segment<dim>(
                    dim * incidence.local[k]);
        force.template segment<dim>(dim * v) = sum;
    }
    state.force = dof_map.size() == 0 ? force : Vector(dof_map.transpose() * force);
    state.displacement = u;
    return state;
}

template <class S>
void CorotatedModel::Impl::jacobian(const State& state, SparseMatrix& J) const {
    constexpr int dim = S::dim, npe = S::npe, n = npe * dim, rotations = dim == 2 ? 1 : 3;
    using ElementMatrix = kernels::ElementMatrix<S>;
    const Index ne = mesh.num_elements();
    const Vector& u = state.displacement;
    std::vector<ElementMatrix> element_jacobian(static_cast<std::size_t>(ne));
    detail::parallel_for(ne, [&](Index e) {
        const CentredCorners<S> corners(mesh, e, u);
        const kernels::Coords<S>& Xc = corners.rest;
        const kernels::Coords<S>& xc = corners.current;
        // c_a: the weights of dx_a in the frame's moment, dM = Σ_a dx_a c_aᵀ.
        kernels::Coords<S> c = Xc;
        if (frame == CorotationFrame::Polar)
            c = Xc * Eigen::Map<const Frame<S>>(inverse_moment[static_cast<std::size_t>(e)].data());
        const Eigen::Map<const Frame<S>> R(state.frames.data() + e * dim * dim);
        const Eigen::Map<const ElementMatrix> K(Ke(e).data());
        Frame<S> Sm = R.transpose() * (xc.transpose() * c);
        Sm = 0.5 * (Sm + Sm.transpose());
        const kernels::Coords<S> y = xc * R;  // rows Rᵀ(x_a - b)
        ElementVector<S> u_hat;
        for (int a = 0; a < npe; ++a) u_hat.template segment<dim>(dim * a) = (y - Xc).row(a);
        const ElementVector<S> Ku = K * u_hat;
        // rotate(k, v): E_k applied to each node block of v.
        const auto rotate = [&](int k, const ElementVector<S>& v) {
            ElementVector<S> out;
            for (int a = 0; a < npe; ++a) {
                if constexpr (dim == 2) {
                    static_cast<void>(k);
                    out.template segment<2>(2 * a) << -v[2 * a + 1], v[2 * a];
                } else {
                    out.template segment<3>(3 * a) = Eigen::Vector3d::Unit(k).cross(
                        Eigen::Vector3d(v.template segment<3>(3 * a)));
                }
            }
            return out;
        };
        Eigen::Matrix<double, n, rotations> V;
        for (int k = 0; k < rotations; ++k) V.col(k) = rotate(k, Ku) - K * rotate(k, u_hat);
        Eigen::Matrix<double, rotations, n> G;
        bool differentiable = true;
        if constexpr (dim == 2) {
            const double trace = Sm.trace();
            differentiable = trace > 1e-8 * Sm.norm();
            for (int a = 0; a < npe; ++a) G.template block<1, 2>(0, 2 * a) << -c(a, 1), c(a, 0);
            G /= trace;
        } else {
            const Eigen::Matrix3d H = Sm.trace() * Eigen::Matrix3d::Identity() - Sm;
            const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(H);
            differentiable = eig.eigenvalues().minCoeff() > 1e-8 * Sm.norm();
            const Eigen::Matrix3d H_inv = H.inverse();
            for (int a = 0; a < npe; ++a) {
                Eigen::Matrix3d cross;
                cross << 0, -c(a, 2), c(a, 1), c(a, 2), 0, -c(a, 0), -c(a, 1), c(a, 0), 0;
                G.template block<3, 3>(0, 3 * a) = H_inv * cross;
            }
        }
        ElementMatrix local = K;
        if (differentiable) local += V * G;
        ElementMatrix& Je = element_jacobian[static_cast<std::size_t>(e)];
        for (int a = 0; a < npe; ++a)
            for (int b = 0; b < npe; ++b)
                Je.template block<dim, dim>(dim * a, dim * b) =
                    R * local.template block<dim, dim>(dim * a, dim * b) * R.transpose();
    });
    J = pattern;
    detail::Skeleton s{incidence, graph, J};
    detail::gather<S, true>(mesh, s, [&](Index e, int b) {
        return element_jacobian[static_cast<std::size_t>(e)].template middleCols<dim>(dim * b);
    });
}

template <class S>
void CorotatedModel::Impl::tangent(const State& state, SparseMatrix& T) const {
    constexpr int dim = S::dim, npe = S::npe;
    T = pattern;
    detail::Skeleton s{incidence, graph, T};
    detail::gather<S, true>(mesh, s, [&](Index e, int b) {
        const Eigen::Map<const Frame<S>> R(state.frames.data() + e * dim * dim);
        const Eigen::Map<const Eigen::Matrix<double, npe * dim, npe * dim>> K(Ke(e).data());
        Eigen::Matrix<double, npe * dim, dim> column;
        for (int a = 0; a < npe; ++a)
            column.template middleRows<dim>(dim * a) =
                R * K.template block<dim, dim>(dim * a, dim * b) * R.transpose();
        return column;
    });
}

CorotatedModel::CorotatedModel(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                               Formulation formulation, CorotationFrame frame, SparseMatrix dof_map)
    : m_impl(std::make_unique<Impl>()) {
    detail::verify_materials(mesh, mats, "CorotatedModel");
    verify_formulation(formulation, mesh.type);
    CG_VERIFY(dof_map.size() == 0 || dof_map.rows() == mesh.num_dofs(),
              "CorotatedModel: the DOF map has {} rows for a mesh of {} DOFs", dof_map.rows(),
              mesh.num_dofs());
    Impl& m = *m_impl;
    m.mesh = mesh;
    m.frame = frame;
    m.dof_map = std::move(dof_map);
    const Index ne = mesh.num_elements();
    const int dim = mesh.dim(), n = mandel_size(dim);
    const auto element_matrix = [&](Index e) {
        return detail::for_element(e, [&] {
            return element_stiffness(mesh.type, mesh.element_positions(e),
                                     mats.of(e).C.topLeftCorner(n, n), formulation);
        });
    };
    m.stiffness_index.resize(static_cast<std::size_t>(ne));
    // Congruent grid cells differ only by their material.
    if (mesh.grid && !mesh::is_simplex(mesh.type) && ne > 0) {
        std::vector<std::ptrdiff_t> first(mats.table.size(), -1);
        for (Index e = 0; e < ne; ++e) {
            auto& f = first[static_cast<std::size_t>(mats.index[e])];
            if (f < 0) {
                f = static_cast<std::ptrdiff_t>(m.stiffness.size());
                m.stiffness.push_back(element_matrix(e));
            }
            m.stiffness_index[static_cast<std::size_t>(e)] = static_cast<std::size_t>(f);
        }
    } else {
        m.stiffness.resize(static_cast<std::size_t>(ne));
        detail::parallel_for(ne, [&](Index e) {
            m.stiffness[static_cast<std::size_t>(e)] = element_matrix(e);
            m.stiffness_index[static_cast<std::size_t>(e)] = static_cast<std::size_t>(e);
        });
    }
    if (frame == CorotationFrame::Polar) {
        m.inverse_moment.resize(static_cast<std::size_t>(ne));
        detail::parallel_for(ne, [&](Index e) {
            const Matrix X0 = centred(mesh.element_positions(e));
            m.inverse_moment[static_cast<std::size_t>(e)] = (X0.transpose() * X0).inverse();
        });
    }
    m.incidence = detail::node_elements(mesh);
    m.graph = detail::node_graph(mesh, m.incidence);
    detail::block_pattern(m.graph, dim, true, true, m.pattern);
}

CorotatedModel::~CorotatedModel() = default;
CorotatedModel::CorotatedModel(CorotatedModel&&) noexcept = default;
CorotatedModel& CorotatedModel::operator=(CorotatedModel&&) noexcept = default;

Index CorotatedModel::num_dofs() const {
    return m_impl->dof_map.size() == 0 ? m_impl->mesh.num_dofs() : m_impl->dof_map.cols();
}

CorotationFrame CorotatedModel::frame() const { return m_impl->frame; }

CorotatedModel::State CorotatedModel::evaluate(const Vector& w) const {
    CG_VERIFY(w.size() == num_dofs(), "CorotatedModel: displacement of size {} for {} DOFs",
              w.size(), num_dofs());
    CG_VERIFY(w.allFinite(), "CorotatedModel: the displacement has a non-finite entry");
    const Vector u = m_impl->mesh_displacement(w);
    return kernels::dispatch(m_impl->mesh.type, [&](auto shape) {
        return m_impl->template evaluate<decltype(shape)>(u);
    });
}

SparseMatrix CorotatedModel::tangent(const State& state) const {
    const Impl& m = *m_impl;
    CG_VERIFY(state.frames.size() ==
                  static_cast<std::size_t>(m.mesh.num_elements() * m.mesh.dim() * m.mesh.dim()),
              "CorotatedModel: tangent of a state of another model");
    SparseMatrix T;
    kernels::dispatch(m.mesh.type,
                      [&](auto shape) { m.template tangent<decltype(shape)>(state, T); });
    return m.mapped(std::move(T));
}

SparseMatrix CorotatedModel::jacobian(const State& state) const {
    const Impl& m = *m_impl;
    CG_VERIFY(state.frames.size() == static_cast<std::size_t>(m.mesh.num_elements() * m.mesh.dim() *
                                                              m.mesh.dim()) &&
                  state.displacement.size() == m.mesh.num_dofs(),
              "CorotatedModel: Jacobian of a state of another model");
    SparseMatrix J;
    kernels::dispatch(m.mesh.type,
                      [&](auto shape) { m.template jacobian<decltype(shape)>(state, J); });
    return m.mapped(std::move(J));
}

}  // namespace coarsegrain::fem
