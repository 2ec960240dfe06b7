#pragma once
/// @file Matrix Market (.mtx) files of sparse matrices and dense arrays, which SciPy
/// (scipy.io.mmread), MATLAB (mmread.m), Julia (MatrixMarket.jl) and Eigen (loadMarket) read:
/// the models that are no element models (the hierarchy's coarse operators) leave coarsegrain
/// this way.
#include <string>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::io {

/// Writes A as "%%MatrixMarket matrix coordinate real general": every stored entry (1-based
/// indices), with 17 significant digits (the doubles themselves when read back), after the
/// comment lines of `comment` (each prefixed by "%"). Written atomically.
/// @throws Error naming the file if it cannot be written
void write_matrix_market(const std::string& file, const SparseMatrix& A,
                         const std::string& comment);

/// Writes A as "%%MatrixMarket matrix array real general" (column-major, 17 significant
/// digits), as write_matrix_market of a sparse matrix; a vector is one column.
/// @throws Error naming the file if it cannot be written
void write_matrix_market(const std::string& file, const Matrix& A, const std::string& comment);

}  // namespace coarsegrain::io
