// The look flags shared by every command that develops (develop, demo, bake-lut): stocks,
// exposure, output mode, grain, MTF and halation, printing, seed and frame, and the colour
// flags (cli/colour_io.h).
//
// Every flag registered here is part of the look (saved by --save-look, read by --look; see
// cli/look_file.h) unless it is marked configurable(false). For a setting to round-trip
// through a look file its option must know its default: options bound to a variable call
// capture_default_str(), enumerations use add_choice() and on/off settings add_switch().
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "cli/colour_io.h"
#include "core/develop.h"
#include "core/plate/grain_synthesis.h"

namespace darkroom::cli {

struct LookOptions {
    std::string film = "kodak-vision3-250d";
    std::string paper = "kodak-2383";  // "none" stops at the negative
    DevelopSettings settings;
    ColourOptions colour;
    // A plate's grain profile (darkroom grain analyze/predict): replaces the stock's grain
    // and is added to the result in the output's encoding, which should be the plate's.
    std::string grain_profile;
    // That profile read and planned once a run (load_plate_grain), shared by its frames.
    std::shared_ptr<const GrainSynthesisPlan> plate_grain;
    int threads = 0;
    bool verbose = false;
};

void add_look_flags(CLI::App& command, LookOptions& look);

// "--NAME" and "--no-NAME", with its default recorded for look files.
CLI::Option* add_switch(CLI::App& command, const std::string& name, bool& value, const std::string& help);

// An enumeration chosen by name (case-insensitive); the look file keeps the name.
template <typename Enum>
CLI::Option* add_choice(CLI::App& command, const std::string& flag, Enum& value,
                        const std::vector<std::pair<std::string, Enum>>& choices, const std::string& help) {
    std::vector<std::string> names;
    std::string current;
    for (const auto& [name, e] : choices) {
        names.push_back(name);
        if (e == value) current = name;
    }
    auto set = [&value, choices](const std::string& text) {
        for (const auto& [name, e] : choices)
            if (CLI::detail::to_lower(text) == name) value = e;
    };
    return command.add_option_function<std::string>(flag, set, help)
        ->check(CLI::IsMember(names, CLI::ignore_case))
        ->default_str(current);
}

// Resolves the stocks and compiles the plan for a frame; prints it with -v.
Plan compile_look(const LookOptions& look, const FrameGeometry& frame);

// The frame an input image is: its size, and grey when it has one or two channels (Y, Y+A),
// whose channel 0 the plan reads as R, G and B. Its window is in the film frame's
// coordinates, which is `film_width_px` wide (0: the image is the whole frame).
FrameGeometry frame_geometry(const ConstImageView& in, int film_width_px = 0);

// The plans of one look for a sequence: compiled once per film frame width (a process's
// first compile takes about half a second, several times a 2K frame's develop) and moved to
// each frame's image window and grain (Plan::in_image, Plan::for_frame). Shared by the
// threads developing frames.
class PlanCache {
public:
    explicit PlanCache(LookOptions look) : look_(std::move(look)) {}
    Plan plan_for(const FrameGeometry& frame, int frame_number);

private:
    LookOptions look_;
    std::mutex mutex_;
    std::map<std::pair<int, bool>, Plan> plans_;  // by the film frame's width and grey input
};

// Develops `out_window` of the image `in` (its window in the film frame's coordinates) with `look`
// through `plan` (compiled for `look` and this frame), converting colour with `colour` (built
// from `look`'s colour flags and output mode, once for a run). The output has max(3, input channels)
// channels; those past RGB (alpha, depth, mattes) are not film's business and pass through.
// `premultiplied_alpha`: the input channel holding an alpha its colour is premultiplied by
// (-1: none). The colour is then divided by it where it is above 0, developed, and multiplied
// by it again, as the plugin does: film develops light, not light times coverage, and where
// the alpha is 0 the result is 0 (a transparent pixel adds nothing when comped over a plate).
// The one path for the program and the Python module.
Image develop_image(const LookOptions& look, const ColourIO& colour, const Plan& plan, const ConstImageView& in,
                    const Window& out_window, int premultiplied_alpha = -1);

// A grain profile file read and planned for synthesis; a bad file is the user's error.
GrainSynthesisPlan read_plate_grain(const std::string& profile_path);

// Reads look.grain_profile, when given, into look.plate_grain: once a run, before any frame,
// so that a bad profile is the run's error, not each frame's; says that it replaces the
// stock's grain (verbose), and warns when it was measured in another space than the output's.
void load_plate_grain(LookOptions& look);

// A plate's grain (its profile read from `profile_path`) on the colour channels of `image`
// (apply_grain_profile); a profile of other channels is the user's error, naming the file.
void apply_plate_grain(const GrainSynthesisPlan& grain, const std::string& profile_path, const ImageView& image,
                       uint64_t seed, int frame, int threads);
// The same on an element whose colour may be premultiplied by the channel `premultiplied_alpha`
// (-1: none): grain on the light, not on light times coverage, so that where the element is
// transparent it adds none over the plate it is comped onto (the colour is divided by the
// alpha first and multiplied back after, as develop does). `image` holds whole pixels, packed.
void apply_plate_grain_to_element(const GrainSynthesisPlan& grain, const std::string& profile_path,
                                  const ImageView& image, int premultiplied_alpha, uint64_t seed, int frame,
                                  int threads);

// What to warn of for the values that film reads and that are not finite, with how it takes
// them: in the pixels of `in` that the plan reads for `out_window` (the window and its halo),
// the colour's, and those of the alpha it is premultiplied by (-1: none). Depth, mattes and a
// straight alpha pass through untouched (a depth of +Inf is a render's background), so they
// are not counted. Empty when every such value is finite.
std::vector<std::string> non_finite_warnings(const Plan& plan, const ConstImageView& in, const Window& out_window,
                                             int premultiplied_alpha);

}  // namespace darkroom::cli
