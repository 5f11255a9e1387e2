// The look layer's user error (look/user_error.h), as the program reports it.
#pragma once

#include "look/user_error.h"

namespace darkroom::cli {

// A failure the user can act on: printed as "darkroom: error: <message>", exit 1.
using darkroom::UserError;

}  // namespace darkroom::cli
