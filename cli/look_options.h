// The look flags shared by every command that develops (develop, demo, bake-lut): stocks,
// exposure, output mode, grain, MTF and halation switches, seed and frame, and the colour
// flags (cli/colour_io.h).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "cli/colour_io.h"
#include "core/develop.h"

namespace darkroom::cli {

struct LookOptions {
    std::string film = "kodak-tri-x-400";
    std::string paper = "vdr-paper-grade-2";  // "none" stops at the negative
    DevelopSettings settings;
    ColourOptions colour;
    int threads = 0;
    bool verbose = false;
};

void add_look_flags(CLI::App& command, LookOptions& look);

// Resolves the stocks and compiles the plan for a frame; prints it with -v.
Plan compile_look(const LookOptions& look, const FrameGeometry& frame);

}  // namespace darkroom::cli
