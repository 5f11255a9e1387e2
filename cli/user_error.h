// The look layer's user error (look/user_error.h) as the program reports it, and the
// program's exit statuses.
#pragma once

#include <CLI/Error.hpp>
#include <string>
#include <vector>

#include "look/user_error.h"

namespace darkroom::cli {

// A failure the user can act on: printed as "darkroom: error: <message>", exit kExitUserError.
using darkroom::UserError;

inline constexpr int kExitUserError = 1;
inline constexpr int kExitInternalError = 3;

struct ExitStatus {
    std::string status, meaning;
};

// Every exit status the program gives, for its --help; docs/reference/exit-codes.md lists the same
// (a test holds them to it).
inline std::vector<ExitStatus> exit_statuses() {
    auto cli11 = [](CLI::ExitCodes code) { return std::to_string(int(code)); };
    return {
        {"0", "success"},
        {std::to_string(kExitUserError),
         "a problem the message names (an input, a setting, an output); for a sequence, every failed frame"},
        {std::to_string(kExitInternalError), "an internal error (a bug)"},
        {"4", "grain compare: the grain does not match within the tolerances"},  // as grain_command.cpp exits
        {cli11(CLI::ExitCodes::ConversionError), "a flag's value that does not convert (a word for a number)"},
        {cli11(CLI::ExitCodes::ValidationError), "a flag's value it does not accept (out of range, not a choice)"},
        {cli11(CLI::ExitCodes::RequiredError), "a command or a required flag missing"},
        {cli11(CLI::ExitCodes::ExcludesError), "flags that exclude each other"},
        {cli11(CLI::ExitCodes::ExtrasError), "an unknown command, flag or argument"},
        {cli11(CLI::ExitCodes::ArgumentMismatch), "a flag with too few or too many values"},
        {"128+N",  // as atomic_file.cpp exits
         "interrupted by signal N (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP); partial outputs removed"},
    };
}

}  // namespace darkroom::cli
