#pragma once
/// @file Tables of figures (one row per item, named columns) and their CSV form.
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::io {

/// A table of numbers a computation reports, e.g. one row per level of a hierarchy.
struct Table {
    std::string name;                  ///< file stem, e.g. "mra_levels" (written as name.csv)
    std::vector<std::string> columns;  ///< #columns names
    Matrix values;                     ///< #rows by #columns
};

/// The CSV text of a table: a header row of the column names, then one row per row of values,
/// each number in shortest round-trip form ("{:.17g}": integers print as integers, NaN as
/// "nan").
/// @throws Error if the column count and the values' columns differ
std::string csv(const Table& table);

/// csv(table), written atomically to `file`.
void write_csv(const Table& table, const std::string& file);

}  // namespace coarsegrain::io
