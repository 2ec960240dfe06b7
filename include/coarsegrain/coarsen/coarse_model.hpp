#pragma once
/// @file The one interface every coarsening method implements (DESIGN.md "data flow"): a method
/// maps the fine model and the scene's "coarse" options to a CoarseModel; one runtime solves any
/// CoarseModel and carries its solution to the fine mesh, so every comparison (the effective
/// tensors, the material-adapted hierarchy, the naive/Voigt/Reuss baselines) is the same code.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/homogenize/report.hpp"
#include "coarsegrain/io/table.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/mra/report.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::mra {
struct Hierarchy;
}

namespace coarsegrain::coarsen {

/// A VTU file a method adds to the output folder (e.g. coarse_model.vtu, harmonic.vtu).
struct VtuOutput {
    std::string file;  ///< name inside the output folder
    mesh::Mesh mesh;
    io::VtuFields fields;
};

/// A fine displacement a method reconstructs besides its coarse solution (mra: the single-level
/// solve of every level, Chen 2019 Sec. 4.1). The runtime treats it as the coarse solution:
/// it writes solution_<name>.vtu (fields of solution_coarse.vtu) and compares it with the fine
/// solution.
struct Reconstruction {
    std::string name;
    Vector u;  ///< over all fine DOFs
    /// The level whose summary entry (index into "levels" of summary "coarse") receives this
    /// reconstruction's "errors", "probes" and "vtu" (the file name).
    std::size_t level = 0;
};

/// The linear map that carries a coarse displacement to the fine DOFs: a sparse matrix (the
/// effective tensors' barycentric or linearized harmonic map, the baselines), or a function that
/// applies it without forming it (mra: Φ^{1,T} S, level by level through the C̃^k: Φ^1 of three
/// levels after global solves on 64x16x16 hexes is 1275 x 55488 and nearly dense, 80-110 s and
/// 2.9 GB of peak to form, while applying it takes milliseconds).
class FineMap {
  public:
    using Apply = std::function<Vector(const Vector&)>;
    FineMap() = default;
    /// u -> M u
    FineMap(SparseMatrix M);  // NOLINT(google-explicit-constructor): a matrix is such a map
    /// u -> apply(u), from `cols` coarse to `rows` fine DOFs
    FineMap(Index rows, Index cols, Apply apply);
    Index rows() const { return rows_; }
    Index cols() const { return cols_; }
    /// The map's matrix if it was given as one (rows() x cols()), nullptr if it is a function
    /// that applies it without forming it.
    const SparseMatrix* matrix() const { return matrix_.get(); }
    /// The fine displacement of coarse DOFs u (cols() entries).
    /// @throws Error if u has the wrong size
    Vector apply(const Vector& u) const;
    /// apply() of a vector, or of each column of a matrix.
    template <class Derived>
    auto operator*(const Eigen::MatrixBase<Derived>& U) const {
        if constexpr (Derived::ColsAtCompileTime == 1) {
            return apply(U);
        } else {
            Matrix out(rows_, U.cols());
            for (Index j = 0; j < U.cols(); ++j) out.col(j) = apply(U.col(j));
            return out;
        }
    }

  private:
    Index rows_ = 0, cols_ = 0;
    std::shared_ptr<const SparseMatrix> matrix_;
    Apply apply_;
};

/// The figures of a coarse model, by method (the CLI writes them to summary "coarse"): none,
/// the effective tensors' and baselines', or the hierarchy's build.
using MethodReport = std::variant<std::monostate, homogenize::Report, mra::HierarchyReport>;

/// The figures a method adds once the fine solution is known: none, or the hierarchy's levels
/// against it (the CLI adds them to summary "coarse", merged with the MethodReport).
using ComparisonReport = std::variant<std::monostate, mra::ComparisonReport>;

/// What a method adds once the fine solution is known.
struct FineComparison {
    ComparisonReport report;
    std::vector<Reconstruction> reconstructions;
    std::vector<VtuOutput> outputs;
    /// Tables of figures, written as <name>.csv; the app knows which it plots.
    std::vector<io::Table> tables;
};

/// Figures and files of a method that need the fine solution (its u over all fine DOFs, and its
/// factorization of K_ff if kept: see uses_fine_factorization in runtime.hpp).
using CompareWithFine = std::function<FineComparison(
    const scene::Scene& scene, const scene::FineModel& fine, const scene::StaticSolution& u)>;

/// The coarse mesh and element materials behind an element model's stiffness (the effective
/// tensors and the baselines): K = Tᵀ K(mesh, materials) T with T = dof_map (mesh DOFs x coarse
/// DOFs; empty: the identity). Corotated kinematics rotate these elements, each with its own
/// (anisotropic) tensor (fem::CorotatedModel).
struct ElementModel {
    mesh::Mesh mesh;
    material::ElementMaterials materials;
    SparseMatrix dof_map;
};

/// A coarse model: an operator on coarse DOFs, its load and conditions, and the linear map that
/// carries a coarse displacement to the fine nodes.
struct CoarseModel {
    std::string method;  ///< "effective-tensor", "naive", "voigt", "reuss", "mra"
    Index nodes = 0;     ///< coarse nodes (mra: nodes of the coarsest grid)
    Index elements = 0;  ///< coarse elements (mra: cells of the coarsest grid)
    SparseMatrix K;      ///< coarse stiffness over all coarse DOFs, both triangles stored
    Vector f;            ///< coarse load, one entry per coarse DOF
    fem::Dirichlet bc;   ///< coarse Dirichlet conditions (empty when built into K)
    FineMap to_fine;     ///< fine DOFs x coarse DOFs: u_fine = to_fine * u_coarse
    /// The coarse mass for the fine mass M (fine DOFs square; consistent or lumped), computed
    /// on request since only dynamics needs it: coarse DOFs square, symmetric positive
    /// semi-definite (definite where the coarse DOFs carry fine mass). Empty if the method
    /// defines none. Effective tensors and baselines: by coarse.mass (homogenize::CoarseMass);
    /// mra: the Galerkin mass through the hierarchy.
    std::function<SparseMatrix(const SparseMatrix& M)> mass;
    /// The element model behind K, if it is one (empty for mra, whose coarse DOFs are no
    /// element model: corotated kinematics solve it linear).
    std::optional<ElementModel> element_model;
    /// The material-adapted hierarchy behind the model (the mra methods: its levels C̃^k, A^k,
    /// B^k, W^k and multilevel solves, mra/multilevel_solver.hpp); null for the other methods.
    std::shared_ptr<const mra::Hierarchy> hierarchy;
    Timings timings;      ///< build phases; their sum is reported as coarse.timings.build
    MethodReport report;  ///< method figures for summary "coarse"
    std::vector<VtuOutput> outputs;  ///< extra files for the output folder
    /// Optional (empty: none): called once by the runtime after the fine and coarse solves.
    CompareWithFine compare_with_fine;
};

}  // namespace coarsegrain::coarsen
