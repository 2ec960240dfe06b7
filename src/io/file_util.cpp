#include "coarsegrain/io/file_util.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::io {

namespace fs = std::filesystem;

void write_atomically(const std::string& file, const std::function<void(std::ostream&)>& write) {
    const fs::path target(file);
    const fs::path tmp = target.parent_path() /
                         fmt::format(".{}.tmp{}", target.filename().string(), ::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        CG_VERIFY(out.good(), "cannot write {}: cannot create a file in {}", file,
                  target.parent_path().empty() ? "." : target.parent_path().string());
        try {
            write(out);
            out.flush();
            CG_VERIFY(out.good(), "cannot write {}: write failed (disk full?)", file);
        } catch (...) {
            out.close();
            std::error_code ec;
            fs::remove(tmp, ec);
            throw;
        }
    }
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) {
        fs::remove(tmp, ec);
        CG_VERIFY(false, "cannot write {}: {}", file, ec.message());
    }
}

void ensure_writable_dir(const std::string& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    CG_VERIFY(!ec && fs::is_directory(dir), "cannot create output folder {}: {}", dir,
              ec ? ec.message() : "a file of that name exists");
    CG_VERIFY(::access(dir.c_str(), W_OK) == 0, "output folder {} is not writable", dir);
}

}  // namespace coarsegrain::io
