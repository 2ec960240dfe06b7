#pragma once
/// Plots a method asks for (coarsen::PlotOutput), made by the Python scripts of scripts/.
#include <string>

#include "coarsegrain/coarsen/coarse_model.hpp"

namespace coarsegrain::app {

/// Runs `python3 <scripts>/<plot.script> <plot.args...>` in `out_dir` and returns whether every
/// file of plot.files was made. The interpreter is $COARSEGRAIN_PYTHON, else /usr/bin/python3
/// if present (Debian's, with numpy and matplotlib), else python3 from PATH; the scripts folder
/// is $COARSEGRAIN_SCRIPTS, else found from this executable's location: an install's
/// <prefix>/share/coarsegrain/scripts (from <prefix>/bin), else the build tree's `scripts` link
/// to the source tree's scripts/ (beside build/release/coarsegrain). A
/// missing script or interpreter, or a script that fails (matplotlib absent), is not an error:
/// a note on stderr names the files not made, the script's message and the command that makes
/// them.
bool make_plot(const std::string& out_dir, const coarsen::PlotOutput& plot);

}  // namespace coarsegrain::app
