#pragma once
/// @file Phase timing and progress lines on stderr.
#include <chrono>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace coarsegrain {

/// Wall-clock seconds of named phases, in the order they ran.
class Timings {
  public:
    void add(const std::string& phase, double seconds);
    /// Seconds of a phase (summed over repeats), 0 if it never ran.
    double operator[](const std::string& phase) const;
    const std::vector<std::pair<std::string, double>>& entries() const { return m_entries; }

  private:
    std::vector<std::pair<std::string, double>> m_entries;
};

/// Globally enables or silences progress lines (the CLI's --quiet). Off by default, so library
/// users and tests see nothing unless they ask.
void set_progress_enabled(bool enabled);
bool progress_enabled();
/// Writes "coarsegrain: <text>" to stderr if progress lines are enabled (one line at a time
/// across threads).
void progress_line(const std::string& text);

/// Asks every computation running in this process to stop at its next phase boundary: from now
/// on, a Phase that starts outside an OpenMP parallel region throws Interrupted, until
/// clear_interrupt(). (The Python module calls it on Ctrl-C.)
void request_interrupt();
/// Lets phases start again.
void clear_interrupt();
bool interrupt_requested();

/// Peak resident memory of this process so far in MB (getrusage's high-water mark), the
/// summaries' "peak_memory_mb".
double peak_resident_mb();

/// Times one phase (RAII). If the phase is still running after one second, a line
/// "coarsegrain: <phase> ..." goes to stderr, and "coarsegrain: <phase> done in 2.31 s, peak
/// 3.2 GB" when it ends (the process's peak so far: the phase where it grows is where the memory
/// went), or "... stopped by an error after 2.31 s, peak 3.2 GB" when an exception ends it;
/// phases shorter than a second print nothing. The time is added to `timings` (if given)
/// when the phase ends or stop() is called.
class Phase {
  public:
    /// @throws Interrupted if an interrupt is requested (request_interrupt) and the phase does
    ///         not start inside an OpenMP parallel region
    Phase(std::string name, Timings* timings = nullptr);
    ~Phase();
    Phase(const Phase&) = delete;
    Phase& operator=(const Phase&) = delete;
    /// Ends the phase now; returns its seconds.
    double stop();

  private:
    struct Watch;
    std::string m_name;
    Timings* m_timings;
    std::chrono::steady_clock::time_point m_start;
    std::unique_ptr<Watch> m_watch;
    bool m_stopped = false;
};

}  // namespace coarsegrain
