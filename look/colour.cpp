#include "look/colour.h"

#include <iostream>

#include "look/user_error.h"

namespace darkroom {

namespace {

// The active config; where another stands in for the one named, the user is told so.
ocio::ActiveConfig resolve_config(const ColourSettings& o, const Naming& name) {
    try {
        ocio::ActiveConfig active = ocio::resolve_config(o.config_path, name(parameter("colorconfig")));
        if (!active.warning.empty()) std::cerr << "darkroom: warning: " << active.warning << "\n";
        return active;
    } catch (const ocio::OcioError& e) {
        throw UserError(e.what());
    }
}

// The names a config's Cineon log space goes by (the embedded config's, then its alias).
const char* const kCineonLogSpaces[] = {"Cineon Log", "cineon"};

// The config's name for the first of `names` it defines; empty if none.
template <size_t N>
std::string config_space_named(const ocio::ColorConverter& converter, const char* const (&names)[N]) {
    for (const char* name : names) {
        try {
            return converter.canonical_color_space(name);
        } catch (const ocio::OcioError&) {
        }
    }
    return "";
}

}  // namespace

ColourIO::ColourIO(const ColourSettings& o, OutputMode output, bool verbose, const Naming& name)
    : converter_(resolve_config(o, name)), input_space_(o.input_space), output_mode_(output), name_(name) {
    const bool to_display = !o.display_view.empty();
    const ocio::ResultEncoding result =
        output == OutputMode::scan ? ocio::ResultEncoding::cineon_log : ocio::ResultEncoding::working_linear;
    // Empty colour spaces are the config's scene_linear role, as hosts and pipelines hand
    // effects scene-linear pixels in their config's terms (the embedded config's is the
    // working space itself); a config without the role leaves them in the working space.
    // The scan's code values and the densities are data: left as they are.
    const bool has_scene_linear = converter_.config().config->hasRole(ocio::OCIO::ROLE_SCENE_LINEAR);
    const bool colour_result = output != OutputMode::density && output != OutputMode::scan;
    const std::string input_space =
        !o.input_space.empty() ? o.input_space : has_scene_linear ? ocio::OCIO::ROLE_SCENE_LINEAR : "";
    const std::string output_space =
        !o.output_space.empty() ? o.output_space : has_scene_linear && colour_result ? ocio::OCIO::ROLE_SCENE_LINEAR : "";
    try {
        input_ = input_space.empty()
                     ? std::make_shared<const ocio::Conversion>(
                           nullptr, "already in the working space (no " + name(parameter("iscolorspace")) + ")")
                     : converter_.to_working(input_space);
        if (to_display) {
            output_ = converter_.to_display(o.display_view[0], o.display_view[1], result);
            output_space_ = converter_.display_view_color_space(o.display_view[0], o.display_view[1]);
        } else if (!output_space.empty()) {
            output_ = converter_.from_working(output_space, result);
            output_space_ = converter_.canonical_color_space(output_space);
        } else {
            output_ = std::make_shared<const ocio::Conversion>(
                nullptr, "left as the model writes it (no " + name(parameter("tocolorspace")) + " or " +
                             name(parameter("ociodisplay")) + ")");
            if (output == OutputMode::scan)
                output_space_ = config_space_named(converter_, kCineonLogSpaces);
            else if (output != OutputMode::density)
                output_space_ = converter_.working_space().color_space;
        }
    } catch (const ocio::OcioError& e) {
        throw UserError(e.what());
    }
    if (!verbose) return;
    std::cerr << converter_.config().describe() << "\n" << "colour: " << converter_.working_space().describe() << "\n";
    auto say = [](const char* what, const ocio::Conversion& c) {
        std::cerr << "colour: " << what << ": " << c.description() << (c.is_noop() ? " (no-op: skipped)" : "") << "\n";
    };
    say("input", *input_);
    say((output_name(output) + " result").c_str(), *output_);
}

std::string ColourIO::input_tag_warning(const std::string& path, const std::string& file_space) const {
    if (!input_space_.empty() || file_space.empty()) return "";
    std::string space;
    try {
        if (converter_.to_working(file_space)->is_noop()) return "";
        space = converter_.canonical_color_space(file_space);
    } catch (const ocio::OcioError&) {
        return "";  // a name the config does not know says nothing it can act on
    }
    return "'" + path + "' says its pixels are in '" + space + "' (oiio:ColorSpace \"" + file_space +
           "\"), but they are read as the working space '" + converter_.working_space().color_space +
           "' (no " + name_(parameter("iscolorspace")) + "): give " + name_(parameter("iscolorspace")) + " \"" + space +
           "\" to convert them";
}

std::string ColourIO::integer_output_warning(const std::string& path, bool integer_file) const {
    const bool linear = output_mode_ == OutputMode::print || output_mode_ == OutputMode::negative ||
                        output_mode_ == OutputMode::texture;
    if (!integer_file || !linear || !output_->is_noop()) return "";
    return "'" + path + "' gets the " + output_name(output_mode_) + "'s linear values ('" + output_space_ +
           "') as integers: a display shows them dark and values above 1 clip; give " + name_(parameter("ociodisplay")) +
           " DISPLAY VIEW (\"\" \"\" for the config's defaults; sRGB Standard in the embedded one) or " +
           name_(parameter("tocolorspace")) + " for a "
           "picture to view, or write a float format such as .exr";
}

void ColourIO::apply(const ocio::Conversion& conversion, const ImageView& image, int threads) {
    // (A buffer of one channel is converted as grey, whatever its stride steps over.)
    conversion.apply({image.data, image.window.width(), image.window.height(), colour_channel_count(image),
                      image.pixel_stride, image.row_stride},
                     threads);
}

}  // namespace darkroom
