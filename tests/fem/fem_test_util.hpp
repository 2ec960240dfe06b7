#pragma once
/// @file Helpers shared by the FEM tests: solving with Dirichlet conditions, random anisotropic
/// tensors, box boundaries and faces, and independent shape functions and quadrature rules.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/solve/spd_solver.hpp"
#include "test_util.hpp"

namespace coarsegrain::test {

/// Solves K u = f with the Dirichlet conditions eliminated (solver facade, CHOLMOD).
inline Vector solve_dirichlet(const SparseMatrix& K, const Vector& f, const fem::Dirichlet& bc) {
    const fem::ReducedSystem sys = fem::reduce(K, f, bc);
    solve::SpdSolver solver;
    solver.compute(sys.K);
    return fem::expand(sys, solver.solve(sys.rhs), bc, static_cast<Index>(K.rows()));
}

/// A random symmetric positive-definite Mandel tensor (n = 3 or 6) with eigenvalues in
/// [1, 1 + spread], in a random orthonormal basis: a generic anisotropic material.
inline Matrix random_spd_tensor(int n, unsigned seed, double spread = 4.0) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    Matrix R(n, n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) R(i, j) = U(rng);
    const Eigen::HouseholderQR<Matrix> qr(R);
    const Matrix Q = qr.householderQ();
    Eigen::VectorXd lambda(n);
    for (int i = 0; i < n; ++i) lambda[i] = 1.0 + spread * 0.5 * (1.0 + U(rng));
    const Matrix C = Q * lambda.asDiagonal() * Q.transpose();
    return 0.5 * (C + C.transpose());
}

/// Nodes on the faces of the mesh's bounding box (the outer boundary of a box-shaped mesh).
inline std::vector<Index> box_boundary_nodes(const mesh::Mesh& m) {
    const Matrix box = mesh::bounding_box(m);
    std::vector<Index> nodes;
    for (Index v = 0; v < m.num_nodes(); ++v) {
        bool on = false;
        for (int d = 0; d < m.dim(); ++d)
            on = on || std::abs(m.rest_positions(v, d) - box(0, d)) < 1e-12 ||
                 std::abs(m.rest_positions(v, d) - box(1, d)) < 1e-12;
        if (on) nodes.push_back(v);
    }
    return nodes;
}

/// The boundary facets of m whose nodes all lie on the plane x_axis = value (mesh::boundary,
/// then mesh::facets_in_box on a thin box around the plane).
inline std::vector<Index> plane_facets(const mesh::Mesh& m, const mesh::Boundary& b, int axis,
                                       double value) {
    const Matrix box = mesh::bounding_box(m);
    Eigen::VectorXd lo = box.row(0).transpose().array() - 1e-9;
    Eigen::VectorXd hi = box.row(1).transpose().array() + 1e-9;
    lo[axis] = value - 1e-9;
    hi[axis] = value + 1e-9;
    return mesh::facets_in_box(m, b, lo, hi);
}

/// The Mandel strain (e11 e22 [e33 √2e23 √2e13] √2e12) of the displacement gradient A.
inline Eigen::VectorXd mandel_strain(const Matrix& A) {
    const int dim = static_cast<int>(A.rows());
    const Matrix eps = 0.5 * (A + A.transpose());
    Eigen::VectorXd e(mandel_size(dim));
    if (dim == 2) {
        e << eps(0, 0), eps(1, 1), kSqrt2 * eps(0, 1);
    } else {
        e << eps(0, 0), eps(1, 1), eps(2, 2), kSqrt2 * eps(1, 2), kSqrt2 * eps(0, 2),
            kSqrt2 * eps(0, 1);
    }
    return e;
}

/// The field of a patch test on mesh m: u = A x + b with a small A from Eigen's generator
/// (entries in [-1e-3, 1e-3]) and a fixed b, prescribed on the nodes of the bounding box's faces.
struct AffinePatch {
    Matrix A;
    Vector exact;  ///< u at every node, interleaved
    fem::Dirichlet bc;
};

inline AffinePatch affine_patch(const mesh::Mesh& m) {
    const int dim = m.dim();
    AffinePatch p;
    p.A.setRandom(dim, dim);
    p.A *= 1e-3;
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(dim, 1e-3, -2e-3);
    p.exact = test::linear_field(m.rest_positions, p.A, b);
    for (const Index v : box_boundary_nodes(m)) p.bc.fix_nodes({v}, p.exact.segment(dim * v, dim));
    return p;
}

/// All indices 0..n-1.
inline std::vector<Index> all_indices(Index n) {
    std::vector<Index> v(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) v[i] = i;
    return v;
}

/// Shape function values at reference point xi, written independently of the library: P1
/// barycentric (1 - sum xi, xi), Q1 tensor products with the corner orderings of ElementType.
inline Eigen::VectorXd shape_values(mesh::ElementType type, const Eigen::VectorXd& xi) {
    if (mesh::is_simplex(type)) {
        Eigen::VectorXd n(xi.size() + 1);
        n[0] = 1.0 - xi.sum();
        n.tail(xi.size()) = xi;
        return n;
    }
    static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    const int npe = mesh::nodes_per_element(type);
    Eigen::VectorXd n(npe);
    for (int a = 0; a < npe; ++a) {
        n[a] = 1.0;
        for (int k = 0; k < xi.size(); ++k) n[a] *= corner[a][k] ? xi[k] : 1.0 - xi[k];
    }
    return n;
}

/// A quadrature rule on the reference element of a type: points (one per row) and weights.
struct Quadrature {
    Matrix points;
    Eigen::VectorXd weights;
};

/// Gauss-Legendre with p points per axis on [0,1]^dim for Q1 elements (exact to degree 2p - 1
/// per axis); for simplices the collapsed (Duffy) product of the same rule (exact to total
/// degree 2p - dim).
inline Quadrature reference_quadrature(mesh::ElementType type, int p) {
    const int dim = mesh::element_dim(type);
    // Gauss-Legendre nodes/weights on [-1,1] by Newton iteration on P_p.
    std::vector<double> x(static_cast<std::size_t>(p)), w(static_cast<std::size_t>(p));
    for (int i = 0; i < p; ++i) {
        double t = std::cos(M_PI * (i + 0.75) / (p + 0.5));
        double dP = 0;
        for (int it = 0; it < 100; ++it) {
            double P0 = 1, P1 = t;
            for (int k = 2; k <= p; ++k) {
                const double P2 = ((2 * k - 1) * t * P1 - (k - 1) * P0) / k;
                P0 = P1;
                P1 = P2;
            }
            dP = p * (t * P1 - P0) / (t * t - 1);
            const double step = P1 / dP;
            t -= step;
            if (std::abs(step) < 1e-16) break;
        }
        x[i] = 0.5 * (1 + t);
        w[i] = 1.0 / ((1 - t * t) * dP * dP);  // = 2/((1-t^2)P'^2) / 2 on [0,1]
    }
    const int nq = dim == 2 ? p * p : p * p * p;
    Quadrature q{Matrix(nq, dim), Eigen::VectorXd(nq)};
    int k = 0;
    for (int c = 0; c < (dim == 3 ? p : 1); ++c)
        for (int b = 0; b < p; ++b)
            for (int a = 0; a < p; ++a, ++k) {
                const double u = x[a], v = x[b], s = dim == 3 ? x[c] : 0.0;
                double weight = w[a] * w[b] * (dim == 3 ? w[c] : 1.0);
                if (!mesh::is_simplex(type)) {
                    q.points(k, 0) = u;
                    q.points(k, 1) = v;
                    if (dim == 3) q.points(k, 2) = s;
                } else if (dim == 2) {
                    q.points(k, 0) = u;
                    q.points(k, 1) = v * (1 - u);
                    weight *= 1 - u;
                } else {
                    q.points(k, 0) = u;
                    q.points(k, 1) = v * (1 - u);
                    q.points(k, 2) = s * (1 - u) * (1 - v);
                    weight *= (1 - u) * (1 - u) * (1 - v);
                }
                q.weights[k] = weight;
            }
    return q;
}

}  // namespace coarsegrain::test
