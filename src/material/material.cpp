#include "coarsegrain/material/material.hpp"

#include <fmt/ranges.h>

#include <cmath>
#include <limits>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::material {

namespace {

void verify_dim(int dim, const char* what) {
    CG_VERIFY(dim == 2 || dim == 3, "{}: dimension {} must be 2 or 3", what, dim);
}

void verify_density(double density, const char* what) {
    CG_VERIFY(std::isfinite(density) && density > 0, "{}: density = {} must be > 0", what, density);
}

/// Mandel scaling s with C_mandel = diag(s) C_voigt diag(s): 1 on normal, √2 on shear components.
Eigen::VectorXd mandel_scaling(Index n, const char* what) {
    CG_VERIFY(n == 3 || n == 6, "{}: the tensor must be 3x3 (2D) or 6x6 (3D), got {} rows", what,
              n);
    Eigen::VectorXd s = Eigen::VectorXd::Ones(n);
    s.tail(n == 6 ? 3 : 1).setConstant(kSqrt2);
    return s;
}

/// Mandel vector of the symmetric tensor d⊗d.
Eigen::VectorXd outer_mandel(const Eigen::VectorXd& d) {
    if (d.size() == 2) return Eigen::Vector3d(d[0] * d[0], d[1] * d[1], kSqrt2 * d[0] * d[1]);
    Eigen::VectorXd m(6);
    m << d[0] * d[0], d[1] * d[1], d[2] * d[2], kSqrt2 * d[1] * d[2], kSqrt2 * d[0] * d[2],
        kSqrt2 * d[0] * d[1];
    return m;
}

}  // namespace

Material isotropic(int dim, double E, double nu, double density, PlaneMode mode) {
    verify_dim(dim, "isotropic material");
    CG_VERIFY(std::isfinite(E) && E > 0, "isotropic material: E = {} must be > 0", E);
    CG_VERIFY(std::isfinite(nu) && nu > -1.0 && nu < 0.5,
              "isotropic material: nu = {} must satisfy -1 < nu < 0.5", nu);
    verify_density(density, "isotropic material");

    Material m;
    m.E = E;
    m.nu = nu;
    m.density = density;
    m.mode = mode;
    const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    const double mu = E / (2.0 * (1.0 + nu));
    if (dim == 3) {
        m.C.topLeftCorner<3, 3>().setConstant(lambda);
        m.C.diagonal().array() += 2.0 * mu;
    } else if (mode == PlaneMode::Strain) {
        m.C.topLeftCorner<2, 2>().setConstant(lambda);
        m.C.topLeftCorner<3, 3>().diagonal().array() += 2.0 * mu;
    } else {
        const double a = E / (1.0 - nu * nu);
        m.C.topLeftCorner<2, 2>() << a, a * nu, a * nu, a;
        m.C(2, 2) = 2.0 * mu;  // = a (1 - nu)
    }
    return m;
}

Material anisotropic(int dim, const Matrix& C_mandel, double density) {
    verify_dim(dim, "anisotropic material");
    const int n = mandel_size(dim);
    CG_VERIFY(C_mandel.rows() == n && C_mandel.cols() == n,
              "anisotropic material: a {}D tensor must be {}x{} (Mandel), got {}x{}", dim, n, n,
              C_mandel.rows(), C_mandel.cols());
    CG_VERIFY(C_mandel.allFinite(), "anisotropic material: C has a non-finite entry");
    verify_density(density, "anisotropic material");
    const double scale = C_mandel.cwiseAbs().maxCoeff();
    CG_VERIFY(scale > 0, "anisotropic material: C is zero");
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
            CG_VERIFY(std::abs(C_mandel(i, j) - C_mandel(j, i)) <= 1e-10 * scale,
                      "anisotropic material: C must be symmetric, but C({},{}) = {} and "
                      "C({},{}) = {} (Mandel indices from 0)",
                      i, j, C_mandel(i, j), j, i, C_mandel(j, i));
    const Matrix C = 0.5 * (C_mandel + C_mandel.transpose());
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(C, Eigen::EigenvaluesOnly);
    const double lmin = eig.eigenvalues()[0], lmax = eig.eigenvalues()[n - 1];
    // Relative: a tensor whose eigenvalues span more than 12 decades is singular to the double
    // round-off of the stiffness sums it enters.
    CG_VERIFY(lmin > 1e-12 * lmax,
              "anisotropic material: C must be positive definite with smallest / largest "
              "eigenvalue > 1e-12, but its eigenvalues are {} (ratio {:.3g})",
              fmt::join(eig.eigenvalues(), ", "), lmax > 0 ? lmin / lmax : lmin);

    Material m;
    m.C.topLeftCorner(n, n) = C;
    m.density = density;
    double e = 0;
    for (int d = 0; d < dim; ++d) e += directional_young(C, Eigen::VectorXd::Unit(dim, d));
    m.E = e / dim;
    m.nu = std::numeric_limits<double>::quiet_NaN();
    return m;
}

Matrix voigt_to_mandel(const Matrix& C_voigt) {
    CG_VERIFY(C_voigt.rows() == C_voigt.cols(), "voigt_to_mandel: the tensor is {}x{}, not square",
              C_voigt.rows(), C_voigt.cols());
    const Eigen::VectorXd s = mandel_scaling(static_cast<Index>(C_voigt.rows()), "voigt_to_mandel");
    return s.asDiagonal() * C_voigt * s.asDiagonal();
}

Matrix mandel_to_voigt(const Matrix& C_mandel) {
    CG_VERIFY(C_mandel.rows() == C_mandel.cols(),
              "mandel_to_voigt: the tensor is {}x{}, not square", C_mandel.rows(), C_mandel.cols());
    const Eigen::VectorXd s =
        mandel_scaling(static_cast<Index>(C_mandel.rows()), "mandel_to_voigt");
    const Eigen::VectorXd inv = s.cwiseInverse();
    return inv.asDiagonal() * C_mandel * inv.asDiagonal();
}

double directional_young(const Matrix& C_mandel, const Eigen::VectorXd& d) {
    const Index n = static_cast<Index>(C_mandel.rows());
    CG_VERIFY(C_mandel.cols() == n && (n == 3 || n == 6),
              "directional_young: the tensor must be 3x3 or 6x6, got {}x{}", C_mandel.rows(),
              C_mandel.cols());
    const int dim = n == 6 ? 3 : 2;
    CG_VERIFY(d.size() == dim, "directional_young: direction has {} components, expected {}",
              d.size(), dim);
    CG_VERIFY(d.norm() > 0, "directional_young: the direction is zero");
    const Eigen::VectorXd m = outer_mandel(d.normalized());
    const Eigen::LLT<Matrix> llt(C_mandel);
    CG_VERIFY(llt.info() == Eigen::Success,
              "directional_young: the tensor is not positive definite");
    return 1.0 / m.dot(llt.solve(m));
}

ElementMaterials assign(const mesh::Mesh& mesh, const std::map<int, Material>& by_id) {
    CG_VERIFY(mesh.material_ids.size() == mesh.num_elements(),
              "assign materials: {} material ids for {} elements", mesh.material_ids.size(),
              mesh.num_elements());
    std::map<int, Index> count;
    for (Index e = 0; e < mesh.num_elements(); ++e) ++count[mesh.material_ids[e]];
    ElementMaterials mats;
    mats.dim = mesh.dim();
    std::map<int, Index> slot;
    for (const auto& [id, n] : count) {
        const auto it = by_id.find(id);
        if (it == by_id.end()) {
            std::vector<int> defined;
            for (const auto& entry : by_id) defined.push_back(entry.first);
            CG_VERIFY(false,
                      "assign materials: material id {} is used by {} element(s) but has no "
                      "material (defined ids: {})",
                      id, n,
                      defined.empty() ? std::string("none")
                                      : fmt::format("{}", fmt::join(defined, ", ")));
        }
        slot[id] = static_cast<Index>(mats.table.size());
        mats.table.push_back(it->second);
    }
    mats.index.resize(mesh.num_elements());
    for (Index e = 0; e < mesh.num_elements(); ++e) mats.index[e] = slot[mesh.material_ids[e]];
    return mats;
}

ElementMaterials uniform(const mesh::Mesh& mesh, const Material& m) {
    ElementMaterials mats;
    mats.dim = mesh.dim();
    mats.table = {m};
    mats.index = IndexVector::Zero(mesh.num_elements());
    return mats;
}

}  // namespace coarsegrain::material
