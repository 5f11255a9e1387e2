// The error type every front end (the darkroom program, the plugin, the Python module)
// reports to its user as it is: a bad setting, file or name the user can act on.
#pragma once

#include <stdexcept>

namespace darkroom {

struct UserError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace darkroom
