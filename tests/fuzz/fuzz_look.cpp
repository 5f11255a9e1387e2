// Look files (cli/look_file.h): the text of a file applied to the develop command's look
// flags, as `--look FILE` does. Rejection is a UserError; an accepted look must save
// (look_json) and read back into a fresh command as the same look.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/look_file.h"
#include "cli/look_options.h"
#include "cli/user_error.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using namespace darkroom::cli;

// The look flags of `darkroom develop`, parsed from an empty command line.
struct Command {
    CLI::App app{"develop"};
    LookOptions look;
    std::string look_path, save_look_path;

    Command() {
        add_look_file_flags(app, look_path, save_look_path);
        add_look_flags(app, look);
        app.parse(std::vector<std::string>{});
    }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    Command command;
    try {
        apply_look_text(command.app, std::string(reinterpret_cast<const char*>(data), size), "fuzz input");
    } catch (const UserError&) {
        return 0;
    }
    const nlohmann::json saved = look_json(command.app);
    Command reloaded;
    apply_look(reloaded.app, saved, "the fuzz input's look, saved");
    fuzz_require(look_json(reloaded.app) == saved);
    return 0;
}
