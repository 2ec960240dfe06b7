#include "coarsegrain/io/inp_export.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <array>
#include <ostream>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"

namespace coarsegrain::io {

namespace {

/// Voigt indices (order 11 22 33 23 13 12) of the CalculiX ANISO constants, in file order.
constexpr std::array<std::pair<int, int>, 21> kAnisoOrder = {{
    {0, 0}, {0, 1}, {1, 1}, {0, 2}, {1, 2}, {2, 2},  // D1111 D1122 D2222 D1133 D2233 D3333
    {0, 5}, {1, 5}, {2, 5}, {5, 5},                  // D1112 D2212 D3312 D1212
    {0, 4}, {1, 4}, {2, 4}, {5, 4}, {4, 4},          // D1113 D2213 D3313 D1213 D1313
    {0, 3}, {1, 3}, {2, 3}, {5, 3}, {4, 3}, {3, 3},  // D1123 D2223 D3323 D1223 D1323 D2323
}};

/// The CalculiX element type of a mesh's elements.
std::string element_type(mesh::ElementType type, material::PlaneMode plane) {
    const char* p = plane == material::PlaneMode::Strain ? "CPE" : "CPS";
    switch (type) {
        case mesh::ElementType::Tet4:
            return "C3D4";
        case mesh::ElementType::Hex8:
            return "C3D8";
        case mesh::ElementType::Tri3:
            return std::string(p) + "3";
        case mesh::ElementType::Quad4:
            return std::string(p) + "4";
    }
    return "";
}

/// A number with 13 significant digits: CalculiX reads at most 20 characters of a number
/// (-1.234567890123e-45 is 19).
std::string number(double x) { return fmt::format("{:.13g}", x); }

/// *NODE (3 coordinates, 0 for z in 2D) and *ELEMENT, numbered from 1.
void write_mesh(std::ostream& out, const mesh::Mesh& mesh, material::PlaneMode plane) {
    out << "*NODE, NSET=NALL\n";
    for (Index v = 0; v < mesh.num_nodes(); ++v) {
        out << v + 1;
        for (int k = 0; k < 3; ++k)
            out << ", " << number(k < mesh.dim() ? mesh.rest_positions(v, k) : 0.0);
        out << '\n';
    }
    out << "*ELEMENT, TYPE=" << element_type(mesh.type, plane) << ", ELSET=EALL\n";
    for (Index e = 0; e < mesh.num_elements(); ++e) {
        out << e + 1;
        for (Index a = 0; a < mesh.elements.cols(); ++a) out << ", " << mesh.elements(e, a) + 1;
        out << '\n';
    }
}

/// One *ELSET, *MATERIAL (ANISO tensor, density; scaled by 1e-30 when `lumped` masses carry
/// the inertia) and *SOLID SECTION per material table entry that elements use.
void write_materials(std::ostream& out, const mesh::Mesh& mesh,
                     const material::ElementMaterials& materials, bool lumped) {
    std::vector<std::vector<Index>> members(materials.table.size());
    for (Index e = 0; e < materials.size(); ++e)
        members[static_cast<std::size_t>(materials.index[e])].push_back(e);
    for (std::size_t m = 0; m < members.size(); ++m) {
        if (members[m].empty()) continue;
        out << fmt::format("*ELSET, ELSET=E{}\n", m + 1);
        for (std::size_t i = 0; i < members[m].size(); ++i)
            out << members[m][i] + 1 << (i % 16 == 15 || i + 1 == members[m].size() ? "\n" : ", ");
        const material::Material& mat = materials.table[m];
        const Matrix C =
            mesh.dim() == 3 ? Matrix(mat.C) : embed_plane_tensor(material::tensor(mat, 2));
        const std::array<double, 21> d = calculix_aniso(C);
        out << fmt::format("*MATERIAL, NAME=M{}\n*ELASTIC, TYPE=ANISO\n", m + 1);
        for (std::size_t k = 0; k < d.size(); ++k)
            out << number(d[k]) << (k == 7 || k == 15 || k + 1 == d.size() ? "\n" : ", ");
        out << "*DENSITY\n" << number(lumped ? 1e-30 * mat.density : mat.density) << '\n';
        out << fmt::format("*SOLID SECTION, ELSET=E{}, MATERIAL=M{}\n", m + 1, m + 1);
        if (mesh.dim() == 2) out << "1.\n";  // thickness
    }
}

/// "node, component, value" for every nonzero entry of an interleaved DOF vector.
void write_dof_values(std::ostream& out, const Vector& values, int dim) {
    for (Index d = 0; d < values.size(); ++d)
        if (values[d] != 0)
            out << d / dim + 1 << ", " << d % dim + 1 << ", " << number(values[d]) << '\n';
}

/// *BOUNDARY: "node, first component, last component, value" per prescribed DOF.
void write_boundary(std::ostream& out, const fem::Dirichlet& bc, int dim) {
    if (bc.dofs.empty()) return;
    out << "*BOUNDARY\n";
    for (std::size_t i = 0; i < bc.dofs.size(); ++i) {
        const Index d = bc.dofs[i];
        const int component = static_cast<int>(d % dim) + 1;
        out << d / dim + 1 << ", " << component << ", " << component << ", "
            << number(bc.values[static_cast<Index>(i)]) << '\n';
    }
}

/// One MASS element per node, numbered after the mesh's elements, with its lumped mass.
void write_masses(std::ostream& out, const mesh::Mesh& mesh, const Vector& lumped_mass) {
    out << "*ELEMENT, TYPE=MASS, ELSET=EMASS\n";
    for (Index v = 0; v < mesh.num_nodes(); ++v)
        out << mesh.num_elements() + v + 1 << ", " << v + 1 << '\n';
    for (Index v = 0; v < mesh.num_nodes(); ++v)
        out << fmt::format("*ELSET, ELSET=MASS{}\n{}\n*MASS, ELSET=MASS{}\n{}\n", v + 1,
                           mesh.num_elements() + v + 1, v + 1, number(lumped_mass[mesh.dim() * v]));
}

}  // namespace

std::array<double, 21> calculix_aniso(const Matrix& C_mandel) {
    CG_VERIFY(C_mandel.rows() == 6 && C_mandel.cols() == 6,
              "calculix_aniso: expected a 6x6 Mandel tensor, got {}x{}", C_mandel.rows(),
              C_mandel.cols());
    const Matrix V = material::mandel_to_voigt(C_mandel);
    std::array<double, 21> d{};
    for (std::size_t k = 0; k < kAnisoOrder.size(); ++k)
        d[k] = V(kAnisoOrder[k].first, kAnisoOrder[k].second);
    return d;
}

Matrix embed_plane_tensor(const Matrix& C2) {
    CG_VERIFY(C2.rows() == 3 && C2.cols() == 3,
              "embed_plane_tensor: expected a 3x3 Mandel tensor, got {}x{}", C2.rows(), C2.cols());
    // Mandel 3D order 11 22 33 23 13 12; 2D order 11 22 12.
    constexpr std::array<int, 3> to3d = {0, 1, 5};
    Matrix C = Matrix::Zero(6, 6);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) C(to3d[i], to3d[j]) = C2(i, j);
    const double out_of_plane = 0.5 * (C2(0, 0) + C2(1, 1));
    C(2, 2) = out_of_plane;
    C(3, 3) = C(4, 4) = out_of_plane;  // Mandel shear entries: 2 D_1313, 2 D_2323
    return C;
}

void write_calculix_deck(const std::string& file, const mesh::Mesh& mesh,
                         const material::ElementMaterials& materials, const Vector& f,
                         const fem::Dirichlet& bc, material::PlaneMode plane,
                         const std::string& heading,
                         const std::optional<CalculixDynamics>& dynamics) {
    const int dim = mesh.dim();
    CG_VERIFY(f.size() == mesh.num_dofs() && materials.size() == mesh.num_elements(),
              "{}: the load has {} entries and the materials {} elements for a mesh of {} DOFs "
              "and {} elements",
              file, f.size(), materials.size(), mesh.num_dofs(), mesh.num_elements());
    CG_VERIFY(bc.dofs.size() == static_cast<std::size_t>(bc.values.size()),
              "{}: {} prescribed DOFs with {} values", file, bc.dofs.size(), bc.values.size());
    for (const Index d : bc.dofs)
        CG_VERIFY(d >= 0 && d < mesh.num_dofs(),
                  "{}: prescribed DOF {} is not one of the mesh's {}", file, d, mesh.num_dofs());
    const bool lumped = dynamics && dynamics->lumped_mass.size() > 0;
    if (dynamics) {
        const Index n = mesh.num_dofs();
        CG_VERIFY(dynamics->dt > 0 && dynamics->steps >= 1 && dynamics->output_every >= 1,
                  "{}: dynamic step of dt {} and {} steps", file, dynamics->dt, dynamics->steps);
        CG_VERIFY(
            (!lumped || dynamics->lumped_mass.size() == n) &&
                (dynamics->initial_velocity.size() == 0 || dynamics->initial_velocity.size() == n),
            "{}: lumped masses ({}) and initial velocity ({}) must have {} entries", file,
            dynamics->lumped_mass.size(), dynamics->initial_velocity.size(), n);
        for (Index v = 0; lumped && v < mesh.num_nodes(); ++v) {
            const auto m = dynamics->lumped_mass.segment(dim * v, dim);
            CG_VERIFY(m.maxCoeff() - m.minCoeff() <= 1e-12 * m.cwiseAbs().maxCoeff(),
                      "{}: node {} has lumped masses {} that differ between its components, "
                      "which a *MASS element cannot hold",
                      file, v + 1, fmt::join(m, ", "));
        }
    }
    write_atomically(file, [&](std::ostream& out) {
        out << "*HEADING\n" << heading << '\n';
        write_mesh(out, mesh, plane);
        write_materials(out, mesh, materials, lumped);
        write_boundary(out, bc, dim);
        if (lumped) write_masses(out, mesh, dynamics->lumped_mass);
        if (dynamics && dynamics->initial_velocity.size() > 0) {
            out << "*INITIAL CONDITIONS, TYPE=VELOCITY\n";
            write_dof_values(out, dynamics->initial_velocity, dim);
        }
        if (dynamics)
            out << fmt::format("*STEP, INC={}\n*DYNAMIC, DIRECT, ALPHA=0\n{}, {}\n",
                               dynamics->steps + 1, number(dynamics->dt),
                               number(dynamics->dt * dynamics->steps));
        else
            out << "*STEP\n*STATIC\n";
        if (!f.isZero()) {
            out << "*CLOAD\n";
            write_dof_values(out, f, dim);
        }
        out << "*NODE PRINT, NSET=NALL"
            << (dynamics ? fmt::format(", FREQUENCY={}", dynamics->output_every) : "")
            << "\nU\n*END STEP\n";
    });
}

}  // namespace coarsegrain::io
