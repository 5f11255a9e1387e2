// Image files through OpenImageIO: read whole images as float, write atomically.
#pragma once

#include <OpenImageIO/imageio.h>
#include <stdexcept>
#include <string>

#include "core/image.h"

namespace darkroom::cli {

// A failure the user can act on: printed as "darkroom: error: <message>", exit 1.
struct UserError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct LoadedImage {
    Image pixels;               // window: (0, 0, width, height) of the data window
    OIIO::ImageSpec spec;       // the file's own description, for metadata pass-through
};

LoadedImage read_image(const std::string& path);

// Whether the file's format (by its extension) stores float pixels: .exr, .tif, .hdr.
bool is_float_format(const std::string& path);

// Writes to a temporary file beside `path`, then renames it over `path`, so a failed or
// interrupted write never leaves a partial file. Refuses to overwrite `protected_input`.
// Pixel type: float for .exr/.tif/.hdr, else the format's default (8/16-bit).
void write_image(const std::string& path, const Image& image, const OIIO::ImageSpec& like,
                 const std::string& protected_input = "");

// Text (JSON, SVG) written the same way: a temporary file beside `path`, then renamed.
void write_text_file(const std::string& path, const std::string& text);

}  // namespace darkroom::cli
