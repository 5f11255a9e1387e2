#include "core/develop_rows.h"

#include <algorithm>
#include <cmath>

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

// The input sanitising and exposure below, on the lanes of a double vector D (any number,
// core/simd.h): one piece of code for the vector blocks and the scalar tails, so every
// machine gets the same exposures.

// NaN is 0; the rest is held within +-kMaxInput.
template <typename D>
__attribute__((always_inline)) inline void sanitize_lanes(D& v) {
    v = v == v ? v : D{};
    v = v < -kMaxInput ? D{} - kMaxInput : v;
    v = kMaxInput < v ? D{} + kMaxInput : v;
}

// h[x ..] = clamp((w . rgb) * scale, 0, kMaxInput); for grey input (w null) rgb[0] * scale.
template <typename D, typename F>
__attribute__((always_inline)) inline void exposure_lanes(const double* const* rgb, const double* w, double scale,
                                                          int x, float* h) {
    D c[3];
    for (int i = 0; i < (w ? 3 : 1); ++i) simd::load(c[i], rgb[i] + x);
    D e = (w ? w[0] * c[0] + w[1] * c[1] + w[2] * c[2] : c[0]) * scale;
    e = e < 0.0 ? D{} : e;  // a selection, as std::clamp: signed zeros kept
    e = kMaxInput < e ? D{} + kMaxInput : e;
    simd::store(h + x, __builtin_convertvector(e, F));
}

// out[x ..] = the sanitised values of channel `first` of interleaved pixels `stride` floats apart.
template <typename D>
__attribute__((always_inline)) inline void sanitized_lanes(const float* first, int stride, int x, double* out) {
    D v;
    for (int k = 0; k < int(sizeof v / sizeof(double)); ++k) v[k] = first[size_t(x + k) * stride];
    sanitize_lanes(v);
    simd::store(out + x, v);
}

// A row in vectors of half the float lanes' doubles, then one at a time:
// one channel of interleaved pixels, sanitised,
struct SanitizedChannel {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* first, int stride, int width, double* out) {
        constexpr int doubles = lanes / 2;
        int x = 0;
        for (; x + doubles <= width; x += doubles)
            sanitized_lanes<typename simd::Lanes<doubles>::D>(first, stride, x, out);
        for (; x < width; ++x) sanitized_lanes<simd::Double1>(first, stride, x, out);
    }
};

// and one layer's exposure (exposure_lanes).
struct ExposureRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const double* const* rgb, const double* w, double scale, int width,
                                                   float* h) {
        constexpr int doubles = lanes / 2;
        int x = 0;
        for (; x + doubles <= width; x += doubles)
            exposure_lanes<typename simd::Lanes<doubles>::D, typename simd::Lanes<doubles>::F>(rgb, w, scale, x, h);
        for (; x < width; ++x) exposure_lanes<simd::Double1, simd::Float1>(rgb, w, scale, x, h);
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
    : in_(in), weights_(weights), grey_input_(grey_input), scale_(scale) {
    for (const auto& w : weights) grey_scale_.push_back((w[0] + w[1] + w[2]) * scale);
}

void FilmExposure::row(int y, int x0, int width, float* const* exposure) const {
    const int source[3] = {0, colour_channel(in_, 1), colour_channel(in_, 2)};  // grey: R = G = B
    thread_local std::vector<double> channel[3];  // the row's sanitised colour channels
    for (auto& c : channel)
        if (c.size() < size_t(width)) c.resize(size_t(width));
    const double* rgb[3] = {channel[0].data(), channel[1].data(), channel[2].data()};
    for (int c = 0; c < (grey_input_ ? 1 : 3); ++c)
        simd::dispatch<SanitizedChannel>(in_.at(x0, y) + source[c], in_.channels, width, channel[c].data());
    for (size_t l = 0; l < weights_.size(); ++l)
        simd::dispatch<ExposureRow>(rgb, grey_input_ ? nullptr : weights_[l].data(),
                                    grey_input_ ? grey_scale_[l] : scale_, width, exposure[l]);
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
