#include "cli/image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/strutil.h>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <unistd.h>

#include "cli/atomic_file.h"

namespace darkroom::cli {

namespace fs = std::filesystem;

namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower((unsigned char)c));
    return ext;
}

}  // namespace

double frame_memory_bytes(const OIIO::ImageSpec& spec) {
    // The input and output as float, and the working planes of a layer or three.
    constexpr int kWorkingPlanes = 6;
    return double(spec.width) * spec.height * (2.0 * spec.nchannels + 2 + kWorkingPlanes) * sizeof(float);
}

namespace {

// A part's header checked for pixels we can hold.
void check_part(const OIIO::ImageSpec& s, const std::string& path) {
    if (s.deep) throw UserError("'" + path + "' has deep pixels, which darkroom neither develops nor passes through");
    if (s.width <= 0 || s.height <= 0 || s.nchannels <= 0) throw UserError("'" + path + "' has no pixels");
    if ((long long)s.width * s.height * s.nchannels > (1LL << 32))
        throw UserError("'" + path + "' is too large (" + std::to_string(s.width) + "x" + std::to_string(s.height) + ")");
    // Refused from its header, before its pixels are: a frame that would not fit in memory.
    const double bytes = frame_memory_bytes(s), memory = double(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
    if (memory > 0 && bytes > memory)
        throw UserError("'" + path + "' is " + std::to_string(s.width) + "x" + std::to_string(s.height) + " with " +
                        std::to_string(s.nchannels) + " channels: developing it takes some " +
                        std::to_string(int(bytes / 1e9 + 0.5)) + " GB, more than this machine's " +
                        std::to_string(int(memory / 1e9)) + " GB of memory");
}

// The file opened at its first subimage (part), its header checked.
std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path) {
    if (!fs::exists(path)) throw UserError("input '" + path + "' does not exist");
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw UserError("cannot read '" + path + "': " + OIIO::geterror());
    check_part(in->spec(), path);
    return in;
}

// Every part's header, each checked.
std::vector<OIIO::ImageSpec> part_specs(OIIO::ImageInput& in, const std::string& path) {
    std::vector<OIIO::ImageSpec> parts;
    for (int p = 0; in.seek_subimage(p, 0); ++p) {
        parts.push_back(in.spec());
        check_part(parts.back(), path);
    }
    return parts;
}

// A channel's layer ("diffuse" of "diffuse.R", "" of "R") and its name within it.
std::string layer_of(const std::string& channel) {
    const size_t dot = channel.rfind('.');
    return dot == std::string::npos ? "" : channel.substr(0, dot);
}

// The channels of `layer` named `bases`, in that order; empty unless it has them all.
std::vector<int> layer_channels(const std::vector<std::string>& names, const std::string& layer,
                                const std::vector<std::string>& bases) {
    std::vector<int> found;
    for (const std::string& base : bases) {
        const auto at = std::find(names.begin(), names.end(), layer.empty() ? base : layer + "." + base);
        if (at == names.end()) return {};
        found.push_back(int(at - names.begin()));
    }
    return found;
}

// The colour channels of `layer`: R, G, B, else Y; empty when it has neither.
std::vector<int> layer_colour(const std::vector<std::string>& names, const std::string& layer) {
    std::vector<int> rgb = layer_channels(names, layer, {"R", "G", "B"});
    return rgb.empty() ? layer_channels(names, layer, {"Y"}) : rgb;
}

// A channel layer of one of the file's parts.
struct PartLayer {
    int part = 0;
    std::string layer;
    bool operator==(const PartLayer& o) const { return part == o.part && layer == o.layer; }
};

std::string part_name(const OIIO::ImageSpec& spec, int part) {
    const std::string name = spec.get_string_attribute("oiio:subimagename");
    return name.empty() ? "#" + std::to_string(part) : name;
}

// "'diffuse', (unnamed)"; in a multi-part file with each one's part: "'diffuse' of part 'aovs'".
std::string layer_list(const std::vector<PartLayer>& layers, const std::vector<OIIO::ImageSpec>& parts) {
    std::string text;
    for (const PartLayer& l : layers) {
        text += (text.empty() ? "" : ", ") + (l.layer.empty() ? "(unnamed)" : "'" + l.layer + "'");
        if (parts.size() > 1) text += " of part '" + part_name(parts[l.part], l.part) + "'";
    }
    return text;
}

// The layer read_image develops: its part, the file channel of each of its channels (the
// layer's colour, its alpha, the rest in the file's order) and how many are colour and alpha;
// no channels for a single-part file without layered names and no `layer` asked for: it is read as it is.
struct LayerOrder {
    int part = 0;
    std::vector<int> channels;
    int colours = 0;
    bool alpha = false;
};

PartLayer chosen_layer(const std::vector<OIIO::ImageSpec>& parts, const std::optional<std::string>& layer,
                       const std::string& path) {
    std::vector<PartLayer> layers, coloured;  // in the file's order
    for (int p = 0; p < int(parts.size()); ++p)
        for (const std::string& n : parts[p].channelnames)
            if (const PartLayer l{p, layer_of(n)}; std::find(layers.begin(), layers.end(), l) == layers.end()) {
                layers.push_back(l);
                if (!layer_colour(parts[p].channelnames, l.layer).empty()) coloured.push_back(l);
            }
    auto colour_in_part = [&](int p) {
        return std::count_if(coloured.begin(), coloured.end(), [&](const PartLayer& l) { return l.part == p; });
    };
    std::vector<PartLayer> matches;  // the candidates for `layer`, or for the default
    if (layer) {
        // A channel layer by its name, or a part by its name: its unnamed colour, or its only colour layer.
        for (const PartLayer& l : coloured)
            if (l.layer == *layer || (parts.size() > 1 && part_name(parts[l.part], l.part) == *layer &&
                                      (l.layer.empty() || colour_in_part(l.part) == 1)))
                matches.push_back(l);
        const bool named = std::any_of(layers.begin(), layers.end(), [&](const PartLayer& l) {
            return l.layer == *layer || (parts.size() > 1 && part_name(parts[l.part], l.part) == *layer);
        });
        if (matches.empty() && !named)
            throw UserError("--layer '" + *layer + "': '" + path + "' has no such layer" +
                            (parts.size() > 1 ? " or part" : "") + "; its layers are " + layer_list(layers, parts));
        if (matches.empty())
            throw UserError("--layer '" + *layer + "' of '" + path + "' has no colour channels (R, G, B or Y); "
                            "the layers with colour are " + (coloured.empty() ? "none" : layer_list(coloured, parts)));
        if (matches.size() > 1)
            throw UserError("--layer '" + *layer + "' of '" + path + "' names several layers with colour, " +
                            layer_list(matches, parts) + ": name a part or layer that only one of them has");
        return matches.front();
    }
    for (const PartLayer& l : coloured)
        if (l.layer.empty()) matches.push_back(l);
    if (matches.empty()) matches = coloured;
    if (matches.size() == 1) return matches.front();
    throw UserError("'" + path + "' has " + (coloured.empty() ? "no layer with colour (R, G, B or Y)" :
                    "several layers with colour, " + layer_list(matches, parts)) +
                    ": name the one to develop with --layer (its layers are " + layer_list(layers, parts) + ")");
}

LayerOrder developed_channel_order(const std::vector<OIIO::ImageSpec>& parts, const std::optional<std::string>& layer,
                                   const std::string& path) {
    const std::vector<std::string>& first = parts.front().channelnames;
    if (!layer && parts.size() == 1 &&
        std::all_of(first.begin(), first.end(), [](const std::string& n) { return layer_of(n).empty(); }))
        return {};
    const PartLayer chosen = chosen_layer(parts, layer, path);
    const std::vector<std::string>& names = parts[chosen.part].channelnames;
    LayerOrder order;
    order.part = chosen.part;
    order.channels = layer_colour(names, chosen.layer);
    order.colours = int(order.channels.size());
    for (const char* alpha : {"A", "Alpha"})
        if (std::vector<int> a = layer_channels(names, chosen.layer, {alpha}); !a.empty()) {
            order.channels.push_back(a.front());
            order.alpha = true;
            break;
        }
    const std::vector<int> developed = order.channels;
    for (int c = 0; c < int(names.size()); ++c)
        if (std::find(developed.begin(), developed.end(), c) == developed.end()) order.channels.push_back(c);
    return order;
}

// The spec with channel i the file's channel order.channels[i].
void reorder_spec(OIIO::ImageSpec& s, const LayerOrder& layer) {
    const std::vector<int>& order = layer.channels;
    const OIIO::ImageSpec file = s;
    auto moved = [&](int channel) {
        const auto at = std::find(order.begin(), order.end(), channel);
        return channel >= 0 && at != order.end() ? int(at - order.begin()) : -1;
    };
    for (int c = 0; c < s.nchannels; ++c) {
        s.channelnames[c] = file.channelnames[order[c]];
        if (!file.channelformats.empty()) s.channelformats[c] = file.channelformats[order[c]];
    }
    // The alpha is the developed layer's own, else none (another layer's passes through).
    s.alpha_channel = layer.alpha ? layer.colours : -1;
    s.z_channel = moved(file.z_channel);
}

// Pixel channel i taken from the file's channel order[i].
void reorder_pixels(Image& image, const std::vector<int>& order) {
    const int n = image.channels;
    std::vector<float> pixel(n);
    for (size_t p = 0; p < image.pixels.size() / n; ++p) {
        float* px = image.pixels.data() + p * n;
        for (int c = 0; c < n; ++c) pixel[c] = px[order[c]];
        std::copy(pixel.begin(), pixel.end(), px);
    }
}

// The header of what read_image reads: the chosen part's, reordered; how to read it.
LoadedImage read_header(OIIO::ImageInput& in, const std::string& path, const std::optional<std::string>& layer,
                        LayerOrder& order) {
    const std::vector<OIIO::ImageSpec> parts = part_specs(in, path);
    order = developed_channel_order(parts, layer, path);
    LoadedImage out;
    out.spec = parts[order.part];
    out.subimages = int(parts.size());
    out.through.developed_part = order.part;
    if (!order.channels.empty()) reorder_spec(out.spec, order);
    return out;
}

}  // namespace

double file_memory_bytes(const std::string& path) {
    const auto in = open_image(path);
    double largest = 0, stored = 0;
    for (const OIIO::ImageSpec& part : part_specs(*in, path)) {
        largest = std::max(largest, frame_memory_bytes(part));
        stored += double(part.image_bytes(true));
    }
    return largest + stored;
}

LoadedImage read_image_header(const std::string& path, const std::optional<std::string>& layer) {
    LayerOrder order;
    return read_header(*open_image(path), path, layer, order);
}

LoadedImage read_image(const std::string& path, const std::optional<std::string>& layer, bool other_parts) {
    auto in = open_image(path);
    LayerOrder order;
    LoadedImage out = read_header(*in, path, layer, order);
    const OIIO::ImageSpec& s = out.spec;
    out.pixels = Image(s.width, s.height, s.nchannels);
    if (!in->read_image(order.part, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, out.pixels.pixels.data()))
        throw UserError("cannot read pixels of '" + path + "': " + in->geterror());
    if (!order.channels.empty()) reorder_pixels(out.pixels, order.channels);
    for (int c = 0; c < s.nchannels; ++c) {
        if (s.channelformat(c) != OIIO::TypeDesc::UINT) continue;
        const int file_channel = order.channels.empty() ? c : order.channels[c];
        ExactChannel exact{s.channelnames[c], std::vector<uint32_t>(size_t(s.width) * s.height)};
        if (!in->read_image(order.part, 0, file_channel, file_channel + 1, OIIO::TypeDesc::UINT, exact.values.data()))
            throw UserError("cannot read pixels of '" + path + "': " + in->geterror());
        out.through.exact_channels.push_back(std::move(exact));
    }
    for (int p = 0; other_parts && p < out.subimages; ++p) {
        if (p == order.part || !in->seek_subimage(p, 0)) continue;
        StoredPart part{in->spec(), std::vector<unsigned char>(in->spec().image_bytes(true))};
        if (!in->read_image(p, 0, 0, part.spec.nchannels, OIIO::TypeDesc::UNKNOWN, part.pixels.data()))
            throw UserError("cannot read pixels of '" + path + "': " + in->geterror());
        out.through.parts.push_back(std::move(part));
    }
    return out;
}

void require_holds_parts(const std::string& output, const std::string& input, const LoadedImage& image) {
    if (image.subimages <= 1 || lower_extension(output) == ".exr") return;
    throw UserError("'" + input + "' has " + std::to_string(image.subimages) + " parts, and '" + output +
                    "' is not OpenEXR, the one format that holds several: write an .exr output, which keeps every "
                    "part (choose the part or layer to develop with --layer)");
}

std::string uint32_channels_warning(const std::string& output, const LoadedImage& image) {
    if (lower_extension(output) == ".exr") return "";
    std::vector<std::string> ids;
    for (int c = 0; c < image.spec.nchannels; ++c)
        if (image.spec.channelformat(c) == OIIO::TypeDesc::UINT) ids.push_back("'" + image.spec.channelnames[c] + "'");
    if (ids.empty()) return "";
    return "the uint32 channel" + std::string(ids.size() > 1 ? "s " : " ") + OIIO::Strutil::join(ids, ", ") +
           " (object IDs) cannot be kept exactly in '" + output + "': they are written in its one data type, scaled "
           "to 0-1; write an .exr output to keep them";
}

Window window_flag(const std::vector<int>& xywh, const Window& image, const std::string& flag) {
    if (xywh.empty()) return image;
    const std::string given = flag + " " + std::to_string(xywh[0]) + "," + std::to_string(xywh[1]) + "," +
                              std::to_string(xywh[2]) + "," + std::to_string(xywh[3]);
    if (xywh[2] <= 0 || xywh[3] <= 0)
        throw UserError(given + " has no pixels: its width and height (the last two) must be above 0");
    // (In 64 bits: a width near INT_MAX would overflow its end.)
    const long long x1 = (long long)xywh[0] + xywh[2], y1 = (long long)xywh[1] + xywh[3];
    if (xywh[0] < image.x0 || xywh[1] < image.y0 || x1 > image.x1 || y1 > image.y1)
        throw UserError(given + " is not inside the " + std::to_string(image.width()) + "x" +
                        std::to_string(image.height()) + " image");
    return Window{xywh[0], xywh[1], int(x1), int(y1)};
}

int colour_channel_count(const OIIO::ImageSpec& spec) {
    // A channel's name without its layer ("diffuse.Y": "Y"; npos + 1 is 0).
    auto base = [](const std::string& name) { return name.substr(name.rfind('.') + 1); };
    const std::vector<std::string>& names = spec.channelnames;
    const bool chroma = std::any_of(names.begin(), names.end(),
                                    [&](const std::string& n) { return base(n) == "RY" || base(n) == "BY"; });
    return !names.empty() && base(names[0]) == "Y" && !chroma ? 1 : darkroom::colour_channel_count(spec.nchannels);
}

int premultiplied_alpha_channel(const OIIO::ImageSpec& spec) {
    return spec.alpha_channel >= 0 && spec.get_int_attribute("oiio:UnassociatedAlpha", 0) == 0 ? spec.alpha_channel : -1;
}

static bool same_file(const std::string& a, const std::string& b) {
    std::error_code ec;
    return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}


bool is_float_format(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".tif" || ext == ".tiff" || ext == ".hdr";
}

void require_known_compression(const std::string& path, const std::string& compression) {
    if (compression.empty()) return;
    // The names OpenImageIO's writers take (its documentation, "Bundled ImageIO Plugins"),
    // and those that take a :level (zip's 1-9, DWA's, JPEG's quality); an unknown name
    // would be written as zip without a word. TIFF's ccittrle is for 1-bit images only.
    // PNG's are zlib's strategies, every one compressed (OpenImageIO 2.4 writes `none`,
    // `zip` or an unknown name as `default`, and ignores a level); JPEG's quality is its level
    // (an unknown name gets the writer's default quality).
    struct Format {
        const char* name;
        std::vector<std::string> names, with_level;
    };
    static const Format exr{"OpenEXR", {"none", "rle", "zip", "zips", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"},
                            {"zip", "zips", "dwaa", "dwab"}};
    static const Format tiff{"TIFF", {"none", "lzw", "zip", "deflate", "packbits", "jpeg"}, {"zip", "deflate", "jpeg"}};
    static const Format png{"PNG", {"default", "filtered", "huffman", "rle", "fixed"}, {}};
    static const Format jpeg{"JPEG", {"jpeg"}, {"jpeg"}};
    const std::string ext = lower_extension(path);
    const Format* format = ext == ".exr"                     ? &exr
                           : ext == ".tif" || ext == ".tiff" ? &tiff
                           : ext == ".png"                   ? &png
                           : ext == ".jpg" || ext == ".jpeg" ? &jpeg
                                                             : nullptr;
    if (!format) return;  // (other formats' writers take their own names, or none)
    const size_t colon = compression.find(':');
    const std::string name = compression.substr(0, colon), level = colon == std::string::npos ? "" : compression.substr(colon + 1);
    auto listed = [](const std::vector<std::string>& names, const std::string& n) {
        return std::find(names.begin(), names.end(), n) != names.end();
    };
    auto join = [](const std::vector<std::string>& names) { return OIIO::Strutil::join(names, ", "); };
    if (!listed(format->names, name))
        throw UserError("--compression '" + compression + "' is not one of " + format->name + "'s: " + join(format->names));
    if (colon == std::string::npos) return;
    char* end = nullptr;
    const double value = std::strtod(level.c_str(), &end);
    if (!listed(format->with_level, name) || level.empty() || *end != '\0' || !(value > 0))
        throw UserError("--compression '" + compression + "': " +
                        (listed(format->with_level, name) ? "the level after ':' must be a number above 0"
                         : format->with_level.empty()
                             ? std::string(format->name) + " takes no level"
                             : "'" + name + "' takes no level (" + join(format->with_level) + " do)"));
}

void require_writable(const std::string& path) {
    if (!OIIO::ImageOutput::create(path)) throw UserError("cannot write '" + path + "': " + OIIO::geterror());
    require_folder(path);
}

void require_format_holds(const std::string& path, const std::string& data_type, int channels) {
    struct Limits {
        const char* name;
        std::vector<int> channels;          // empty: any count
        std::vector<std::string> types;     // -d values it stores
    };
    // What each writer stores (OpenImageIO 2.4): DPX's writer aborts on 2 or more than 4
    // channels; the others drop channels or change the type quietly.
    static const std::vector<std::pair<std::vector<std::string>, Limits>> formats{
        {{".dpx"}, {"DPX", {1, 3, 4}, {"uint8", "uint10", "uint12", "uint16", "float"}}},
        {{".png"}, {"PNG", {1, 2, 3, 4}, {"uint8", "uint10", "uint12", "uint16"}}},  // (10, 12: as 16)
        {{".jpg", ".jpeg"}, {"JPEG", {1, 3}, {"uint8"}}},
        {{".hdr"}, {"Radiance HDR", {3}, {"float"}}},
        {{".exr"}, {"OpenEXR", {}, {"half", "float"}}},
    };
    const std::string ext = lower_extension(path);
    for (const auto& [extensions, limits] : formats) {
        if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) continue;
        const std::vector<int>& counts = limits.channels;
        if (channels > 0 && !counts.empty() && std::find(counts.begin(), counts.end(), channels) == counts.end()) {
            std::vector<std::string> held;
            for (int c : counts) held.push_back(std::to_string(c));
            throw UserError("cannot write '" + path + "': " + limits.name + " holds " +
                            OIIO::Strutil::join(held, ", ") + " channels, and the output has " +
                            std::to_string(channels) + ": write OpenEXR (.exr) or TIFF (.tif), which hold any");
        }
        if (!data_type.empty() && std::find(limits.types.begin(), limits.types.end(), data_type) == limits.types.end())
            throw UserError("-d " + data_type + ": " + limits.name + " ('" + path + "') stores " +
                            OIIO::Strutil::join(limits.types, ", "));
    }
}

const std::vector<std::string>& output_data_types() {
    static const std::vector<std::string> types{"uint8", "uint10", "uint12", "uint16", "half", "float"};
    return types;
}

WriteOptions with_input_data_type(WriteOptions options, const OIIO::ImageSpec& input, const std::string& path) {
    if (!options.data_type.empty()) return options;
    // (The developed colour's own type: a layered file's others may differ.)
    const OIIO::TypeDesc type = input.channelformat(0);
    options.keep_channel_types = true;
    if (type == OIIO::TypeDesc::HALF || type == OIIO::TypeDesc::FLOAT) {
        if (is_float_format(path)) options.data_type = type.c_str();
        return options;
    }
    if (type != OIIO::TypeDesc::UINT8 && type != OIIO::TypeDesc::UINT16) return options;
    const std::string ext = lower_extension(path);
    if (ext == ".exr" || ext == ".hdr") {
        options.data_type = "half";
        return options;
    }
    const int bits = input.get_int_attribute("oiio:BitsPerSample", 0);
    options.data_type = type == OIIO::TypeDesc::UINT16 && (bits == 10 || bits == 12) ? "uint" + std::to_string(bits)
                                                                                     : type.c_str();
    return options;
}

namespace {

// -d uint10 and uint12: 16-bit integers of which the file stores that many bits, where its
// format can (DPX, TIFF; as oiiotool's -d); 0 for the other types.
int packed_bits(const WriteOptions& options) {
    return options.data_type == "uint10" ? 10 : options.data_type == "uint12" ? 12 : 0;
}

// The pixels' type asked of the writer: -d, else float for float formats and uint16 for others.
OIIO::TypeDesc output_type(const std::string& path, const WriteOptions& options) {
    if (packed_bits(options) > 0) return OIIO::TypeDesc::UINT16;
    if (!options.data_type.empty()) return OIIO::TypeDesc(options.data_type);
    return is_float_format(path) ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT16;
}

OIIO::ImageSpec output_spec(const Image& image, const OIIO::ImageSpec& like, const std::string& path,
                            const WriteOptions& options) {
    const OIIO::TypeDesc type = output_type(path, options);
    OIIO::ImageSpec spec(image.window.width(), image.window.height(), image.channels, type);
    spec.extra_attribs = like.extra_attribs;
    // The input's bit depth describes the input's encoding, not a new data type's (as oiiotool).
    if (type != like.format) spec.erase_attribute("oiio:BitsPerSample");
    if (packed_bits(options) > 0) spec.attribute("oiio:BitsPerSample", packed_bits(options));
    // A DPX header's transfer and colorimetric describe the pixels' encoding: the input's hold
    // only while its colour space does, and a scan's code values are printing density, log.
    if (options.colour_space) {
        spec.erase_attribute("dpx:Transfer");
        spec.erase_attribute("dpx:Colorimetric");
    }
    if (options.printing_density) {
        spec.attribute("dpx:Transfer", "Logarithmic");
        spec.attribute("dpx:Colorimetric", "Printing density");
    }
    spec.x = like.x + image.window.x0;
    spec.y = like.y + image.window.y0;
    spec.full_x = like.full_x;
    spec.full_y = like.full_y;
    spec.full_width = like.full_width > 0 ? like.full_width : spec.width;
    spec.full_height = like.full_height > 0 ? like.full_height : spec.height;
    // The input's channels under their names and roles (a layer's "diffuse.R" stays so). A grey
    // input developed (develop_image's layout) has R, G, B for its one channel of colour (in its
    // layer: "diffuse.Y" gives "diffuse.R"), and the channels past it two places on: its depth
    // stays "Z", the z channel, not alpha.
    const int shift = colour_channel_count(like) == 1 && image.channels == like.nchannels + 2 ? 2 : 0;
    const std::string grey_layer = shift > 0 ? layer_of(like.channelnames[0]) : "";
    std::vector<int> from(image.channels);  // the input channel of each output channel, -1: none
    for (int c = 0; c < image.channels; ++c) {
        from[c] = shift > 0 && c < 3 ? -1 : c - shift;
        const char* rgb[3] = {"R", "G", "B"};
        const bool named = from[c] >= 0 && from[c] < like.nchannels;
        spec.channelnames[c] = named ? like.channelnames[from[c]]
                               : c < 3 ? (grey_layer.empty() ? "" : grey_layer + ".") + rgb[c]
                                       : "A";
    }
    // Without -d, the channels past the colour keep their own types where the format stores
    // one per channel (a float depth beside half colour), so that they pass through bit for bit;
    // uint32 ones (object IDs) even with -d, which sets the picture's precision, not an ID's.
    if (!like.channelformats.empty() && lower_extension(path) == ".exr") {
        spec.channelformats.assign(image.channels, type);
        for (int c = 3; c < image.channels; ++c) {
            const OIIO::TypeDesc own = from[c] >= 0 && from[c] < like.nchannels ? like.channelformats[from[c]] : type;
            if (options.keep_channel_types || own == OIIO::TypeDesc::UINT) spec.channelformats[c] = own;
        }
    }
    auto output_of = [&](int input) {
        const auto at = std::find(from.begin(), from.end(), input);
        return input >= 0 && at != from.end() ? int(at - from.begin()) : -1;
    };
    // A fourth channel the input does not describe is alpha.
    const bool undescribed_fourth = image.channels == 4 && from.back() >= like.nchannels;
    spec.alpha_channel = like.alpha_channel >= 0 ? output_of(like.alpha_channel) : undescribed_fourth ? 3 : -1;
    spec.z_channel = output_of(like.z_channel);
    if (options.colour_space && options.colour_space->empty()) spec.erase_attribute("oiio:ColorSpace");
    if (options.colour_space && !options.colour_space->empty()) spec.attribute("oiio:ColorSpace", *options.colour_space);
    if (!options.compression.empty()) spec.attribute("compression", options.compression);
    if (!options.command_line.empty()) {
        std::string history = spec.get_string_attribute("Exif:ImageHistory");
        if (!OIIO::Strutil::ends_with(history, options.command_line)) {
            if (!history.empty() && history.back() != '\n') history += "\n";
            spec.attribute("Exif:ImageHistory", history + options.command_line);
        }
        spec.attribute("Software", "darkroom " DARKROOM_VERSION " : " + options.command_line);
    }
    if (!options.look_json.empty()) spec.attribute("darkroom:look", options.look_json);
    return spec;
}

}  // namespace

bool writes_integers(const std::string& path, const WriteOptions& options) {
    return !is_float_format(path) || !output_type(path, options).is_floating_point();
}

namespace {

// `image`'s pixels as the file stores them (each channel in its type in `spec`), the exact
// channels' stored values in place of their float ones. `image.window` is relative to the data
// window of `like`, which the exact channels cover.
std::vector<unsigned char> stored_pixels(const Image& image, const OIIO::ImageSpec& spec, const OIIO::ImageSpec& like,
                                         const std::vector<ExactChannel>& exact) {
    const size_t pixel_bytes = spec.pixel_bytes(true);
    std::vector<unsigned char> stored(pixel_bytes * size_t(image.window.pixel_count()));
    size_t offset = 0;  // the channel's bytes in a pixel
    for (int c = 0; c < image.channels; ++c) {
        const OIIO::TypeDesc type = spec.channelformat(c);
        const auto kept = std::find_if(exact.begin(), exact.end(), [&](const ExactChannel& e) {
            return e.name == spec.channelnames[c] && type == OIIO::TypeDesc::UINT;
        });
        for (int y = image.window.y0; y < image.window.y1; ++y)
            for (int x = image.window.x0; x < image.window.x1; ++x) {
                unsigned char* to = stored.data() + size_t((y - image.window.y0) * image.window.width() +
                                                           (x - image.window.x0)) * pixel_bytes + offset;
                if (kept != exact.end())
                    std::memcpy(to, &kept->values[size_t(y) * like.width + x], sizeof(uint32_t));
                else
                    OIIO::convert_pixel_values(OIIO::TypeDesc::FLOAT, image.at(x, y) + c, type, to);
            }
        offset += type.size();
    }
    return stored;
}

}  // namespace

std::unique_ptr<TempFile> write_image_to_temp(const std::string& path, const Image& image, const OIIO::ImageSpec& like,
                                              const std::string& protected_input, const WriteOptions& options,
                                              const PassThrough& through) {
    if (!protected_input.empty() && same_file(path, protected_input))
        throw UserError("refusing to overwrite the input '" + path + "' with the output");
    require_format_holds(path, "", image.channels);
    OIIO::ImageSpec spec = output_spec(image, like, path, options);
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw UserError("cannot write '" + path + "': " + OIIO::geterror());
    if (!out->supports("origin")) spec.x = spec.y = 0;
    // The parts in the file's order, the developed one in its place.
    std::vector<OIIO::ImageSpec> specs;
    for (const StoredPart& part : through.parts) specs.push_back(part.spec);
    const int developed = std::min(through.developed_part, int(specs.size()));
    specs.insert(specs.begin() + developed, spec);
    if (specs.size() > 1 && !out->supports("multiimage"))
        throw UserError("cannot write '" + path + "': its format holds one part, the input has " +
                        std::to_string(specs.size()));
    const bool exact = std::any_of(spec.channelformats.begin(), spec.channelformats.end(),
                                   [](OIIO::TypeDesc t) { return t == OIIO::TypeDesc::UINT; }) &&
                       !through.exact_channels.empty();
    auto write_part = [&](int p) {
        const OIIO::TypeDesc stored = OIIO::TypeDesc::UNKNOWN;  // (each channel in its own type)
        if (p != developed) return out->write_image(stored, through.parts[p - (p > developed)].pixels.data());
        if (!exact) return out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
        return out->write_image(stored, stored_pixels(image, spec, like, through.exact_channels).data());
    };
    auto temp = std::make_unique<TempFile>(fs::path(path));
    bool written = temp->create([&] { return out->open(temp->path().string(), int(specs.size()), specs.data()); });
    for (int p = 0; written && p < int(specs.size()); ++p)
        written = (p == 0 || out->open(temp->path().string(), specs[p], OIIO::ImageOutput::AppendSubimage)) &&
                  write_part(p);
    if (!written || !out->close()) throw UserError("cannot write '" + path + "': " + out->geterror());
    return temp;
}

void write_image(const std::string& path, const Image& image, const OIIO::ImageSpec& like,
                 const std::string& protected_input, const WriteOptions& options,
                 const std::function<void()>& committed, const PassThrough& through) {
    write_image_to_temp(path, image, like, protected_input, options, through)->commit(committed);
}

}  // namespace darkroom::cli
