#pragma once
/// @file Safe file output: write to a temporary name, then rename.
#include <functional>
#include <ostream>
#include <string>

namespace coarsegrain::io {

/// Calls write(stream) on a temporary file beside `file` and renames it to `file` only when
/// writing succeeded; on failure the temporary is removed and nothing is left under `file`.
/// @throws Error naming the file if it cannot be opened or written
void write_atomically(const std::string& file, const std::function<void(std::ostream&)>& write);

/// Creates the folder (and parents) if needed and checks it is writable.
/// @throws Error naming the folder otherwise
void ensure_writable_dir(const std::string& dir);

}  // namespace coarsegrain::io
