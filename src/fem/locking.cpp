#include "coarsegrain/fem/locking.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>

namespace coarsegrain::fem {

namespace {

/// Poisson ratios of the measurements, and the tip-deflection error (percent, against the
/// converged answer) of the 4 x 1 x 1 cantilever on 32x8x8 cells (3D) / the 4 x 1 plane-strain
/// one on 32x8 (2D) at each: printed by bench/bench_locking (docs/guide.md, "Near-incompressible
/// materials"). The errors at nu = 0.3 are discretization; their growth with nu is locking.
constexpr std::array<double, 6> kNu = {0.3, 0.45, 0.49, 0.499, 0.4999, 0.49999};

struct Measured {
    mesh::ElementType type;
    Formulation formulation;
    std::array<double, 6> error;  ///< percent, at kNu
};

constexpr std::array<Measured, 6> kMeasured = {{
    {mesh::ElementType::Hex8, Formulation::Standard, {1.3, 4.4, 13.5, 40.1, 68.8, 87.0}},
    {mesh::ElementType::Hex8, Formulation::Incompatible, {0.4, 1.1, 1.5, 1.9, 3.5, 9.1}},
    {mesh::ElementType::Tet4, Formulation::Standard, {6.6, 16.1, 40.8, 79.2, 90.6, 92.1}},
    {mesh::ElementType::Quad4, Formulation::Standard, {1.3, 5.4, 20.4, 66.0, 88.5, 91.7}},
    {mesh::ElementType::Quad4, Formulation::Incompatible, {0.3, 1.1, 1.5, 1.7, 1.7, 1.7}},
    {mesh::ElementType::Tri3, Formulation::Standard, {5.9, 14.3, 38.9, 78.3, 89.1, 90.4}},
}};

/// Growth of the error over its nu = 0.3 value (percentage points) from which a warning is given.
constexpr double kWarnGrowth = 5.0;

/// Locking grows with lambda / mu = 2 nu / (1 - 2 nu): interpolate in -log10(1 - 2 nu).
double locking_variable(double nu) { return -std::log10(1.0 - 2.0 * nu); }

/// The measured error at nu, interpolated linearly in locking_variable; clamped to the table's
/// ends (`beyond` is set when nu exceeds the last measured one).
double interpolated_error(const Measured& m, double nu, bool* beyond) {
    *beyond = nu > kNu.back();
    if (nu <= kNu.front()) return m.error.front();
    if (*beyond) return m.error.back();
    const double t = locking_variable(nu);
    for (std::size_t i = 1; i < kNu.size(); ++i) {
        const double t0 = locking_variable(kNu[i - 1]), t1 = locking_variable(kNu[i]);
        if (t <= t1) return m.error[i - 1] + (m.error[i] - m.error[i - 1]) * (t - t0) / (t1 - t0);
    }
    return m.error.back();
}

std::string advice(mesh::ElementType type, Formulation f) {
    const bool three = mesh::element_dim(type) == 3;
    if (f == Formulation::Incompatible)
        return "refine the mesh (the error fell 2-4x with each halving of the element size)";
    if (!mesh::is_simplex(type)) return "use \"fem\": {\"formulation\": \"incompatible\"}";
    return fmt::format(
        "quadratic {} are not available: use a finer mesh, or {} elements with \"fem\": "
        "{{\"formulation\": \"incompatible\"}}",
        three ? "tets" : "triangles", three ? "hex" : "quad");
}

}  // namespace

std::vector<std::string> locking_warnings(const mesh::Mesh& mesh,
                                          const material::ElementMaterials& mats,
                                          Formulation formulation) {
    std::vector<std::string> out;
    const Measured* measured = nullptr;
    for (const Measured& m : kMeasured)
        if (m.type == mesh.type && m.formulation == formulation) measured = &m;
    if (measured == nullptr) return out;
    // The scene's material id of each table entry: that of its first element.
    std::vector<Index> first(mats.table.size(), -1);
    for (Index e = 0; e < mats.size(); ++e)
        if (first[static_cast<std::size_t>(mats.index[e])] < 0)
            first[static_cast<std::size_t>(mats.index[e])] = e;
    const bool three = mesh.dim() == 3;
    for (std::size_t i = 0; i < mats.table.size(); ++i) {
        const material::Material& m = mats.table[i];
        if (first[i] < 0 || !std::isfinite(m.nu)) continue;  // unused, or anisotropic
        if (!three && m.mode == material::PlaneMode::Stress) continue;  // no constraint in plane
        bool beyond = false;
        const double error = interpolated_error(*measured, m.nu, &beyond);
        if (error - measured->error.front() < kWarnGrowth) continue;
        const int id = mesh.material_ids.size() == mesh.num_elements()
                           ? mesh.material_ids[first[i]]
                           : static_cast<int>(i);
        out.push_back(fmt::format(
            "material {}: nu = {:g}: {} {} elements lock{} (tip deflection error {}{:.0f}% on a "
            "{} cantilever, {:.1f}% at nu = 0.3); {}",
            id, m.nu, formulation_name(formulation), mesh::element_name(mesh.type),
            formulation == Formulation::Incompatible ? " mildly" : "",
            beyond ? "at least " : "~", error, three ? "32x8x8" : "32x8 plane-strain",
            measured->error.front(), advice(mesh.type, formulation)));
    }
    return out;
}

}  // namespace coarsegrain::fem
