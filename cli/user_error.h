// The error type every caller of the look library (the darkroom program, the Python module)
// reports to its user as it is.
#pragma once

#include <stdexcept>

namespace darkroom::cli {

// A failure the user can act on: printed as "darkroom: error: <message>", exit 1.
struct UserError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace darkroom::cli
