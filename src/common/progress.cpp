#include "coarsegrain/common/progress.hpp"

#include <omp.h>
#include <sys/resource.h>

#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <mutex>
#include <thread>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain {

namespace {
std::atomic<bool> g_progress{false};
std::atomic<bool> g_interrupt{false};
std::mutex g_print;
}  // namespace

void set_progress_enabled(bool enabled) { g_progress = enabled; }
bool progress_enabled() { return g_progress; }
void progress_line(const std::string& text) {
    if (!progress_enabled()) return;
    const std::lock_guard<std::mutex> lock(g_print);
    std::fprintf(stderr, "coarsegrain: %s\n", text.c_str());
}
double peak_resident_mb() {
    rusage r{};
    getrusage(RUSAGE_SELF, &r);
    return static_cast<double>(r.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}
void request_interrupt() { g_interrupt = true; }
void clear_interrupt() { g_interrupt = false; }
bool interrupt_requested() { return g_interrupt; }

void Timings::add(const std::string& phase, double seconds) {
    for (auto& [name, t] : m_entries)
        if (name == phase) {
            t += seconds;
            return;
        }
    m_entries.emplace_back(phase, seconds);
}

double Timings::operator[](const std::string& phase) const {
    for (const auto& [name, t] : m_entries)
        if (name == phase) return t;
    return 0.0;
}

// A watcher thread that announces the phase after one second unless it ended before.
struct Phase::Watch {
    std::mutex m;
    std::condition_variable cv;
    bool done = false;
    bool announced = false;
    std::thread thread;
    // Exceptions in flight when the phase began: more at its end means an error ended it.
    int exceptions = std::uncaught_exceptions();
};

Phase::Phase(std::string name, Timings* timings)
    : m_name(std::move(name)), m_timings(timings), m_start(std::chrono::steady_clock::now()) {
    if (g_interrupt && !omp_in_parallel())
        throw Interrupted(fmt::format("interrupted before phase \"{}\"", m_name));
    if (!progress_enabled()) return;
    m_watch = std::make_unique<Watch>();
    Watch* w = m_watch.get();
    const std::string label = m_name;
    w->thread = std::thread([w, label] {
        std::unique_lock lock(w->m);
        if (!w->cv.wait_for(lock, std::chrono::seconds(1), [w] { return w->done; })) {
            w->announced = true;
            const std::lock_guard print(g_print);
            std::fprintf(stderr, "coarsegrain: %s ...\n", label.c_str());
        }
    });
}

double Phase::stop() {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    if (m_stopped) return seconds;
    m_stopped = true;
    if (m_timings) m_timings->add(m_name, seconds);
    if (m_watch) {
        {
            const std::lock_guard lock(m_watch->m);
            m_watch->done = true;
        }
        m_watch->cv.notify_one();
        m_watch->thread.join();
        if (m_watch->announced) {
            const bool failed = std::uncaught_exceptions() > m_watch->exceptions;
            const std::lock_guard print(g_print);
            std::fprintf(stderr, "coarsegrain: %s %s %.2f s, peak %.1f GB\n", m_name.c_str(),
                         failed ? "stopped by an error after" : "done in", seconds,
                         peak_resident_mb() / 1024.0);
        }
    }
    return seconds;
}

Phase::~Phase() { stop(); }

}  // namespace coarsegrain
