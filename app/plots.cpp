#include "plots.hpp"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

namespace coarsegrain::app {

namespace {

std::string env_or(const char* name, const std::string& fallback) {
    const char* v = std::getenv(name);
    return v && *v ? std::string(v) : fallback;
}

std::string python() {
    return env_or("COARSEGRAIN_PYTHON",
                  access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3");
}

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// Runs a shell command; returns its exit status and stdout + stderr.
int run_captured(const std::string& command, std::string& output) {
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return -1;
    std::array<char, 512> buffer{};
    while (std::fgets(buffer.data(), static_cast<int>(buffer.size()), pipe))
        output += buffer.data();
    return pclose(pipe);
}

/// Folders that may hold the plotting scripts, in the order they are tried: $COARSEGRAIN_SCRIPTS
/// alone if set; else, relative to this executable's folder (/proc/self/exe, symbolic links
/// resolved), an install's <prefix>/share/coarsegrain/scripts beside <prefix>/bin, then the
/// build tree's link to the source scripts/ (made by CMake next to the executable). No source
/// path is compiled in.
std::vector<std::filesystem::path> script_dirs() {
    namespace fs = std::filesystem;
    if (const char* v = std::getenv("COARSEGRAIN_SCRIPTS"); v && *v) return {fs::path(v)};
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (ec || exe.empty()) return {};
    const fs::path dir = exe.parent_path();
    return {(dir / COARSEGRAIN_SCRIPTS_INSTALL_RELATIVE).lexically_normal(),
            (dir / COARSEGRAIN_SCRIPTS_BUILD_RELATIVE).lexically_normal()};
}

}  // namespace

std::vector<PlotOutput> table_plots(const io::Table& table) {
    const std::string csv = table.name + ".csv";
    if (table.name == "mra_levels")
        return {{"plot_mra.py",
                 {"mra_errors.png", csv, "--cond", "mra_condition.png"},
                 {"mra_errors.png", "mra_condition.png"}}};
    if (table.name == "coarsest_youngs")
        return {{"plot_youngs.py", {"coarsest_youngs.png", csv}, {"coarsest_youngs.png"}}};
    if (table.name == "coarsest_stress")
        return {{"plot_stress.py", {"coarsest_stress.png", csv}, {"coarsest_stress.png"}}};
    return {};
}

bool make_plot(const std::string& out_dir, const PlotOutput& plot) {
    namespace fs = std::filesystem;
    const std::vector<fs::path> dirs = script_dirs();
    // The first folder holding the script; if none does, the first one, for the messages.
    fs::path script = dirs.empty() ? fs::path(plot.script) : dirs.front() / plot.script;
    for (const fs::path& d : dirs) {
        std::error_code ec;
        if (fs::is_regular_file(d / plot.script, ec)) {
            script = d / plot.script;
            break;
        }
    }
    std::string command = python() + " " + shell_quote(fs::absolute(script).string());
    for (const std::string& a : plot.args) {
        command += ' ';
        command += shell_quote(a);
    }
    std::string output;
    const int status = fs::exists(script)
                           ? run_captured("cd " + shell_quote(out_dir) + " && " + command, output)
                           : -1;
    bool made = status == 0;
    for (const std::string& f : plot.files) made = made && fs::exists(fs::path(out_dir) / f);
    if (made) return true;
    std::string files;
    for (const std::string& f : plot.files) {
        if (!files.empty()) files += ", ";
        files += f;
    }
    std::string searched;
    for (const fs::path& d : dirs) searched += (searched.empty() ? "" : ", ") + d.string();
    const std::string reason =
        !fs::exists(script)
            ? "script " + plot.script + " not found in " +
                  (searched.empty() ? "(no folder)" : searched) +
                  "; set COARSEGRAIN_SCRIPTS to the folder holding it"
            : "needs Python 3 with matplotlib; " +
                  (output.empty() ? "exit status " + std::to_string(status)
                                  : output.substr(0, output.find('\n')));
    std::fprintf(stderr, "note: %s not made (%s). To make it: cd %s && %s\n", files.c_str(),
                 reason.c_str(), shell_quote(out_dir).c_str(), command.c_str());
    return false;
}

}  // namespace coarsegrain::app
