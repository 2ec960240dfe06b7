#include "coarsegrain/io/table.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/io/file_util.hpp"

namespace coarsegrain::io {

std::string csv(const Table& table) {
    CG_VERIFY(static_cast<Index>(table.columns.size()) == table.values.cols(),
              "table {}: {} column names for {} columns", table.name, table.columns.size(),
              table.values.cols());
    std::string s = fmt::format("{}\n", fmt::join(table.columns, ","));
    for (Index i = 0; i < table.values.rows(); ++i)
        s += fmt::format("{:.17g}\n", fmt::join(table.values.row(i), ","));
    return s;
}

void write_csv(const Table& table, const std::string& file) {
    const std::string text = csv(table);
    write_atomically(file, [&](std::ostream& os) { os << text; });
}

}  // namespace coarsegrain::io
