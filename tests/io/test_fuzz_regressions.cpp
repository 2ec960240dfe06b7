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

// Hostile inputs must read or throw coarsegrain::Error, never anything else: every seed cut
// at 32 points (truncated files of every format), plus every input saved under
// tests/data/fuzz_regressions/ after a fuzzer crash was fixed.
TEST(FuzzRegressions, TruncatedAndSavedInputsReadOrThrowError) {
    const std::string dir = test::temp_dir("io_fuzz_regressions");
    std::vector<std::vector<std::uint8_t>> hostile;
    for (const fs::path& seed : inputs(fs::path(COARSEGRAIN_TEST_DATA) / ".." / ".." / "fuzz" / "corpus")) {
        const std::vector<std::uint8_t> bytes = bytes_of(seed);
        for (std::size_t k = 1; k < 32; ++k)
            hostile.emplace_back(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(k * bytes.size() / 32));
    }
    for (const fs::path& file : inputs(fs::path(COARSEGRAIN_TEST_DATA) / "fuzz_regressions"))
        hostile.push_back(bytes_of(file));
    EXPECT_GE(hostile.size(), 8u * 31u);
    std::size_t rejected = 0;
    for (const std::vector<std::uint8_t>& bytes : hostile) {
        try {
            fuzz::read_fuzz_input(bytes.data(), bytes.size(), dir);
        } catch (const Error&) {
            ++rejected;  // reported as bad input: fine
        } catch (const std::exception& e) {
            ADD_FAILURE() << "an input of " << bytes.size()
                          << " bytes threw a non-coarsegrain exception: " << e.what();
        }
    }
    // Most truncations cut a section short and must be reported, not silently accepted.
    EXPECT_GT(rejected, hostile.size() / 2);
}
