#include "cli/colour_io.h"

#include <iostream>

#include "cli/image_io.h"

namespace darkroom::cli {

namespace {

// The active config; where another stands in for the one named, the user is told so.
ocio::ActiveConfig resolve_config(const ColourOptions& o) {
    try {
        ocio::ActiveConfig active = ocio::resolve_config(o.config_path, "--colorconfig");
        if (!active.warning.empty()) std::cerr << "darkroom: warning: " << active.warning << "\n";
        return active;
    } catch (const ocio::OcioError& e) {
        throw UserError(e.what());
    }
}

const char* output_mode_name(OutputMode mode) {
    switch (mode) {
        case OutputMode::print: return "print";
        case OutputMode::negative: return "negative";
        case OutputMode::density: return "density";
        case OutputMode::scan: return "scan";
        case OutputMode::texture: return "texture";
    }
    return "?";
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

void add_colour_flags(CLI::App& cmd, ColourOptions& colour) {
    cmd.add_option("--colorconfig", colour.config_path,
                   "OCIO config file (default: $OCIO, else the embedded config)");
    cmd.add_option("--iscolorspace", colour.input_space,
                   "Colour space of the input (default: the working space, linear Rec.709)");
    CLI::Option* to_space =
        cmd.add_option("--tocolorspace", colour.output_space, "Convert the result to this colour space");
    cmd.add_option("--ociodisplay", colour.display_view,
                   "Convert the result to this display and view (\"\" for the config's defaults)")
        ->expected(2)
        ->type_name("DISPLAY VIEW")
        ->excludes(to_space);
}

ColourIO::ColourIO(const ColourOptions& o, OutputMode output, bool verbose)
    : converter_(resolve_config(o)), input_space_(o.input_space), output_mode_(output) {
    const bool to_display = !o.display_view.empty();
    const bool converts_result = to_display || !o.output_space.empty();
    if (output == OutputMode::density && converts_result)
        throw UserError(std::string("--output density writes densities, which are data, not colours: ") +
                        (to_display ? "--ociodisplay" : "--tocolorspace") + " cannot convert them");
    const ocio::ResultEncoding result =
        output == OutputMode::scan ? ocio::ResultEncoding::cineon_log : ocio::ResultEncoding::working_linear;
    try {
        input_ = input_space_.empty()
                     ? std::make_shared<const ocio::Conversion>(nullptr, "already in the working space (no --iscolorspace)")
                     : converter_.to_working(input_space_);
        if (to_display) {
            output_ = converter_.to_display(o.display_view[0], o.display_view[1], result);
            output_space_ = converter_.display_view_color_space(o.display_view[0], o.display_view[1]);
        } else if (!o.output_space.empty()) {
            output_ = converter_.from_working(o.output_space, result);
            output_space_ = converter_.canonical_color_space(o.output_space);
        } else {
            output_ = std::make_shared<const ocio::Conversion>(nullptr, "left as the model writes it (no --tocolorspace or --ociodisplay)");
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
    say((std::string(output_mode_name(output)) + " result").c_str(), *output_);
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
           "' (no --iscolorspace): give --iscolorspace \"" + space + "\" to convert them";
}

std::string ColourIO::integer_output_warning(const std::string& path, bool integer_file) const {
    const bool linear = output_mode_ == OutputMode::print || output_mode_ == OutputMode::negative ||
                        output_mode_ == OutputMode::texture;
    if (!integer_file || !linear || !output_->is_noop()) return "";
    return "'" + path + "' gets the " + output_mode_name(output_mode_) + "'s linear values ('" + output_space_ +
           "') as integers: a display shows them dark and values above 1 clip; give --ociodisplay DISPLAY VIEW "
           "(\"\" \"\" for the config's defaults; sRGB Standard in the embedded one) or --tocolorspace for a "
           "picture to view, or write a float format such as .exr";
}

void ColourIO::apply(const ocio::Conversion& conversion, const ImageView& image, int threads) {
    // (A buffer of one channel is converted as grey, whatever its stride steps over.)
    conversion.apply({image.data, image.window.width(), image.window.height(), colour_channel_count(image),
                      image.pixel_stride, image.row_stride},
                     threads);
}

}  // namespace darkroom::cli
