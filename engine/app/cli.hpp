#pragma once
// The stokesian command line (docs/cli.md): subcommands run, solve, check, plot, sweep; --help on
// each, --version. Exit status: 0 success, 1 usage, 2 scene/config error, 3 physics error, 4 file
// error, 5 out of memory, 6 a sweep with failed or unfinished runs.
#include <string>
#include <vector>

namespace stokesian::app {

int main_cli(int argc, char** argv);

// A plot script (`name`): next to an installed binary (<exe>/../share/stokesian), at the configured
// install prefix, or in the source tree; empty when none exists. `searched` lists the places.
std::string find_plot_script(std::vector<std::string>* searched = nullptr,
                             const std::string& name = "stokesian_plot.py");

}  // namespace stokesian::app
