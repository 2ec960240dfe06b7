#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <regex>
#include <stdexcept>
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
        std::vector<char> held(std::size_t{256} << 20);  // 0.25 GB resident during the phase
        std::memset(held.data(), 1, held.size());
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
    // One decimal of GB: at least the 0.25 GB held during the phase, at most the mark read
    // after it, which can only have grown since.
    EXPECT_GE(std::stod(m[2]), 0.25 - 0.05);
    EXPECT_LE(std::stod(m[2]), peak_resident_mb() / 1024.0 + 0.05);
}

TEST(PhaseProgress, PhaseEndedByAnErrorSaysSo) {
    set_progress_enabled(true);
    testing::internal::CaptureStderr();
    try {
        const Phase phase("a failing phase");
        std::this_thread::sleep_for(std::chrono::milliseconds(1100));
        throw std::runtime_error("out of memory");
    } catch (const std::runtime_error&) {
    }
    const std::string out = testing::internal::GetCapturedStderr();
    set_progress_enabled(false);
    EXPECT_NE(out.find("coarsegrain: a failing phase stopped by an error after"), std::string::npos)
        << out;
    EXPECT_EQ(out.find("done in"), std::string::npos) << out;
}

}  // namespace
}  // namespace coarsegrain
