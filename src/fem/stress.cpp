#include "coarsegrain/fem/stress.hpp"

#include <cmath>

#include "coarsegrain/common/error.hpp"
#include "element_kernels.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem {

namespace {

/// Von Mises stress of a full 3D stress in Mandel form (s11 s22 s33 √2s23 √2s13 √2s12):
/// sqrt(((s11-s22)^2 + (s22-s33)^2 + (s33-s11)^2) / 2 + 3 (s23^2 + s13^2 + s12^2)).
double von_mises(const Eigen::Matrix<double, 6, 1>& s) {
    const double normal = (s[0] - s[1]) * (s[0] - s[1]) + (s[1] - s[2]) * (s[1] - s[2]) +
                          (s[2] - s[0]) * (s[2] - s[0]);
    return std::sqrt(0.5 * normal + 1.5 * s.tail<3>().squaredNorm());  // 3 s_ij^2 = 1.5 (√2 s_ij)^2
}

/// sigma_zz of a 2D element: lambda (e11 + e22) for an isotropic plane-strain material, 0 for
/// plane stress and for anisotropic materials (whose 2D tensor has no out-of-plane coupling).
double sigma_zz(const material::Material& m, const Eigen::Vector3d& strain) {
    if (std::isnan(m.nu) || m.mode == material::PlaneMode::Stress) return 0.0;
    const double lambda = m.E * m.nu / ((1.0 + m.nu) * (1.0 - 2.0 * m.nu));
    return lambda * (strain[0] + strain[1]);
}

}  // namespace

ElementStress element_stress(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                             const Vector& u) {
    const int dim = mesh.dim();
    CG_VERIFY(u.size() == mesh.num_dofs(), "element_stress: u has {} entries, expected {}",
              u.size(), mesh.num_dofs());
    detail::verify_materials(mesh, mats, "element_stress");
    const int n = mandel_size(dim);
    ElementStress out;
    out.strain.resize(mesh.num_elements(), n);
    out.stress.resize(mesh.num_elements(), n);
    out.von_mises.resize(mesh.num_elements());
    kernels::dispatch(mesh.type, [&](auto shape) {
        using S = decltype(shape);
        constexpr int nm = mandel_size(S::dim);
        detail::parallel_for(mesh.num_elements(), [&](Index e) {
            const kernels::BMatrix<S> B = detail::for_element(e, [&] {
                double detJ = 0;
                return kernels::strain_displacement<S>(kernels::physical_gradients<S>(
                    kernels::element_coords<S>(mesh, e), S::centre(), detJ));
            });
            Eigen::Matrix<double, S::npe * S::dim, 1> ue;
            for (int a = 0; a < S::npe; ++a)
                ue.template segment<S::dim>(S::dim * a) =
                    u.segment<S::dim>(S::dim * mesh.elements(e, a));
            const material::Material& m = mats.of(e);
            const Eigen::Matrix<double, nm, 1> strain = B * ue;
            const Eigen::Matrix<double, nm, 1> stress = m.C.topLeftCorner<nm, nm>() * strain;
            out.strain.row(e) = strain.transpose();
            out.stress.row(e) = stress.transpose();
            Eigen::Matrix<double, 6, 1> full = Eigen::Matrix<double, 6, 1>::Zero();
            if constexpr (S::dim == 3) {
                full = stress;
            } else {
                full << stress[0], stress[1], sigma_zz(m, strain), 0.0, 0.0, stress[2];
            }
            out.von_mises[e] = von_mises(full);
        });
    });
    return out;
}

double strain_energy(const SparseMatrix& K, const Vector& u) {
    CG_VERIFY(K.rows() == u.size() && K.cols() == u.size(),
              "strain_energy: K is {}x{} but u has {} entries", K.rows(), K.cols(), u.size());
    return 0.5 * u.dot(K * u);
}

Matrix mandel_to_physical(const Matrix& m) {
    Matrix out = m;
    const int n = static_cast<int>(m.cols());
    const int first_shear = n == 6 ? 3 : 2;
    out.rightCols(n - first_shear) *= kInvSqrt2;
    return out;
}

}  // namespace coarsegrain::fem
