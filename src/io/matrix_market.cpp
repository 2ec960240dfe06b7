#include "coarsegrain/io/matrix_market.hpp"

#include <fmt/format.h>

#include <ostream>
#include <sstream>

#include "coarsegrain/io/file_util.hpp"

namespace coarsegrain::io {

namespace {

/// The header line and `comment`, each of its lines prefixed by "%".
void header(std::ostream& out, const std::string& format, const std::string& comment) {
    out << "%%MatrixMarket matrix " << format << " real general\n";
    std::istringstream lines(comment);
    for (std::string line; std::getline(lines, line);) out << "% " << line << '\n';
}

}  // namespace

void write_matrix_market(const std::string& file, const SparseMatrix& A,
                         const std::string& comment) {
    write_atomically(file, [&](std::ostream& out) {
        header(out, "coordinate", comment);
        out << A.rows() << ' ' << A.cols() << ' ' << A.nonZeros() << '\n';
        for (Index j = 0; j < A.outerSize(); ++j)
            for (SparseMatrix::InnerIterator it(A, j); it; ++it)
                out << fmt::format("{} {} {:.17g}\n", it.row() + 1, it.col() + 1, it.value());
    });
}

void write_matrix_market(const std::string& file, const Matrix& A, const std::string& comment) {
    write_atomically(file, [&](std::ostream& out) {
        header(out, "array", comment);
        out << A.rows() << ' ' << A.cols() << '\n';
        for (Index j = 0; j < A.cols(); ++j)
            for (Index i = 0; i < A.rows(); ++i) out << fmt::format("{:.17g}\n", A(i, j));
    });
}

}  // namespace coarsegrain::io
