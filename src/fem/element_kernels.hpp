#pragma once
/// @file Dimension-generic fixed-size element kernels (private to src/fem).
///
/// One traits struct per element type (Shape<T>) gives the reference shape functions and their
/// gradients; everything else (Jacobian, B matrix, stiffness, mass, load weights) is written
/// once for all four types. Q1 elements live on [0,1]^dim, P1 elements on the unit simplex.
#include <fmt/ranges.h>

#include <array>
#include <cmath>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem::kernels {

using mesh::ElementType;

/// Mandel shear components (row, i, j): strain row `row` is √2 e_ij.
template <int Dim>
struct ShearPairs;
template <>
struct ShearPairs<2> {
    static constexpr std::array<std::array<int, 3>, 1> value = {{{2, 0, 1}}};
};
template <>
struct ShearPairs<3> {
    static constexpr std::array<std::array<int, 3>, 3> value = {{{3, 1, 2}, {4, 0, 2}, {5, 0, 1}}};
};

/// Quadrature rule on the reference element: points (Dim each) and weights.
template <int Dim, int N>
struct Rule {
    std::array<Eigen::Matrix<double, Dim, 1>, N> points;
    std::array<double, N> weights;
};

/// Tensor-product Gauss-Legendre rule with P points per axis on [0,1]^Dim.
template <int Dim, int P>
Rule<Dim, (Dim == 2 ? P * P : P * P * P)> gauss_cube() {
    static_assert(P == 1 || P == 2 || P == 3, "1, 2 or 3 Gauss points per axis");
    std::array<double, P> x{}, w{};
    if constexpr (P == 1) {
        x = {0.5};
        w = {1.0};
    } else if constexpr (P == 2) {
        const double g = 0.5 / std::sqrt(3.0);
        x = {0.5 - g, 0.5 + g};
        w = {0.5, 0.5};
    } else {
        const double g = 0.5 * std::sqrt(0.6);
        x = {0.5 - g, 0.5, 0.5 + g};
        w = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
    }
    Rule<Dim, (Dim == 2 ? P * P : P * P * P)> rule;
    int q = 0;
    for (int k = 0; k < (Dim == 3 ? P : 1); ++k)
        for (int j = 0; j < P; ++j)
            for (int i = 0; i < P; ++i, ++q) {
                rule.points[q][0] = x[i];
                rule.points[q][1] = x[j];
                rule.weights[q] = w[i] * w[j];
                if constexpr (Dim == 3) {
                    rule.points[q][2] = x[k];
                    rule.weights[q] *= w[k];
                }
            }
    return rule;
}

/// Reference Q1 element on [0,1]^Dim; corner a sits at kCorners[a] (orderings of ElementType).
template <int Dim>
struct Q1 {
    static constexpr int dim = Dim;
    static constexpr int npe = Dim == 2 ? 4 : 8;
    static constexpr bool simplex = false;
    static constexpr std::array<std::array<int, 3>, 8> kCorners = {
        {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};
    using Point = Eigen::Matrix<double, Dim, 1>;

    static Eigen::Matrix<double, npe, 1> N(const Point& xi) {
        Eigen::Matrix<double, npe, 1> n;
        for (int a = 0; a < npe; ++a) {
            n[a] = 1.0;
            for (int k = 0; k < Dim; ++k) n[a] *= kCorners[a][k] ? xi[k] : 1.0 - xi[k];
        }
        return n;
    }
    /// npe by Dim reference gradients dN_a / dxi_k.
    static Eigen::Matrix<double, npe, Dim> dN(const Point& xi) {
        Eigen::Matrix<double, npe, Dim> g;
        for (int a = 0; a < npe; ++a)
            for (int d = 0; d < Dim; ++d) {
                double v = 1.0;
                for (int k = 0; k < Dim; ++k) {
                    const bool one = kCorners[a][k] != 0;
                    v *= k == d ? (one ? 1.0 : -1.0) : (one ? xi[k] : 1.0 - xi[k]);
                }
                g(a, d) = v;
            }
        return g;
    }
    static Point centre() { return Point::Constant(0.5); }
    /// 2 Gauss points per axis: exact stiffness on parallelograms / parallelepipeds.
    static auto stiffness_rule() { return gauss_cube<Dim, 2>(); }
    /// 3 Gauss points per axis: N_a N_b det J has degree <= 4 per axis on any Q1 element.
    static auto mass_rule() { return gauss_cube<Dim, 3>(); }
    /// 2 Gauss points per axis: N_a det J has degree <= 3 per axis.
    static auto load_rule() { return gauss_cube<Dim, 2>(); }
};

/// Reference P1 simplex with corners 0, e_1, .., e_Dim; N = (1 - sum xi, xi_1, .., xi_Dim).
template <int Dim>
struct P1 {
    static constexpr int dim = Dim;
    static constexpr int npe = Dim + 1;
    static constexpr bool simplex = true;
    using Point = Eigen::Matrix<double, Dim, 1>;

    static Eigen::Matrix<double, npe, 1> N(const Point& xi) {
        Eigen::Matrix<double, npe, 1> n;
        n[0] = 1.0 - xi.sum();
        n.template tail<Dim>() = xi;
        return n;
    }
    static Eigen::Matrix<double, npe, Dim> dN(const Point&) {
        Eigen::Matrix<double, npe, Dim> g;
        g.row(0).setConstant(-1.0);
        g.template bottomRows<Dim>().setIdentity();
        return g;
    }
    static Point centre() { return Point::Constant(1.0 / (Dim + 1)); }
    /// Measure of the reference simplex, 1 / Dim!.
    static constexpr double reference_measure() { return Dim == 2 ? 0.5 : 1.0 / 6.0; }
};

template <ElementType T>
struct ShapeOf;
template <>
struct ShapeOf<ElementType::Tri3> {
    using type = P1<2>;
};
template <>
struct ShapeOf<ElementType::Tet4> {
    using type = P1<3>;
};
template <>
struct ShapeOf<ElementType::Quad4> {
    using type = Q1<2>;
};
template <>
struct ShapeOf<ElementType::Hex8> {
    using type = Q1<3>;
};
template <ElementType T>
using Shape = typename ShapeOf<T>::type;

template <class S>
using Coords = Eigen::Matrix<double, S::npe, S::dim>;  ///< npe by dim corner positions
template <class S>
using Tensor = Eigen::Matrix<double, mandel_size(S::dim), mandel_size(S::dim)>;
template <class S>
using ElementMatrix = Eigen::Matrix<double, S::npe * S::dim, S::npe * S::dim>;
template <class S>
using BMatrix = Eigen::Matrix<double, mandel_size(S::dim), S::npe * S::dim>;

/// Physical gradients (npe by dim) of the shape functions at xi and det J. Throws if det J is
/// not positive (relative to the element size), i.e. the element is inverted or degenerate.
template <class S>
Eigen::Matrix<double, S::npe, S::dim> physical_gradients(const Coords<S>& X,
                                                         const typename S::Point& xi,
                                                         double& detJ) {
    const Eigen::Matrix<double, S::npe, S::dim> dN = S::dN(xi);
    const Eigen::Matrix<double, S::dim, S::dim> J = X.transpose() * dN;  // J_ik = dx_i / dxi_k
    detJ = J.determinant();
    const double h = (X.colwise().maxCoeff() - X.colwise().minCoeff()).maxCoeff();
    CG_VERIFY(detJ > 1e-12 * (S::dim == 3 ? h * h * h : h * h),
              "element is {}: Jacobian determinant {:.3g} at reference point ({:.3g}) (element "
              "size {:.3g}); check the node order",
              detJ < 0 ? "inverted" : "degenerate", detJ, fmt::join(xi, ", "), h);
    return dN * J.inverse();
}

/// Mandel strain-displacement matrix from the physical gradients G (npe by dim).
template <class S>
BMatrix<S> strain_displacement(const Eigen::Matrix<double, S::npe, S::dim>& G) {
    BMatrix<S> B = BMatrix<S>::Zero();
    for (int a = 0; a < S::npe; ++a) {
        for (int d = 0; d < S::dim; ++d) B(d, S::dim * a + d) = G(a, d);
        for (const auto& [row, i, j] : ShearPairs<S::dim>::value) {
            B(row, S::dim * a + i) = kInvSqrt2 * G(a, j);
            B(row, S::dim * a + j) = kInvSqrt2 * G(a, i);
        }
    }
    return B;
}

/// The elasticity tensor as a (dim*dim) square matrix A acting on displacement gradients:
/// A = P^T C P, where P (mandel_size by dim*dim) maps grad u (entry (i,k) = du_i/dx_k at
/// i*dim + k) to the Mandel strain. Then eps : C : eps' = grad u : A : grad u', and A carries
/// the minor symmetries of C_ikjl.
template <int Dim>
Eigen::Matrix<double, Dim * Dim, Dim * Dim> gradient_tensor(
    const Eigen::Matrix<double, mandel_size(Dim), mandel_size(Dim)>& C) {
    // Mandel row of the strain component (i, k) and its factor in P: 1 on the diagonal,
    // 1/√2 for each of the two off-diagonal gradient entries of a shear component.
    std::array<int, Dim * Dim> row{};
    std::array<double, Dim * Dim> factor{};
    for (int d = 0; d < Dim; ++d) {
        row[d * Dim + d] = d;
        factor[d * Dim + d] = 1.0;
    }
    for (const auto& [r, i, j] : ShearPairs<Dim>::value) {
        row[i * Dim + j] = row[j * Dim + i] = r;
        factor[i * Dim + j] = factor[j * Dim + i] = kInvSqrt2;
    }
    Eigen::Matrix<double, Dim * Dim, Dim * Dim> A;
    for (int q = 0; q < Dim * Dim; ++q)
        for (int p = 0; p < Dim * Dim; ++p) A(p, q) = factor[p] * factor[q] * C(row[p], row[q]);
    return A;
}

/// K_e = ∫ B^T C B: one point (exact) for P1, 2^dim Gauss points for Q1.
///
/// Evaluated component by component instead of through the dense B: with G the npe by dim
/// physical gradients and A = gradient_tensor(C), the (i, j) components of all node pairs are
/// K^{ij}_ab = ∫ G_a^T A^{ij} G_b, i.e. the npe x npe matrix G A^{ij} G^T, where A^{ij} is the
/// dim x dim block of A at rows i*dim.., columns j*dim... Only i <= j is computed (K^{ji} =
/// (K^{ij})^T), about a third of the work of B^T C B and no zero entries of B touched.
template <class S>
ElementMatrix<S> stiffness(const Coords<S>& X, const Tensor<S>& C) {
    constexpr int D = S::dim, npe = S::npe;
    using Block = Eigen::Matrix<double, npe, npe>;
    const Eigen::Matrix<double, D * D, D* D> A = gradient_tensor<D>(C);
    std::array<Block, D*(D + 1) / 2> Kij;
    for (Block& k : Kij) k.setZero();
    const auto add_point = [&](const typename S::Point& xi, double weight) {
        double detJ = 0;
        const Eigen::Matrix<double, npe, D> G = physical_gradients<S>(X, xi, detJ);
        int p = 0;
        for (int i = 0; i < D; ++i)
            for (int j = i; j < D; ++j, ++p) {
                const Eigen::Matrix<double, npe, D> GA =
                    (weight * detJ) * (G * A.template block<D, D>(i * D, j * D));
                Kij[p].noalias() += GA.lazyProduct(G.transpose());
            }
    };
    if constexpr (S::simplex) {
        add_point(S::centre(), S::reference_measure());
    } else {
        const auto rule = S::stiffness_rule();
        for (std::size_t q = 0; q < rule.points.size(); ++q)
            add_point(rule.points[q], rule.weights[q]);
    }
    ElementMatrix<S> K;
    int p = 0;
    for (int i = 0; i < D; ++i)
        for (int j = i; j < D; ++j, ++p)
            for (int b = 0; b < npe; ++b)
                for (int a = 0; a < npe; ++a) {
                    if (i == j) {
                        // Diagonal components: symmetrize the round-off of K^{ii}.
                        K(D * a + i, D * b + i) = 0.5 * (Kij[p](a, b) + Kij[p](b, a));
                    } else {
                        K(D * a + i, D * b + j) = Kij[p](a, b);
                        K(D * b + j, D * a + i) = Kij[p](a, b);
                    }
                }
    return K;  // exactly symmetric
}

/// Mandel strain-displacement matrix of Rows "nodes" from their physical gradients G (Rows by
/// dim): the columns of node a are dim*a .. dim*a + dim - 1 (strain_displacement for any count).
template <int Dim, int Rows>
Eigen::Matrix<double, mandel_size(Dim), Rows * Dim> strain_displacement_of(
    const Eigen::Matrix<double, Rows, Dim>& G) {
    Eigen::Matrix<double, mandel_size(Dim), Rows * Dim> B;
    B.setZero();
    for (int a = 0; a < Rows; ++a) {
        for (int d = 0; d < Dim; ++d) B(d, Dim * a + d) = G(a, d);
        for (const auto& [row, i, j] : ShearPairs<Dim>::value) {
            B(row, Dim * a + i) = kInvSqrt2 * G(a, j);
            B(row, Dim * a + j) = kInvSqrt2 * G(a, i);
        }
    }
    return B;
}

/// How the gradients of the incompatible modes are mapped to physical space.
enum class ModeMapping {
    /// Taylor, Beresford and Wilson (1976): the centre Jacobian J0 and the factor j0 / j(xi)
    /// (j = det J), so that the modes' strain integrates to zero over any element and the element
    /// passes the patch test on distorted meshes. The element of Formulation::Incompatible.
    Taylor,
    /// CalculiX's C3D8I (shape8hu.f): the centre Jacobian J0 without the factor j0 / j, i.e.
    /// Wilson's modes with Taylor's J0. Identical to Taylor on parallelograms / parallelepipeds
    /// (j constant); on other elements the modes' strain has a nonzero mean and the element fails
    /// the patch test. Kept to show exactly what CalculiX computes (tests/fem/test_calculix.cpp).
    CalculiX,
};

/// Q1 stiffness with incompatible modes (Wilson, Taylor et al.): the displacement is enriched
/// inside each element by the dim bubbles P_k = 4 xi_k (1 - xi_k) per component (the 1 - r_k^2
/// of the [-1,1] element), dim * dim internal amplitudes that are condensed out statically:
/// K = K_uu - K_ua K_aa^-1 K_au, all blocks ∫ B^T C B with 2^dim Gauss points. The modes'
/// gradients dP_k/dxi_k (row k of J0^-1), scaled per ModeMapping, vanish at the element centre,
/// so the centre strain is that of the nodal (Q1) field alone. The modes add the quadratic
/// displacements a Q1 element lacks: bending without shear locking and, on regular meshes,
/// volumetric strain free enough not to lock near incompressibility (docs/guide.md).
template <class S, ModeMapping Mapping = ModeMapping::Taylor>
ElementMatrix<S> incompatible_stiffness(const Coords<S>& X, const Tensor<S>& C) {
    static_assert(!S::simplex, "incompatible modes are defined for Q1 elements only");
    constexpr int D = S::dim, npe = S::npe, rows = npe + D, nu = D * npe, na = D * D;
    using Full = Eigen::Matrix<double, D * rows, D * rows>;
    double j0 = 0;
    physical_gradients<S>(X, S::centre(), j0);  // throws if the element is degenerate
    const Eigen::Matrix<double, D, D> J0inv =
        (X.transpose() * S::dN(S::centre())).inverse();  // J_ik = dx_i / dxi_k at the centre
    Full K = Full::Zero();
    const auto rule = S::stiffness_rule();
    for (std::size_t q = 0; q < rule.points.size(); ++q) {
        const typename S::Point& xi = rule.points[q];
        double j = 0;
        Eigen::Matrix<double, rows, D> G;
        G.template topRows<npe>() = physical_gradients<S>(X, xi, j);
        const double scale = Mapping == ModeMapping::Taylor ? j0 / j : 1.0;
        for (int k = 0; k < D; ++k)
            G.row(npe + k) = (scale * 4.0 * (1.0 - 2.0 * xi[k])) * J0inv.row(k);
        const Eigen::Matrix<double, mandel_size(D), D* rows> B = strain_displacement_of<D, rows>(G);
        K.noalias() += (rule.weights[q] * j) * (B.transpose() * C * B);
    }
    const Eigen::LLT<Eigen::Matrix<double, na, na>> Kaa(K.template bottomRightCorner<na, na>());
    CG_VERIFY(Kaa.info() == Eigen::Success,
              "incompatible modes: the modes' stiffness is not positive definite (degenerate "
              "element or elasticity tensor)");
    const Eigen::Matrix<double, nu, na> Kua = K.template topRightCorner<nu, na>();
    const ElementMatrix<S> Kc =
        K.template topLeftCorner<nu, nu>() - Kua * Kaa.solve(Kua.transpose());
    return 0.5 * (Kc + Kc.transpose());  // exactly symmetric despite round-off
}

/// Scalar consistent mass ∫ rho N_a N_b (npe square); exact for every element of its type.
template <class S>
Eigen::Matrix<double, S::npe, S::npe> scalar_mass(const Coords<S>& X, double density) {
    double detJ = 0;
    if constexpr (S::simplex) {
        physical_gradients<S>(X, S::centre(), detJ);
        const double measure = detJ * S::reference_measure();
        // ∫ N_a N_b = measure (1 + delta_ab) / ((dim+1)(dim+2)).
        Eigen::Matrix<double, S::npe, S::npe> M;
        M.setConstant(density * measure / ((S::dim + 1) * (S::dim + 2)));
        M.diagonal() *= 2.0;
        return M;
    } else {
        Eigen::Matrix<double, S::npe, S::npe> M = Eigen::Matrix<double, S::npe, S::npe>::Zero();
        const auto rule = S::mass_rule();
        for (std::size_t q = 0; q < rule.points.size(); ++q) {
            physical_gradients<S>(X, rule.points[q], detJ);
            const auto n = S::N(rule.points[q]);
            M.noalias() += (density * rule.weights[q] * detJ) * (n * n.transpose());
        }
        return 0.5 * (M + M.transpose());  // exactly symmetric despite round-off
    }
}

/// ∫ N_a over the element (npe values); exact for every element of its type.
template <class S>
Eigen::Matrix<double, S::npe, 1> load_weights(const Coords<S>& X) {
    double detJ = 0;
    if constexpr (S::simplex) {
        physical_gradients<S>(X, S::centre(), detJ);
        return Eigen::Matrix<double, S::npe, 1>::Constant(detJ * S::reference_measure() / S::npe);
    } else {
        Eigen::Matrix<double, S::npe, 1> w = Eigen::Matrix<double, S::npe, 1>::Zero();
        const auto rule = S::load_rule();
        for (std::size_t q = 0; q < rule.points.size(); ++q) {
            physical_gradients<S>(X, rule.points[q], detJ);
            w += (rule.weights[q] * detJ) * S::N(rule.points[q]);
        }
        return w;
    }
}

/// Corner positions of element e of the mesh as a fixed-size matrix.
template <class S>
Coords<S> element_coords(const mesh::Mesh& mesh, Index e) {
    Coords<S> X;
    for (int a = 0; a < S::npe; ++a) X.row(a) = mesh.rest_positions.row(mesh.elements(e, a));
    return X;
}

/// Corner positions of one cell of a regular grid (Q1 shapes: every cell of a Quad4 / Hex8 grid
/// is this one, translated).
template <class S>
Coords<S> grid_cell(const mesh::GridInfo& grid) {
    const Eigen::Vector3d h = grid.spacing();
    Coords<S> X;
    for (int a = 0; a < S::npe; ++a)
        for (int d = 0; d < S::dim; ++d) X(a, d) = S::kCorners[a][d] * h[d];
    return X;
}

/// Calls f(Shape<T>{}) for the mesh's element type: the one dispatch from runtime to templates.
template <class F>
decltype(auto) dispatch(ElementType type, F&& f) {
    switch (type) {
        case ElementType::Tri3:
            return f(Shape<ElementType::Tri3>{});
        case ElementType::Quad4:
            return f(Shape<ElementType::Quad4>{});
        case ElementType::Tet4:
            return f(Shape<ElementType::Tet4>{});
        case ElementType::Hex8:
            break;
    }
    return f(Shape<ElementType::Hex8>{});
}

}  // namespace coarsegrain::fem::kernels
