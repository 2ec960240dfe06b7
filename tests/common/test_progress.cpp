#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "coarsegrain/common/progress.hpp"

namespace coarsegrain {
namespace {

TEST(PeakResidentMemory, CoversMemoryTheProcessHolds) {
    // 256 MB written, so resident: the high-water mark is at least that while it is held
    // (whatever the process held before).
    constexpr std::size_t kBytes = std::size_t{256} << 20;
    std::vector<char> held(kBytes);
    std::memset(held.data(), 1, held.size());
    EXPECT_GE(peak_resident_mb(), 256.0);
    EXPECT_EQ(held[kBytes / 2], 1);
}

TEST(PhaseProgress, EndLineGivesSecondsAndThePeakSoFar) {
    set_progress_enabled(true);
    testing::internal::CaptureStderr();
    Timings timings;
    {
        const Phase phase("a long phase", &timings);
        std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    }
    const std::string out = testing::internal::GetCapturedStderr();
    set_progress_enabled(false);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        out, m, std::regex(R"(coarsegrain: a long phase done in ([0-9.]+) s, peak ([0-9.]+) GB)")))
        << out;
    EXPECT_GE(std::stod(m[1]), 1.1);
    EXPECT_NEAR(std::stod(m[1]), timings["a long phase"], 0.01);
    // One decimal of GB: the mark read after the phase, which can only have grown since.
    EXPECT_LE(std::stod(m[2]), peak_resident_mb() / 1024.0 + 0.05);
    EXPECT_GT(std::stod(m[2]), 0.0);
}

}  // namespace
}  // namespace coarsegrain
