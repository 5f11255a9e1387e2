// Look files (look/look.h): the text of a file applied to a default look, as `--look FILE`,
// the plugin's Look file and Python's look= do. Rejection is a UserError and changes nothing;
// an accepted look must pass the cross-setting checks or be refused by them with a
// UserError, save and read back as the same look, and develop a frame to finite colour
// (fuzz_render.h) at the fast tier and at its own (the reference tier's cost grows with the
// frame's size in mm, so it is left to the corpus's extreme files, tests/look/test_extremes.cpp)
// or refuse with a UserError.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "look/look.h"
#include "look/parameters.h"
#include "look/user_error.h"
#include "tests/fuzz/fuzz_check.h"
#include "tests/fuzz/fuzz_render.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    darkroom::Look look;
    try {
        darkroom::apply_look_text(look, std::string(reinterpret_cast<const char*>(data), size), "fuzz input");
    } catch (const darkroom::UserError&) {
        fuzz_require(look == darkroom::Look{});
        return 0;
    }
    const nlohmann::json saved = look.to_json();
    darkroom::Look reloaded;
    darkroom::apply_look_json(reloaded, saved, "the fuzz input's look, saved");
    fuzz_require(reloaded.to_json() == saved);
    using darkroom::Quality;
    std::vector<Quality> tiers{Quality::fast};
    if (look.settings.quality != Quality::fast && look.settings.quality != Quality::reference)
        tiers.push_back(look.settings.quality);
    for (Quality quality : tiers) {
        try {
            fuzz_require(darkroom::fuzz::develops_finite(look, quality).value_or(true));
        } catch (const darkroom::UserError&) {
        }
    }
    return 0;
}
