#include "plots.hpp"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

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

}  // namespace

bool make_plot(const std::string& out_dir, const coarsen::PlotOutput& plot) {
    namespace fs = std::filesystem;
    const fs::path script =
        fs::path(env_or("COARSEGRAIN_SCRIPTS", COARSEGRAIN_SCRIPTS_DIR)) / plot.script;
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
    const std::string reason = !fs::exists(script) ? "script " + script.string() + " not found"
                               : output.empty()    ? "exit status " + std::to_string(status)
                                                   : output.substr(0, output.find('\n'));
    std::fprintf(stderr,
                 "note: %s not made (needs Python 3 with matplotlib; %s). To make it: cd %s && "
                 "%s\n",
                 files.c_str(), reason.c_str(), shell_quote(out_dir).c_str(), command.c_str());
    return false;
}

}  // namespace coarsegrain::app
