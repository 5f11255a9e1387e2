#include "core/develop_rows.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>

#include "core/stages/print.h"
#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

namespace {

// The scan output: Cineon-style 10-bit printing-density code values (Kodak Cineon: 0.002
// density per code value, base+fog at code 95), written as code / 1023.
constexpr double kScanBaseCode = 95.0, kScanDensityPerCode = 0.002, kScanFullCode = 1023.0;

// The input's sanitising and exposure below work on the lanes of a vector of any width
// (core/simd.h), one piece of code for the vector blocks and the scalar tails, so every
// machine gets the same exposures.

// NaN is 0; the rest is held within +-kMaxInput (floats or doubles).
template <typename V>
__attribute__((always_inline)) inline void sanitize_lanes(V& v) {
    using T = std::remove_reference_t<decltype(v[0])>;
    constexpr T max = T(kMaxInput);
    v = v == v ? v : V{};
    v = v < -max ? V{} - max : v;
    v = max < v ? V{} + max : v;
}

// Lane j of channel `channel` of `vectors` vectors of interleaved pixels: where its float
// lies (vector, index), and the two shuffles that gather it (core/simd.h's vectors of
// `lanes`): for three vectors the first two's, then the third's; for four, the first
// pair's and the second pair's, then both.
constexpr int source_of(int j, int channel, int vectors) { return j * vectors + channel; }
constexpr int first_pick(int j, int channel, int vectors, int lanes) {
    const int s = source_of(j, channel, vectors);
    return s < 2 * lanes ? s : (vectors == 4 ? s - 2 * lanes : 0);
}
constexpr int second_pick(int j, int channel, int vectors, int lanes) {
    const int s = source_of(j, channel, vectors);
    if (vectors == 4) return s < 2 * lanes ? j : lanes + j;
    return s < 2 * lanes ? j : lanes + s - 2 * lanes;
}

template <int channel, int vectors, typename V, size_t... J>
__attribute__((always_inline)) inline V deinterleaved(const V* v, std::index_sequence<J...>) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    const V low = __builtin_shufflevector(v[0], v[1], first_pick(J, channel, vectors, lanes)...);
    const V high = vectors == 4 ? __builtin_shufflevector(v[2], v[3], first_pick(J, channel, vectors, lanes)...) : v[2];
    return __builtin_shufflevector(low, high, second_pick(J, channel, vectors, lanes)...);
}

// The first `colours` (1 or 3) colour channels of the lanes' pixels from px on, `stride`
// floats apart (a grey image, grey_image, holds all three in its first): vector loads and
// shuffles for RGB and RGBA pixels, else a load a lane.
template <typename V>
__attribute__((always_inline)) inline void channels_at(const float* px, int stride, bool grey_image, int colours,
                                                       V* c) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    if constexpr (lanes >= 4) {
        if (colours == 3 && !grey_image && (stride == 3 || stride == 4)) {
            V v[4];
            for (int k = 0; k < stride; ++k) simd::load(v[k], px + k * lanes);
            const auto j = std::make_index_sequence<lanes>();
            if (stride == 3) {
                c[0] = deinterleaved<0, 3>(v, j), c[1] = deinterleaved<1, 3>(v, j), c[2] = deinterleaved<2, 3>(v, j);
            } else {
                c[0] = deinterleaved<0, 4>(v, j), c[1] = deinterleaved<1, 4>(v, j), c[2] = deinterleaved<2, 4>(v, j);
            }
            return;
        }
    }
    for (int i = 0; i < colours; ++i)
        for (int k = 0; k < lanes; ++k) c[i][k] = px[size_t(k) * stride + (grey_image ? 0 : i)];
}

// Each layer's exposure at the lanes' pixels: the colours sanitised, then
// clamp((w . rgb) * scale, 0, kMaxInput), or for grey input (colours 1) clamp(grey * grey_scale).
template <typename V>
__attribute__((always_inline)) inline void exposure_lanes(const float* px, int stride, bool grey_image, int colours,
                                                          const float* weights, const float* grey_scale, int layers,
                                                          float scale, int x, float* const* exposure) {
    constexpr float max = float(kMaxInput);
    V c[3];
    channels_at(px + size_t(x) * stride, stride, grey_image, colours, c);
    for (int i = 0; i < colours; ++i) sanitize_lanes(c[i]);
    for (int l = 0; l < layers; ++l) {
        const float* w = weights + 3 * l;
        V e = colours == 1 ? c[0] * grey_scale[l] : (w[0] * c[0] + w[1] * c[1] + w[2] * c[2]) * scale;
        e = e < 0.0f ? V{} : e;  // a selection, as std::clamp: signed zeros kept
        e = max < e ? V{} + max : e;
        simd::store(exposure[l] + x, e);
    }
}

struct ExposureRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* px, int stride, bool grey_image, int colours,
                                                   const float* weights, const float* grey_scale, int layers,
                                                   float scale, int width, float* const* exposure) {
        int x = 0;
        for (; x + lanes <= width; x += lanes)
            exposure_lanes<typename simd::Lanes<lanes>::F>(px, stride, grey_image, colours, weights, grey_scale,
                                                           layers, scale, x, exposure);
        for (; x < width; ++x)
            exposure_lanes<simd::Float1>(px, stride, grey_image, colours, weights, grey_scale, layers, scale, x,
                                         exposure);
    }
};

}  // namespace

int colour_channel(const ConstImageView& in, int c) { return colour_channel_count(in.channels) == 3 ? c : 0; }

double sanitize(float v) {
    simd::Double1 lane{double(v)};
    sanitize_lanes(lane);
    return lane[0];
}

FilmExposure::FilmExposure(const ConstImageView& in, const std::vector<std::array<double, 3>>& weights,
                           bool grey_input, double scale)
    : in_(in), layers_(int(weights.size())), colours_(grey_input ? 1 : 3), scale_(float(scale)) {
    for (const auto& w : weights) {
        for (double v : w) weights_.push_back(float(v));
        grey_scale_.push_back(float((w[0] + w[1] + w[2]) * scale));
    }
}

void FilmExposure::row(int y, int x0, int width, float* const* exposure) const {
    simd::dispatch<ExposureRow>(in_.at(x0, y), int(in_.pixel_stride), colour_channel_count(in_.channels) == 1,
                                colours_, weights_.data(), grey_scale_.data(), layers_, scale_, width, exposure);
}

void convert_row(OutputMode output, double d_min, float* row, int width) {
    for (int x = 0; x < width; ++x) {
        if (output == OutputMode::negative)
            row[x] = float(std::pow(10.0, -double(row[x])));
        else if (output == OutputMode::scan)
            row[x] = float((kScanBaseCode + (double(row[x]) - d_min) / kScanDensityPerCode) / kScanFullCode);
    }
}

void xyz_table_to_rgb(const Table3D& table, const float* const* d, float* const* rgb, int width) {
    const Matrix3& m = print_xyz_to_rgb();
    float* const* xyz = rgb;  // XYZ first, in the result rows
    table.apply_row(d, xyz, width);
    for (int c = 0; c < 3; ++c) fast_exp2_row(xyz[c], width);
    for (int x = 0; x < width; ++x) {
        const float v[3] = {xyz[0][x], xyz[1][x], xyz[2][x]};
        for (int c = 0; c < 3; ++c)
            rgb[c][x] = float(m[c][0]) * v[0] + float(m[c][1]) * v[1] + float(m[c][2]) * v[2];
    }
}

void write_row(const float* const* result, size_t planes, const ConstImageView& in, const ImageView& out, int y, int x0,
               int width) {
    const int alpha = colour_channel_count(in.channels);  // the channel after the colour
    const bool copy_alpha = alpha < in.channels && out.channels >= 4;
    for (int i = 0; i < width; ++i) {
        float* px = out.at(x0 + i, y);
        for (int c = 0; c < 3; ++c) px[c] = result[std::min<size_t>(c, planes - 1)][i];
        if (copy_alpha) px[3] = in.at(x0 + i, y)[alpha];
    }
}

}  // namespace darkroom
