// The look's flags on a command that develops (develop, demo, bake-lut), made from the
// parameter table (look/parameters.h): "--" + each key, with the table's help, default and
// range; --look FILE and --save-look FILE; and the run options beside them (threads,
// verbosity, the frame number), which are how to run, not how the image looks.
//
// Flags given on the command line override the look file, which overrides the defaults.
// Values are checked by the table's one check (check_value) after parsing, so a value
// is refused the same way from a flag, a look file, the plugin or Python.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <vector>

#include "look/look.h"
#include "look/parameters.h"

namespace darkroom::cli {

struct LookFlags {
    std::string look_path, save_look_path;
    // What the command line gave, by key: the flag's words (a switch: "true" or "false").
    std::map<std::string, std::vector<std::string>> given;
    int threads = 0;
    bool verbose = false;
    int frame = 0;
    CLI::Option* frame_option = nullptr;

    // The look: the look file's settings (or the defaults), then the flags given over them.
    // Throws UserError naming the flag or the file's key for a value the table refuses.
    Look look() const;
    bool frame_given() const { return frame_option && frame_option->count() > 0; }
};

// Which settings a command takes: all, or only those a per-pixel LUT can hold (bake-lut;
// a look file's other settings are then ignored).
enum class LookScope { all, per_pixel };

// Adds every look setting's flag, --look and --save-look, and the run options (--threads,
// -v; --frame where `with_frame`).
void add_look_flags(CLI::App& command, LookFlags& flags, LookScope scope = LookScope::all, bool with_frame = true);

}  // namespace darkroom::cli
