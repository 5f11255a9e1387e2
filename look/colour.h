// Colour management of a look (its colour settings, look/look.h): which OCIO config is
// active, the input picture's colour space to the model's working space, and the model's
// result to an output colour space or to a display and view, for every front end. The
// library is ocio/.
//
// What the model's result is, per output mode (core/develop.h):
//   print, negative, texture  working-space values (linear Rec.709, D65)
//   scan                      Cineon log code values / 1023 (the "Cineon Log" space)
//   density                   data: asking to colour-convert it is an error
#pragma once

#include <string>
#include <vector>

#include "core/develop.h"
#include "core/image.h"
#include "look/parameters.h"
#include "ocio/transform.h"

namespace darkroom {

// The active config and the two conversions one develop run needs, resolved up front so
// that a bad config or name fails before any pixel is computed (UserError naming it, and
// the setting by `name`: a flag, a plugin parameter, a keyword).
class ColourIO {
public:
    // With `verbose`, prints the active config and why, the working space, and each
    // conversion (or that it is skipped as a no-op) to stderr.
    ColourIO(const ColourSettings& settings, OutputMode output, bool verbose, const Naming& name = flag_name);

    // In place, on the colour channels (the first three, or a grey image's one: further
    // channels, e.g. alpha, unchanged), on `threads` threads (0: all cores).
    void input_to_working(const ImageView& image, int threads) const { apply(*input_, image, threads); }
    void result_to_output(const ImageView& image, int threads) const { apply(*output_, image, threads); }

    const ocio::ColorConverter& converter() const { return converter_; }
    // The input colour space as given; empty for the working space.
    const std::string& input_space() const { return input_space_; }
    const ocio::Conversion& input_conversion() const { return *input_; }
    const ocio::Conversion& output_conversion() const { return *output_; }
    // What to warn of when an input file's own tag ("oiio:ColorSpace", `file_space`) names a
    // colour space the config knows and the pixels are read as another: without --iscolorspace
    // an sRGB PNG or JPEG would be taken as scene-linear. Empty when there is nothing to say:
    // --iscolorspace given (it overrides the tag), no tag, a tag the config does not know
    // (OpenImageIO's "Linear" for float formats), or the working space under any name.
    std::string input_tag_warning(const std::string& path, const std::string& file_space) const;
    // What to warn of when working-space (linear) values are written unconverted to an
    // integer file (a PNG, a JPEG, -d uint8 or uint16): it shows dark and clips at 1. Empty
    // for a float file, a converted result, a scan (code values) or densities (refused elsewhere).
    std::string integer_output_warning(const std::string& path, bool integer_file) const;
    // The config's name for the colour space the written result is in, for the output's
    // "oiio:ColorSpace"; empty where the result is data (density) or in no space the config
    // names (a scan without a Cineon log space, a working space reached through ACES).
    const std::string& output_space() const { return output_space_; }
    // Whether the written result is the scan's Cineon log code values, unconverted: printing
    // density, as a film scanner's DPX says in its header.
    bool writes_printing_density() const { return output_mode_ == OutputMode::scan && output_->is_noop(); }

private:
    static void apply(const ocio::Conversion& conversion, const ImageView& image, int threads);

    ocio::ColorConverter converter_;
    std::string input_space_, output_space_;
    OutputMode output_mode_;
    Naming name_;
    ocio::ConversionPtr input_, output_;
};

}  // namespace darkroom
