// Replays fuzzer inputs through the same entry point as the libFuzzer target
// (fuzz/read_fuzz_input.hpp). Under the sanitizer build this also checks memory safety.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../fuzz/read_fuzz_input.hpp"
#include "coarsegrain/common/error.hpp"
#include "test_util.hpp"

using namespace coarsegrain;

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> inputs(const fs::path& folder) {
    std::vector<fs::path> out;
    for (const auto& entry : fs::directory_iterator(folder))
        if (entry.is_regular_file() && entry.path().extension() != ".md")
            out.push_back(entry.path());
    return out;
}

std::vector<std::uint8_t> bytes_of(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

// The seed corpus holds valid files of every format: each must read without any error.
TEST(FuzzSeeds, EverySeedIsAValidMesh) {
    const std::string dir = test::temp_dir("io_fuzz_seeds");
    const auto seeds = inputs(fs::path(COARSEGRAIN_TEST_DATA) / ".." / ".." / "fuzz" / "corpus");
    EXPECT_GE(seeds.size(), 8u);
    for (const fs::path& seed : seeds) {
        const std::vector<std::uint8_t> bytes = bytes_of(seed);
        EXPECT_NO_THROW(fuzz::read_fuzz_input(bytes.data(), bytes.size(), dir)) << seed;
    }
}

// Inputs that once crashed the fuzzer must now read or throw coarsegrain::Error.
TEST(FuzzRegressions, SavedInputsReadOrThrowError) {
    const std::string dir = test::temp_dir("io_fuzz_regressions");
    const auto saved = inputs(fs::path(COARSEGRAIN_TEST_DATA) / "fuzz_regressions");
    if (saved.empty()) GTEST_SKIP() << "no saved crash inputs";
    for (const fs::path& file : saved) {
        const std::vector<std::uint8_t> bytes = bytes_of(file);
        try {
            fuzz::read_fuzz_input(bytes.data(), bytes.size(), dir);
        } catch (const Error&) {
            // reported as bad input: fine
        } catch (const std::exception& e) {
            ADD_FAILURE() << file << " threw a non-coarsegrain exception: " << e.what();
        }
    }
}
