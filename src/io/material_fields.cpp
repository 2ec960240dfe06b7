#include "coarsegrain/io/material_fields.hpp"

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::io {

namespace {

const Field* find_cell_field(const VtuFields& fields, const std::string& name) {
    for (const Field& f : fields.cell_data)
        if (f.name == name) return &f;
    return nullptr;
}

}  // namespace

std::string voigt_field_name(int I, int J) { return fmt::format("C_voigt_{}{}", I + 1, J + 1); }

void add_element_material_fields(VtuFields& fields, const material::ElementMaterials& mats) {
    const int n = mandel_size(mats.dim);
    const Index ne = mats.size();
    Matrix voigt(ne, n * (n + 1) / 2);
    Vector density(ne);
    for (Index e = 0; e < ne; ++e) {
        const Matrix C = material::mandel_to_voigt(material::tensor(mats.of(e), mats.dim));
        int k = 0;
        for (int I = 0; I < n; ++I)
            for (int J = I; J < n; ++J) voigt(e, k++) = C(I, J);
        density[e] = mats.of(e).density;
    }
    int k = 0;
    for (int I = 0; I < n; ++I)
        for (int J = I; J < n; ++J) fields.add_cell_scalar(voigt_field_name(I, J), voigt.col(k++));
    fields.add_cell_scalar("density", density);
}

bool has_element_material_fields(const VtuFields& fields, int dim) {
    const int n = mandel_size(dim);
    for (int I = 0; I < n; ++I)
        for (int J = I; J < n; ++J)
            if (!find_cell_field(fields, voigt_field_name(I, J))) return false;
    return true;
}

std::map<int, material::Material> element_materials_from_fields(const VtuFields& fields,
                                                                mesh::Mesh& mesh,
                                                                const std::string& source) {
    const int dim = mesh.dim(), n = mandel_size(dim);
    const Index ne = mesh.num_elements();
    auto column = [&](const std::string& name) -> const Matrix& {
        const Field* f = find_cell_field(fields, name);
        CG_VERIFY(f,
                  "{}: cell field {} is missing (element tensors need every C_voigt_IJ and "
                  "density)",
                  source, name);
        CG_VERIFY(f->values.rows() == ne && f->values.cols() == 1,
                  "{}: cell field {} is {}x{}, expected one value per element ({})", source, name,
                  f->values.rows(), f->values.cols(), ne);
        return f->values;
    };
    std::vector<const Matrix*> entries;
    for (int I = 0; I < n; ++I)
        for (int J = I; J < n; ++J) entries.push_back(&column(voigt_field_name(I, J)));
    const Matrix& density = column("density");
    std::map<int, material::Material> out;
    mesh.material_ids.resize(ne);
    for (Index e = 0; e < ne; ++e) {
        Matrix C(n, n);
        int k = 0;
        for (int I = 0; I < n; ++I)
            for (int J = I; J < n; ++J, ++k) C(I, J) = C(J, I) = (*entries[k])(e, 0);
        try {
            out[e] = material::anisotropic(dim, material::voigt_to_mandel(C), density(e, 0));
        } catch (const Error& err) {
            CG_VERIFY(false, "{}: element {}: {}", source, e, err.what());
        }
        mesh.material_ids[e] = e;
    }
    return out;
}

}  // namespace coarsegrain::io
