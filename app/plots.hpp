#pragma once
/// The pictures of a run, made by the Python scripts of scripts/ from the files it wrote.
#include <string>
#include <vector>

#include "coarsegrain/io/table.hpp"

namespace coarsegrain::app {

/// A plot: `python3 <scripts>/<script> <args...>` run in the output folder.
struct PlotOutput {
    std::string script;              ///< file name inside scripts/, e.g. "plot_mra.py"
    std::vector<std::string> args;   ///< arguments; file names are relative to the output folder
    std::vector<std::string> files;  ///< the images the script writes (output folder names)
};

/// The plot of a table a method reports (written as <name>.csv), if there is one: mra_levels
/// (plot_mra.py: mra_errors.png, Chen 2019 Fig. 9, and mra_condition.png, Fig. 8),
/// coarsest_youngs (plot_youngs.py: coarsest_youngs.png), coarsest_stress (plot_stress.py:
/// coarsest_stress.png, Fig. 16).
std::vector<PlotOutput> table_plots(const io::Table& table);

/// Runs `python3 <scripts>/<plot.script> <plot.args...>` in `out_dir` and returns whether every
/// file of plot.files was made. The interpreter is $COARSEGRAIN_PYTHON, else /usr/bin/python3
/// if present (Debian's, with numpy and matplotlib), else python3 from PATH; the scripts folder
/// is $COARSEGRAIN_SCRIPTS, else found from this executable's location: an install's
/// <prefix>/share/coarsegrain/scripts (from <prefix>/bin), else the build tree's `scripts` link
/// to the source tree's scripts/ (beside build/release/coarsegrain). A
/// missing script or interpreter, or a script that fails (matplotlib absent), is not an error:
/// a note on stderr names the files not made, the script's message and the command that makes
/// them.
bool make_plot(const std::string& out_dir, const PlotOutput& plot);

}  // namespace coarsegrain::app
