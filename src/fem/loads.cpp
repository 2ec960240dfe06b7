#include "coarsegrain/fem/loads.hpp"

#include <cmath>

#include "coarsegrain/common/error.hpp"
#include "element_kernels.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem {

Vector gravity_load(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                    const Eigen::VectorXd& g) {
    const int dim = mesh.dim();
    CG_VERIFY(g.size() == dim, "gravity_load: gravity has {} components, expected {}", g.size(),
              dim);
    detail::verify_materials(mesh, mats, "gravity_load");
    return kernels::dispatch(mesh.type, [&](auto shape) {
        using S = decltype(shape);
        using Weights = Eigen::Matrix<double, S::npe, 1>;
        // rho ∫ N_a per element (parallel), then the per-node sums (serial, O(#E npe)).
        std::vector<Weights> w(static_cast<std::size_t>(mesh.num_elements()));
        detail::parallel_for(mesh.num_elements(), [&](Index e) {
            w[e] = mats.of(e).density * detail::for_element(e, [&] {
                       return kernels::load_weights<S>(kernels::element_coords<S>(mesh, e));
                   });
        });
        Eigen::VectorXd node_mass = Eigen::VectorXd::Zero(mesh.num_nodes());
        for (Index e = 0; e < mesh.num_elements(); ++e)
            for (int a = 0; a < S::npe; ++a) node_mass[mesh.elements(e, a)] += w[e][a];
        Vector f(dim * mesh.num_nodes());
        for (Index v = 0; v < mesh.num_nodes(); ++v) f.segment(dim * v, dim) = node_mass[v] * g;
        return f;
    });
}

namespace {

/// ∫ N_a over a facet with nodes P (rows), for each facet node a: exact for segments and
/// triangles (measure / n), 2x2 Gauss over the bilinear map for quads (exact for planar
/// parallelograms).
Eigen::VectorXd facet_weights(const Matrix& P) {
    const Index n = static_cast<Index>(P.rows());
    Eigen::VectorXd w(n);
    if (n == 2) {
        w.setConstant(0.5 * (P.row(1) - P.row(0)).norm());
    } else if (n == 3) {
        const Eigen::Vector3d e1 = (P.row(1) - P.row(0)).transpose();
        const Eigen::Vector3d e2 = (P.row(2) - P.row(0)).transpose();
        w.setConstant(e1.cross(e2).norm() / 6.0);
    } else {
        // Bilinear facet x(s,t) = sum N_a(s,t) P_a with corners (0,0) (1,0) (1,1) (0,1).
        w.setZero();
        const auto rule = kernels::gauss_cube<2, 2>();
        for (std::size_t q = 0; q < rule.points.size(); ++q) {
            const auto N = kernels::Q1<2>::N(rule.points[q]);
            const auto dN = kernels::Q1<2>::dN(rule.points[q]);
            const Eigen::Vector3d xs = P.transpose() * dN.col(0);
            const Eigen::Vector3d xt = P.transpose() * dN.col(1);
            w += rule.weights[q] * xs.cross(xt).norm() * N;
        }
    }
    return w;
}

}  // namespace

Vector traction_load(const mesh::Mesh& mesh, const mesh::Boundary& b,
                     const std::vector<Index>& facets, const Eigen::VectorXd& t) {
    const int dim = mesh.dim();
    CG_VERIFY(t.size() == dim, "traction_load: traction has {} components, expected {}", t.size(),
              dim);
    const Index nf = static_cast<Index>(b.facets.cols());
    CG_VERIFY((dim == 2 && nf == 2) || (dim == 3 && (nf == 3 || nf == 4)),
              "traction_load: {}D boundary facets must have {} nodes, got {}", dim,
              dim == 2 ? "2" : "3 or 4", nf);
    Vector f = Vector::Zero(dim * mesh.num_nodes());
    Matrix P(nf, dim);
    for (const Index k : facets) {
        CG_VERIFY(k >= 0 && k < b.size(), "traction_load: facet {} out of range 0..{}", k,
                  b.size() - 1);
        for (Index a = 0; a < nf; ++a) {
            const Index v = b.facets(k, a);
            CG_VERIFY(v >= 0 && v < mesh.num_nodes(),
                      "traction_load: facet {} refers to node {}, but nodes are numbered 0..{}", k,
                      v, mesh.num_nodes() - 1);
            P.row(a) = mesh.rest_positions.row(v);
        }
        const Eigen::VectorXd w = facet_weights(P);
        for (Index a = 0; a < nf; ++a) f.segment(dim * b.facets(k, a), dim) += w[a] * t;
    }
    return f;
}

}  // namespace coarsegrain::fem
