#include "coarsegrain/homogenize/effective_tensor.hpp"

#include <cmath>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::homogenize {

namespace {

/// [begin, end) of each coarse element's run in overlaps sorted by coarse element.
std::vector<std::size_t> coarse_ranges(const std::vector<mesh::Overlap>& overlaps,
                                       Index num_coarse) {
    std::vector<std::size_t> start(static_cast<std::size_t>(num_coarse) + 1, 0);
    for (std::size_t k = 0; k < overlaps.size(); ++k) {
        const Index q = overlaps[k].coarse;
        CG_VERIFY(q >= 0 && q < num_coarse, "overlap {} names coarse element {} of {}", k, q,
                  num_coarse);
        CG_VERIFY(k == 0 || overlaps[k - 1].coarse <= q,
                  "overlaps must be sorted by coarse element (mesh::intersect's order)");
        ++start[static_cast<std::size_t>(q) + 1];
    }
    for (Index q = 0; q < num_coarse; ++q) start[q + 1] += start[q];
    return start;
}

Matrix block(int dim, const Mandel6& M) {
    const int n = mandel_size(dim);
    return M.topLeftCorner(n, n);
}

Mandel6 embed(const Matrix& M) {
    Mandel6 out = Mandel6::Zero();
    out.topLeftCorner(M.rows(), M.cols()) = M;
    return out;
}

}  // namespace

std::vector<Mandel6> energy_averages(int dim, const std::vector<Mandel6>& G_fine,
                                     const material::ElementMaterials& fine_materials,
                                     const std::vector<mesh::Overlap>& overlaps,
                                     const Vector& coarse_measures) {
    const int n = mandel_size(dim);
    CG_VERIFY(G_fine.size() == static_cast<std::size_t>(fine_materials.size()),
              "energy averages: {} fine mollifiers for {} fine elements", G_fine.size(),
              fine_materials.size());
    const Index nc = static_cast<Index>(coarse_measures.size());
    const std::vector<std::size_t> start = coarse_ranges(overlaps, nc);
    // G_p^T C_p G_p once per fine element that overlaps anything.
    std::vector<Mandel6> P(G_fine.size(), Mandel6::Zero());
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < fine_materials.size(); ++p) {
        const auto C = material::tensor(fine_materials.of(p), dim);
        const auto G = G_fine[p].topLeftCorner(n, n);
        P[p].topLeftCorner(n, n).noalias() = G.transpose() * C * G;
    }
    std::vector<Mandel6> A(static_cast<std::size_t>(nc), Mandel6::Zero());
#pragma omp parallel for schedule(dynamic, 4)
    for (Index q = 0; q < nc; ++q) {
        for (std::size_t k = start[q]; k < start[q + 1]; ++k)
            A[q] += overlaps[k].measure * P[overlaps[k].fine];
        A[q] /= coarse_measures[q];
        A[q] = 0.5 * (A[q] + A[q].transpose()).eval();
    }
    return A;
}

double mollifier_scale(int dim, const std::vector<Mandel6>& G_fine, const Vector& fine_measures) {
    CG_VERIFY(G_fine.size() == static_cast<std::size_t>(fine_measures.size()),
              "mollifier scale: {} mollifiers for {} measures", G_fine.size(),
              fine_measures.size());
    const int n = mandel_size(dim);
    double s = 0;
    for (std::size_t p = 0; p < G_fine.size(); ++p)
        s += fine_measures[static_cast<Index>(p)] * G_fine[p].topLeftCorner(n, n).norm();
    return s / fine_measures.sum();
}

bool mollifier_singular(int dim, const Mandel6& G, double scale) {
    const Eigen::JacobiSVD<Matrix> svd(block(dim, G));
    return !(svd.singularValues().minCoeff() > 1e-10 * scale);
}

double condition_number(int dim, const Mandel6& G) {
    const Eigen::JacobiSVD<Matrix> svd(block(dim, G));
    return svd.singularValues().maxCoeff() / svd.singularValues().minCoeff();
}

std::vector<Mandel6> effective_tensors(int dim, const std::vector<Mandel6>& A,
                                       const std::vector<Mandel6>& G_coarse) {
    CG_VERIFY(A.size() == G_coarse.size(), "effective tensors: {} averages for {} mollifiers",
              A.size(), G_coarse.size());
    std::vector<Mandel6> C(A.size());
    for (std::size_t q = 0; q < A.size(); ++q) {
        const Eigen::PartialPivLU<Matrix> lu(block(dim, G_coarse[q]));
        const Matrix Ginv = lu.inverse();
        CG_VERIFY(Ginv.allFinite(),
                  "effective tensor: the coarse mollifier of coarse element {} "
                  "is singular",
                  q);
        const Matrix Cq = Ginv.transpose() * block(dim, A[q]) * Ginv;
        C[q] = embed(0.5 * (Cq + Cq.transpose()));
    }
    return C;
}

std::vector<Mandel6> average_tensors(Average kind, const material::ElementMaterials& fine_materials,
                                     const std::vector<mesh::Overlap>& overlaps, Index num_coarse) {
    const int dim = fine_materials.dim, n = mandel_size(dim);
    const std::vector<std::size_t> start = coarse_ranges(overlaps, num_coarse);
    if (kind == Average::Naive)
        for (const material::Material& m : fine_materials.table)
            CG_VERIFY(std::isfinite(m.nu),
                      "naive average: needs isotropic fine materials (Lamé parameters), but a "
                      "fine material is anisotropic");
    std::vector<Mandel6> C(static_cast<std::size_t>(num_coarse), Mandel6::Zero());
#pragma omp parallel for schedule(dynamic, 4)
    for (Index q = 0; q < num_coarse; ++q) {
        double vol = 0, lambda = 0, mu = 0;
        Matrix sum = Matrix::Zero(n, n);
        for (std::size_t k = start[q]; k < start[q + 1]; ++k) {
            const material::Material& m = fine_materials.of(overlaps[k].fine);
            const double w = overlaps[k].measure;
            vol += w;
            switch (kind) {
                case Average::Naive:
                    lambda += w * m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu));
                    mu += w * m.E / (2 * (1 + m.nu));
                    break;
                case Average::Voigt:
                    sum += w * material::tensor(m, dim);
                    break;
                case Average::Reuss:
                    sum += w * Matrix(material::tensor(m, dim)).inverse();
                    break;
            }
        }
        if (!(vol > 0)) continue;  // reported below, outside the parallel region
        if (kind == Average::Naive) {
            lambda /= vol;
            mu /= vol;
            const material::Material& first = fine_materials.of(overlaps[start[q]].fine);
            const double E = mu * (3 * lambda + 2 * mu) / (lambda + mu);
            const double nu = lambda / (2 * (lambda + mu));
            C[q] = material::isotropic(dim, E, nu, 1.0, first.mode).C;
        } else {
            const Matrix avg = sum / vol;
            C[q] = embed(kind == Average::Voigt ? avg : Matrix(avg.inverse()));
        }
    }
    for (Index q = 0; q < num_coarse; ++q)
        CG_VERIFY(start[q + 1] > start[q],
                  "average tensors: coarse element {} contains no fine material", q);
    return C;
}

Vector coarse_element_masses(const material::ElementMaterials& fine_materials,
                             const std::vector<mesh::Overlap>& overlaps, Index num_coarse) {
    Vector m = Vector::Zero(num_coarse);
    for (const mesh::Overlap& o : overlaps)
        m[o.coarse] += fine_materials.of(o.fine).density * o.measure;
    return m;
}

}  // namespace coarsegrain::homogenize
