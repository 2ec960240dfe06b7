#include "coarsegrain/fem/element.hpp"

#include "coarsegrain/common/error.hpp"
#include "element_kernels.hpp"

namespace coarsegrain::fem {

namespace {

template <class S>
kernels::Coords<S> fixed_coords(const Matrix& X, const char* what) {
    CG_VERIFY(X.rows() == S::npe && X.cols() == S::dim,
              "{}: expected {} by {} corner positions, got {} by {}", what, S::npe, S::dim,
              X.rows(), X.cols());
    return X;
}

}  // namespace

Matrix strain_displacement(mesh::ElementType type, const Matrix& X, const Eigen::VectorXd& xi,
                           double* detJ) {
    return kernels::dispatch(type, [&](auto shape) -> Matrix {
        using S = decltype(shape);
        CG_VERIFY(xi.size() == S::dim, "strain_displacement: xi has {} components, expected {}",
                  xi.size(), S::dim);
        double det = 0;
        const typename S::Point p = S::simplex ? S::centre() : typename S::Point(xi);
        const Matrix B = kernels::strain_displacement<S>(
            kernels::physical_gradients<S>(fixed_coords<S>(X, "strain_displacement"), p, det));
        if (detJ) *detJ = det;
        return B;
    });
}

std::string formulation_name(Formulation f) {
    return f == Formulation::Incompatible ? "incompatible" : "standard";
}

Formulation parse_formulation(const std::string& name) {
    if (name == "standard") return Formulation::Standard;
    if (name == "incompatible") return Formulation::Incompatible;
    throw Error(fmt::format(
        "unknown formulation \"{}\"; expected \"standard\" or \"incompatible\"", name));
}

bool formulation_applies(Formulation f, mesh::ElementType type) {
    return f == Formulation::Standard || !mesh::is_simplex(type);
}

void verify_formulation(Formulation f, mesh::ElementType type) {
    CG_VERIFY(formulation_applies(f, type),
              "fem.formulation \"{}\" does not apply to {} elements: it needs hex or quad "
              "elements; use \"standard\" for tets and triangles",
              formulation_name(f), mesh::element_name(type));
}

Matrix element_stiffness(mesh::ElementType type, const Matrix& X, const Matrix& C,
                         Formulation formulation) {
    verify_formulation(formulation, type);
    return kernels::dispatch(type, [&](auto shape) -> Matrix {
        using S = decltype(shape);
        constexpr int n = mandel_size(S::dim);
        CG_VERIFY(C.rows() == n && C.cols() == n,
                  "element_stiffness: a {}D tensor must be {}x{}, got {}x{}", S::dim, n, n,
                  C.rows(), C.cols());
        const kernels::Coords<S> Xe = fixed_coords<S>(X, "element_stiffness");
        if constexpr (!S::simplex)
            if (formulation == Formulation::Incompatible)
                return kernels::incompatible_stiffness<S>(Xe, kernels::Tensor<S>(C));
        return kernels::stiffness<S>(Xe, kernels::Tensor<S>(C));
    });
}

Matrix element_mass(mesh::ElementType type, const Matrix& X, double density, bool lumped) {
    return kernels::dispatch(type, [&](auto shape) -> Matrix {
        using S = decltype(shape);
        Eigen::Matrix<double, S::npe, S::npe> m =
            kernels::scalar_mass<S>(fixed_coords<S>(X, "element_mass"), density);
        if (lumped) m = Eigen::Matrix<double, S::npe, 1>(m.rowwise().sum()).asDiagonal();
        Matrix M = Matrix::Zero(S::npe * S::dim, S::npe * S::dim);
        for (int a = 0; a < S::npe; ++a)
            for (int b = 0; b < S::npe; ++b)
                for (int d = 0; d < S::dim; ++d) M(S::dim * a + d, S::dim * b + d) = m(a, b);
        return M;
    });
}

Eigen::VectorXd element_load_weights(mesh::ElementType type, const Matrix& X) {
    return kernels::dispatch(type, [&](auto shape) -> Eigen::VectorXd {
        using S = decltype(shape);
        return kernels::load_weights<S>(fixed_coords<S>(X, "element_load_weights"));
    });
}

Eigen::VectorXd element_centre(mesh::ElementType type) {
    return kernels::dispatch(
        type, [&](auto shape) -> Eigen::VectorXd { return decltype(shape)::centre(); });
}

}  // namespace coarsegrain::fem
