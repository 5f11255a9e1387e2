// Look files: every look flag of a command, saved to and loaded from versioned JSON.
//
//   {"format": "darkroom-look", "version": 1,
//    "settings": {"film": "kodak-tri-x-400", "exposure": 0.5, "grain": true, ...}}
//
// A setting's key is its flag's long name without the dashes (null: not set, the program's
// default; arrays for flags that take several values), so the file covers every
// flag that add_look_flags registers, including flags added later, with no list to keep
// in step. A flag is part of the look unless it is marked configurable(false) (input and
// output names, threads, verbosity: how to run, not how the image looks). Flags given on
// the command line override the file, as with CLI11's own config files.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

namespace darkroom::cli {

inline constexpr const char* kLookFormat = "darkroom-look";
inline constexpr int kLookVersion = 1;

// Adds --look FILE and --save-look FILE to `command`; both are run options, not settings.
struct LookFileFlags {
    CLI::Option* look = nullptr;
    CLI::Option* save_look = nullptr;
};
LookFileFlags add_look_file_flags(CLI::App& command, std::string& look_path, std::string& save_look_path);

// Fills every look option of `command` that the command line left unset from `look`.
// Throws UserError naming `source` and the key for an unknown or invalid setting, a wrong
// format or version.
void apply_look(CLI::App& command, const nlohmann::json& look, const std::string& source);
// The same for the text of a look file (UserError too if it is not JSON), and for a file.
void apply_look_text(CLI::App& command, const std::string& text, const std::string& source);
void apply_look_file(CLI::App& command, const std::string& path);

// The look of `command` as parsed: every look option, given or default.
nlohmann::json look_json(const CLI::App& command);

// Writes look_json(command) to `path` through a temporary file.
void save_look_file(const CLI::App& command, const std::string& path);

}  // namespace darkroom::cli
