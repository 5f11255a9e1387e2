// Colour conversions between the model's working space and the active config's colour
// spaces and displays, on float pixel buffers.
//
// - A Conversion is a ready-to-run OCIO CPU processor. Conversions are cached process-wide
//   by (config cache id, kind, names), so asking again is a map look-up.
// - A conversion that cannot change a pixel (OCIO's isNoOp after lossless optimisation:
//   the same space, an alias or role of it, data spaces, a round trip whose steps cancel)
//   holds no processor and apply() returns at once.
// - Unknown names throw UnknownNameError listing what the config defines; a config that
//   cannot make the conversion throws ConfigError naming the config.
// - Everything here is safe to call from several threads at once.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ocio/config.h"

namespace darkroom::ocio {

// Float pixels in memory that this library does not own. Strides are in floats (as in
// core/image.h), so a row stride may be negative. RGB are the first three channels; any
// further channels (alpha, ...) are left untouched. One- and two-channel buffers are grey:
// each pixel is converted as R = G = B and the mean of the result is stored back (exact
// for the neutral-preserving conversions of the embedded config).
struct PixelBuffer {
    float* data = nullptr;  // first pixel of the first row
    int width = 0, height = 0;
    int channels = 0;
    std::ptrdiff_t pixel_stride = 0;  // floats between horizontally adjacent pixels
    std::ptrdiff_t row_stride = 0;    // floats between vertically adjacent pixels

    // Tightly packed, interleaved pixels.
    static PixelBuffer packed(float* data, int width, int height, int channels) {
        return {data, width, height, channels, channels, (std::ptrdiff_t)width * channels};
    }
};

class Conversion {
public:
    // Wraps `processor` (may be null: a no-op). `description` reads "A -> B".
    Conversion(OCIO::ConstProcessorRcPtr processor, std::string description);

    bool is_noop() const { return cpu_ == nullptr; }
    const std::string& description() const { return description_; }
    // The OCIO processor (null for a no-op), e.g. to write its operations into a CLF.
    const OCIO::ConstProcessorRcPtr& processor() const { return processor_; }

    // On `threads` row bands (0: all cores; an OFX host calling per tile passes 1).
    void apply(const PixelBuffer& pixels, int threads = 1) const;
    // Packed RGB triplets.
    void apply_rgb(float* rgb, std::size_t n_pixels) const;

private:
    OCIO::ConstProcessorRcPtr processor_;  // null for a no-op
    OCIO::ConstCPUProcessorRcPtr cpu_;     // null for a no-op
    std::string description_;
};

using ConversionPtr = std::shared_ptr<const Conversion>;

// How the working space (scene-linear Rec.709, D65) is found in the active config.
struct WorkingSpaceLink {
    std::string color_space;      // a colour space of the config that is the working space, or
    std::string aces_interchange; // else the config's aces_interchange colour space, reached
                                  // through OCIO's built-in lin Rec.709 -> ACES2065-1 transforms
    std::string problem;          // else why neither was found (conversions then throw)
    std::string describe() const;
};

// What the model's result pixels are, on the way out.
enum class ResultEncoding {
    working_linear,  // values in the working space (print, negative, texture)
    cineon_log,      // Cineon log code values / 1023 (scan): decoded by
                     // cineon_log_to_lin_rec709() first, whatever the config
};

class ColorConverter {
public:
    explicit ColorConverter(ActiveConfig config);

    const ActiveConfig& config() const { return config_; }
    const WorkingSpaceLink& working_space() const { return link_; }

    // Input colour space -> working space.
    ConversionPtr to_working(const std::string& color_space) const;
    // Working space (or Cineon log, see ResultEncoding) -> output colour space.
    ConversionPtr from_working(const std::string& color_space,
                               ResultEncoding source = ResultEncoding::working_linear) const;
    // Working space (or Cineon log) -> (display, view). An empty display means the config's
    // default display; an empty view, that display's default view. Names ignore case, as
    // in OCIO.
    ConversionPtr to_display(const std::string& display, const std::string& view,
                             ResultEncoding source = ResultEncoding::working_linear) const;

    // The config's own name for a colour space, alias or role; throws UnknownNameError.
    std::string canonical_color_space(const std::string& name) const;
    // The OCIO 2.1 encoding of a colour space ("scene-linear", "log", "sdr-video", "data",
    // ...), or "" when the config does not say.
    std::string encoding(const std::string& color_space) const;
    // The display and view to_display would use for these arguments (defaults resolved).
    std::pair<std::string, std::string> resolve_display_view(const std::string& display, const std::string& view) const;
    // The colour space that to_display's result is in (the view's, or for a view through a
    // view transform the display's), as OCIO names it.
    std::string display_view_color_space(const std::string& display, const std::string& view) const;

private:
    // The cached conversion for `key`, made from the transform `make` returns on a miss
    // (null: a no-op).
    ConversionPtr cached(const std::string& key, const std::string& description,
                         const std::function<OCIO::ConstTransformRcPtr()>& make) const;
    bool is_data(const std::string& color_space) const;
    // The working space's name for messages.
    std::string working_space_label() const;
    // `source` -> a colour space of the config that `then` starts from: the working space
    // itself, or its aces_interchange space reached through built-in transforms.
    OCIO::ConstTransformRcPtr from_result(ResultEncoding source,
                                          const std::function<OCIO::TransformRcPtr(const std::string&)>& then) const;
    void require_working_space() const;

    ActiveConfig config_;
    WorkingSpaceLink link_;
};

// The names a user config's linear Rec.709 space is looked for under, in order.
const std::vector<std::string>& working_space_candidate_names();

}  // namespace darkroom::ocio
