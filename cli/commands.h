// Each subcommand registers its flags and callback on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace darkroom::cli {

void add_develop_command(CLI::App& app);
void add_stocks_command(CLI::App& app);
void add_sensitometry_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_grain_command(CLI::App& app);
void add_plot_command(CLI::App& app);
void add_bake_lut_command(CLI::App& app);
void add_colorconfig_command(CLI::App& app);
void add_bench_command(CLI::App& app);

// The command line as typed, for the outputs' Software and ImageHistory metadata.
void set_command_line(int argc, char** argv);
const std::string& command_line();

}  // namespace darkroom::cli
