#include "cli/image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace darkroom::cli {

namespace fs = std::filesystem;

LoadedImage read_image(const std::string& path) {
    if (!fs::exists(path)) throw UserError("input '" + path + "' does not exist");
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw UserError("cannot read '" + path + "': " + OIIO::geterror());
    LoadedImage out;
    out.spec = in->spec();
    const OIIO::ImageSpec& s = out.spec;
    if (s.width <= 0 || s.height <= 0 || s.nchannels <= 0) throw UserError("'" + path + "' has no pixels");
    if ((long long)s.width * s.height * s.nchannels > (1LL << 32))
        throw UserError("'" + path + "' is too large (" + std::to_string(s.width) + "x" + std::to_string(s.height) + ")");
    out.pixels = Image(s.width, s.height, s.nchannels);
    if (!in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, out.pixels.pixels.data()))
        throw UserError("cannot read pixels of '" + path + "': " + in->geterror());
    return out;
}

// Renames a finished temporary file over the target, removing it if that fails.
static void move_into_place(const fs::path& temp, const fs::path& target) {
    std::error_code ec;
    fs::rename(temp, target, ec);
    if (ec) {
        fs::remove(temp, ec);
        throw UserError("cannot move the finished output to '" + target.string() + "': " + ec.message());
    }
}

static bool same_file(const std::string& a, const std::string& b) {
    std::error_code ec;
    return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

bool is_float_format(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower((unsigned char)c));
    return ext == ".exr" || ext == ".tif" || ext == ".tiff" || ext == ".hdr";
}

void write_image(const std::string& path, const Image& image, const OIIO::ImageSpec& like,
                 const std::string& protected_input) {
    if (!protected_input.empty() && same_file(path, protected_input))
        throw UserError("refusing to overwrite the input '" + path + "' with the output");
    fs::path target(path);
    bool wants_float = is_float_format(path);

    OIIO::ImageSpec spec(image.window.width(), image.window.height(), image.channels,
                         wants_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT16);
    spec.x = image.window.x0;
    spec.y = image.window.y0;
    spec.full_x = like.full_x;
    spec.full_y = like.full_y;
    spec.full_width = like.full_width > 0 ? like.full_width : spec.width;
    spec.full_height = like.full_height > 0 ? like.full_height : spec.height;
    if (image.channels == 4) spec.alpha_channel = 3;

    // The temporary name keeps the extension so OIIO picks the same format.
    fs::path temp = target.parent_path() / (".darkroom-tmp-" + std::to_string(getpid()) + "-" +
                                            target.filename().string());
    auto out = OIIO::ImageOutput::create(target.string());
    if (!out) throw UserError("cannot write '" + path + "': " + OIIO::geterror());
    if (!out->supports("origin")) spec.x = spec.y = 0;
    if (!out->open(temp.string(), spec) ||
        !out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()) || !out->close()) {
        std::string err = out->geterror();
        std::error_code ec;
        fs::remove(temp, ec);
        throw UserError("cannot write '" + path + "': " + err);
    }
    move_into_place(temp, target);
}

void write_text_file(const std::string& path, const std::string& text) {
    fs::path target(path), temp = target.parent_path() / (".darkroom-tmp-" + std::to_string(getpid()) + "-" +
                                                          target.filename().string());
    {
        std::FILE* f = std::fopen(temp.string().c_str(), "wb");
        if (!f) throw UserError("cannot write '" + path + "'");
        bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
        ok &= std::fclose(f) == 0;
        if (!ok) {
            fs::remove(temp);
            throw UserError("cannot write '" + path + "'");
        }
    }
    move_into_place(temp, target);
}

}  // namespace darkroom::cli
