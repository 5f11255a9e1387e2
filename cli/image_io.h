// Image files through OpenImageIO: read whole images as float, write atomically.
#pragma once

#include <OpenImageIO/imageio.h>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/atomic_file.h"
#include "cli/user_error.h"
#include "core/image.h"

namespace darkroom::cli {

// A part of a multi-part file that passes through untouched: its header and its pixels as
// the file stores them (each channel in its own type).
struct StoredPart {
    OIIO::ImageSpec spec;
    std::vector<unsigned char> pixels;
};

// A channel of the developed part that float cannot hold exactly (uint32, an object ID past
// 2^24), kept as stored so that it is written back so.
struct ExactChannel {
    std::string name;
    std::vector<uint32_t> values;  // one a pixel of the part's data window, row by row
};

// What of an input passes through to its output besides the channels read as float.
struct PassThrough {
    std::vector<StoredPart> parts;  // the file's other parts, in its order
    int developed_part = 0;         // the developed part's index in the file
    std::vector<ExactChannel> exact_channels;
};

struct LoadedImage {
    Image pixels;               // window: (0, 0, width, height) of the data window
    OIIO::ImageSpec spec;       // the developed part's own description, for metadata pass-through
    int subimages = 1;          // the file's parts (a multi-part EXR, a multi-page TIFF)
    PassThrough through;
};

// The window a flag's X,Y,W,H gives (from the image's first pixel): all of `image` when it is
// empty; a UserError naming `flag` when it has no pixels or is not inside `image`.
Window window_flag(const std::vector<int>& xywh, const Window& image, const std::string& flag);

// About the memory developing a part of this header takes (its pixels read and written as
// float, and the working planes): read_image refuses a file past the machine's memory.
double frame_memory_bytes(const OIIO::ImageSpec& spec);
// The same for a whole file, from its headers: its largest part developed and the others held
// as stored to pass through; a batch runs no more frames at once than fit.
double file_memory_bytes(const std::string& path);

// The layer to develop, chosen among all the file's parts (a multi-part EXR) and the channel
// layers in each, read as float with its colour first: its colour (R, G, B or Y), then its
// alpha, then every other channel of its part in the file's order, under its own name (a
// render's AOVs: depth.Z, diffuse.R, ...). The layer is `layer`, which names a channel layer
// ("diffuse" of "diffuse.R"; "" for the channels without one) or a part (its unnamed colour,
// or its only colour layer); by default the unnamed layer with colour of any part, else the
// only layer with colour. UserError listing the candidates where the choice is ambiguous or
// `layer` has no colour. A single-part file without layered names ("name.channel") is read as
// it is, its first channels the colour. Everything else passes through (`through`, unless
// `other_parts` is false: the other parts are not read), bit for bit: the other channels of
// the part as float (exact for half and float; uint32 kept as stored), the other parts as stored.
LoadedImage read_image(const std::string& path, const std::optional<std::string>& layer = std::nullopt,
                       bool other_parts = true);

// What read_image would read, without any pixels: the developed part's header, its channels
// in read_image's order, and the file's parts; the same checks and messages.
LoadedImage read_image_header(const std::string& path, const std::optional<std::string>& layer = std::nullopt);

// Throws UserError, before any work, when the output's format cannot hold the input's parts:
// only OpenEXR holds several.
void require_holds_parts(const std::string& output, const std::string& input, const LoadedImage& image);

// What to warn of where the output cannot keep the developed part's uint32 channels (object
// IDs) exactly: any format but OpenEXR gets them as its one type, scaled to 0-1. Empty otherwise.
std::string uint32_channels_warning(const std::string& output, const LoadedImage& image);

// How many of a file's first channels are colour: one (grey) where the first is named
// luminance, "Y" or a layer's "<layer>.Y" (a grey plate with alpha and depth: Y, A, Z),
// unless the file is luminance-chroma (RY, BY); otherwise by the count (core/image.h).
int colour_channel_count(const OIIO::ImageSpec& spec);

// The channel of an alpha the colour is premultiplied by, -1 for none: OpenImageIO's readers
// give premultiplied colour (a PNG's or TIFF's straight alpha converted as it is read) unless
// the spec says "oiio:UnassociatedAlpha".
int premultiplied_alpha_channel(const OIIO::ImageSpec& spec);

// Whether the file's format (by its extension) stores float pixels: .exr, .tif, .hdr.
bool is_float_format(const std::string& path);

// Throws UserError for a --compression that the output's format (OpenEXR, TIFF, PNG or
// JPEG, by the extension) has no such name for, or a level where it takes none: OpenImageIO
// would write its default instead. Other formats' names are left to their writers.
void require_known_compression(const std::string& path, const std::string& compression);

// How an output is encoded and what it says about itself.
struct WriteOptions {
    std::string data_type;     // -d: uint8, uint10, uint12, uint16, half, float; empty: float for float formats, else uint16
                               // (develop and grain apply fill it from the input: with_input_data_type)
    std::string compression;   // --compression, as OpenImageIO names it (e.g. "zip", "dwaa:45")
    std::string command_line;  // appended to Exif:ImageHistory and named in Software, as oiiotool does
    std::string look_json;     // the settings used, stored as "darkroom:look"
    // "oiio:ColorSpace": unset keeps the input's (its pixels' space is kept); empty removes
    // it (the pixels are data); otherwise the space the written pixels are in.
    std::optional<std::string> colour_space;
    // The pixels are Cineon printing density code values (a scan): a DPX says so in its header.
    bool printing_density = false;
    // data_type is the input's own (no -d): the channels that pass through keep each their
    // own type where the format stores one per channel (OpenEXR), so they are bit for bit.
    bool keep_channel_types = false;
};

// Throws UserError, before any work, when `path` cannot be written: OpenImageIO has no writer
// for its format (by its extension), or its folder does not exist.
void require_writable(const std::string& path);

// Throws UserError, before any work, when the output's format (by the extension of `path`)
// cannot hold `channels` channels (DPX 1, 3 or 4; PNG 1 to 4; JPEG 1 or 3; Radiance HDR 3;
// 0: not checked) or the data type -d asks for (`data_type`, "" for the default): its writer
// would abort, drop channels or write another type without a word. OpenEXR and TIFF hold any.
void require_format_holds(const std::string& path, const std::string& data_type, int channels = 0);

// Whether the file gets integer pixels: a format without float ones (PNG, JPEG, DPX), or
// -d uint8 or uint16.
bool writes_integers(const std::string& path, const WriteOptions& options);

// The data types -d accepts.
const std::vector<std::string>& output_data_types();

// -d's default for an output made from `input`, as oiiotool's: the input's own data type (a
// half render's result stays half; an 8- or 16-bit, or 10- or 12-bit DPX, input's stays so),
// where the output's format stores it: a half or float input in a format without floats (PNG,
// DPX) gets the writer's default (uint16), an integer one in OpenEXR or Radiance HDR (no
// integers) half. `options` unchanged where -d was given.
WriteOptions with_input_data_type(WriteOptions options, const OIIO::ImageSpec& input, const std::string& path);

// Writes through a TempFile (cli/atomic_file.h): a failed or interrupted write never leaves
// a partial file; `committed` runs as the finished file takes its name (TempFile::commit).
// Refuses to overwrite `protected_input` (the same file under any name). `image.window` is
// relative to the data window of `like`, whose attributes, display window, channel names
// and alpha channel the output keeps (the first three channels are named R, G, B). `through`
// is written with it: its exact channels in place of theirs, and its parts (OpenEXR) around
// it, `image` in the developed part's place.
void write_image(const std::string& path, const Image& image, const OIIO::ImageSpec& like,
                 const std::string& protected_input = "", const WriteOptions& options = {},
                 const std::function<void()>& committed = {}, const PassThrough& through = {});
// The same, the finished file left under its temporary name until the caller commits it (a
// batch names its frames' outputs in frame order, whichever is written first).
std::unique_ptr<TempFile> write_image_to_temp(const std::string& path, const Image& image, const OIIO::ImageSpec& like,
                                              const std::string& protected_input, const WriteOptions& options,
                                              const PassThrough& through = {});

}  // namespace darkroom::cli
