// stokesian command line: run, solve, check, plot, sweep, average (engine/app/cli.cpp, docs/cli.md).
// Exit status: 0 success, 1 usage, 2 scene/config error, 3 physics error, 4 file error, 5 out of
// memory, 6 a sweep with failed or unfinished runs.
#include "engine/app/cli.hpp"

int main(int argc, char** argv) { return stokesian::app::main_cli(argc, argv); }
