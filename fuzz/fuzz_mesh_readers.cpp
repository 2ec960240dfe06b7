// libFuzzer target for the mesh readers: every input either reads or throws coarsegrain::Error;
// any other exception, a crash, a sanitizer report, a hang or a memory blow-up is a bug.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "coarsegrain/common/error.hpp"
#include "read_fuzz_input.hpp"

namespace {

/// A private folder for this process's input files (libFuzzer's -jobs run several processes).
const std::string& work_dir() {
    static const std::string dir = [] {
        const char* tmp = std::getenv("TMPDIR");
        const std::filesystem::path path = std::filesystem::path(tmp ? tmp : "/tmp") /
                                           ("coarsegrain_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(path);
        return path.string();
    }();
    return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        coarsegrain::fuzz::read_fuzz_input(data, size, work_dir());
    } catch (const coarsegrain::Error&) {
        // Bad input reported as it should be.
    }
    return 0;
}
