// A look: everything that decides how an image develops (stocks, exposure and printing,
// output, grain, optics, colour management, quality). It is Darkroom's saved object: dialled
// in the plugin, rendered on the farm by the program or Python, kept in look files.
//
// Every setting is a row of the parameter table (look/parameters.h), which each front end
// reads for its flags, parameters and keywords; a look file holds the table's keys:
//
//   {"format": "darkroom-look", "version": 1,
//    "settings": {"film": "kodak-tri-x-400", "exposure": 0.5, "grain": true, ...}}
//
// Keys left out keep their defaults; null leaves a setting unset (its default, or the
// stock's own value where the table says so). Their JSON Schema is
// docs/reference/schemas/look.schema.json.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/develop.h"

namespace darkroom {

inline constexpr const char* kLookFormat = "darkroom-look";
inline constexpr int kLookVersion = 1;

// OCIO: which config, the input picture's colour space and where the result goes. Empty
// names are the defaults ($OCIO, else the embedded config; the working space; unconverted).
struct ColourSettings {
    std::string config_path;
    std::string input_space;
    std::string output_space;
    std::vector<std::string> display_view;  // a display and a view, or empty
};

struct Look {
    std::string film = "kodak-vision3-250d";  // a built-in stock id or a stock file
    std::string paper = "kodak-2383";         // the same, or "none": stop at the negative
    DevelopSettings settings;                 // settings.frame is the image's, not the look's
    ColourSettings colour;
    // A plate's grain profile (darkroom grain analyze/predict): replaces the stock's grain
    // and is added to the result in the output's encoding, which should be the plate's.
    std::string grain_profile;
    // Its grain adjusted (GrainControls): per-channel gain and size, and a response tilt.
    std::array<double, 3> grain_profile_gain{1.0, 1.0, 1.0}, grain_profile_size{1.0, 1.0, 1.0};
    double grain_profile_tilt = 0;

    // The look as a look file holds it (every setting of the table).
    nlohmann::json to_json() const;
    // A look's identity: equal looks have equal ids (the canonical JSON text), so caches key
    // on it and a setting added to the table is part of it with no list to keep in step.
    std::string id() const { return to_json().dump(); }
    bool operator==(const Look& other) const { return id() == other.id(); }
};

// Sets the settings a look file's JSON gives over `look`; `source` names the file in
// messages. Throws UserError naming the file and key for an unknown key, a wrong value, a
// wrong format or version.
void apply_look_json(Look& look, const nlohmann::json& file, const std::string& source);
// The same for a file's text (UserError too when it is not JSON) and for a file.
void apply_look_text(Look& look, const std::string& text, const std::string& source);
Look read_look_file(const std::string& path, const Look& base = Look{});
// The JSON Schema of look files, made from the parameter table (a test keeps
// docs/reference/schemas/look.schema.json, this written out, the same).
nlohmann::json look_schema();
// Writes the look through a temporary file renamed over `path`, so that it is whole or absent.
void write_look_file(const std::string& path, const Look& look);

}  // namespace darkroom
