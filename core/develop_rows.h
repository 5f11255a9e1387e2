// Row steps that Plan's two ways of running share: stage after stage over whole planes
// (develop.cpp) and every stage a row at a time (develop_one_pass.cpp). Internal to core.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "core/develop.h"
#include "core/image.h"

namespace darkroom {

// Input values beyond this magnitude (and +Inf) are held at it; NaN and -Inf count as 0.
constexpr double kMaxInput = 1e30;

// The input channel that holds colour channel c (R, G, B): grey input (one channel, or grey
// and alpha) holds all three in its first.
int colour_channel(const ConstImageView& in, int c);

// An input value as the film sees it: NaN and -Inf are 0, the rest held within +-kMaxInput.
double sanitize(float v);

// The preview tier's proxy (develop_proxy.cpp) reads the frame's pixels in 2x2 blocks, counted
// from the film frame's origin: proxy pixel (X, Y) is the mean of the colours, sanitised, of
// the pixels from (2X, 2Y) to (2X + 1, 2Y + 1) that `image` (the image's window at the frame's
// pixels) holds: 4, or 2 or 1 at its edges, summed a row after the other, left to right.
// Its colours (1 or 3, as colour_channel_count) at X ... X + width - 1 of proxy row Y, into
// `colours` interleaved.
void block_mean_row(const ConstImageView& in, const Window& image, int Y, int X, int width, float* colours);

// The standard deviation of a field after the proxy's upsample over the field's own (its
// bilinear taps, 3/4 and 1/4 along each axis, at every frame pixel), for a field whose
// neighbouring pixels correlate by lag1_correlation along x and along y.
double proxy_upsampled_sigma_ratio(double lag1_correlation);

// Each film layer's exposure from rows of the input: the row's colour channels sanitised,
// then each layer's weighted sum times `scale`, held within [0, kMaxInput], in float. Grey
// input (grey_input: its first channel alone is read) weighs it by the sum of a layer's
// weights. With `blocks_of`, the rows are the preview's proxy's, each pixel's colours those
// block_mean_row gives from `in`, whose image window at the frame's pixels it is.
class FilmExposure {
public:
    FilmExposure(const ConstImageView& in, const std::vector<std::array<double, 3>>& weights, bool grey_input,
                 double scale, const Window* blocks_of = nullptr);
    // Each layer's exposure at x0 ... x0 + width - 1 of row y into exposure[layer].
    void row(int y, int x0, int width, float* const* exposure) const;

private:
    const ConstImageView& in_;
    int layers_, colours_;
    float scale_;
    std::vector<float> weights_;     // 3 per layer
    std::vector<float> grey_scale_;  // per layer, for grey input
    const Window* blocks_of_;
};

// A row of developed densities as `output` writes them: the negative's transmittance 10^-D,
// the scan's code values / 1023 (code 95 at base_density, kScanDensityPerCode per code), or
// (density, print) unchanged.
void convert_row(OutputMode output, double base_density, float* row, int width);

// Row y of the result into channels 0-2 of `out` from x0 on (a single plane serves all
// three), and the input's alpha (the channel after its colour) where both have one.
void write_row(const float* const* result, size_t planes, const ConstImageView& in, const ImageView& out, int y, int x0,
               int width);

}  // namespace darkroom
