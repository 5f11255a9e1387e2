// Look files (look/look.h): the text of a file applied to a default look, as `--look FILE`,
// the plugin's Look file and Python's look= do. Rejection is a UserError and changes nothing;
// an accepted look must pass the cross-setting checks or be refused by them with a
// UserError, and save and read back as the same look.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "look/look.h"
#include "look/parameters.h"
#include "look/user_error.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    darkroom::Look look;
    try {
        darkroom::apply_look_text(look, std::string(reinterpret_cast<const char*>(data), size), "fuzz input");
    } catch (const darkroom::UserError&) {
        fuzz_require(look == darkroom::Look{});
        return 0;
    }
    try {
        darkroom::validate(look, darkroom::look_file_key);
    } catch (const darkroom::UserError&) {
    }
    const nlohmann::json saved = look.to_json();
    darkroom::Look reloaded;
    darkroom::apply_look_json(reloaded, saved, "the fuzz input's look, saved");
    fuzz_require(reloaded.to_json() == saved);
    return 0;
}
