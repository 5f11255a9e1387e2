// Row steps that Plan's two ways of running share: stage after stage over whole planes
// (develop.cpp) and every stage a row at a time (develop_one_pass.cpp). Internal to core.
#pragma once

#include <array>
#include <cstddef>
#include <type_traits>
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

// The proxy factors whose block means and upsample run in vector code, each its own
// instantiation (a frame of up to about 64 MP); the others a pixel at a time, the same values.
constexpr int kMaxVectorProxyFactor = 8;
// f(std::integral_constant<int, factor>()) where the factor is one of those, and true; false
// where not.
template <int N = 2, typename F>
bool with_vector_factor(int factor, F&& f) {
    if constexpr (N > kMaxVectorProxyFactor) {
        return false;
    } else {
        if (factor != N) return with_vector_factor<N + 1>(factor, f);
        f(std::integral_constant<int, N>());
        return true;
    }
}

// The preview tier's proxy (develop_proxy.cpp) reads the frame's pixels in blocks of
// factor x factor, counted from the film frame's origin: proxy pixel (X, Y) is the mean of
// the colours, sanitised, of the pixels from (N X, N Y) to (N X + N - 1, N Y + N - 1), N the
// factor, that `image` (the image's window at the frame's pixels) holds: all N^2, or fewer at
// its edges, summed a row after the other, left to right.
struct ProxyBlocks {
    Window image;
    int factor;
};
// Its colours (1 or 3, as colour_channel_count) at X ... X + width - 1 of proxy row Y, into
// `colours` interleaved.
void block_mean_row(const ConstImageView& in, const ProxyBlocks& blocks, int Y, int X, int width, float* colours);

// The proxy's bilinear upsample at `factor`: frame pixel N X + k (N the factor) has its centre
// at proxy coordinate X + offset, and takes 1 - |offset| of proxy pixel X and |offset| of its
// neighbour on that side (along x, then along y; at the proxy frame's edges the edge repeats).
constexpr double proxy_upsample_offset(int k, int factor) { return (k + 0.5) / factor - 0.5; }
// That neighbour's weight, in float as the upsample applies it.
constexpr float proxy_upsample_far_weight(int k, int factor) {
    return float(proxy_upsample_offset(k, factor) < 0 ? -proxy_upsample_offset(k, factor)
                                                      : proxy_upsample_offset(k, factor));
}

// The proxy's result upsampled to out_window's pixels of `out` at `factor`: `proxy` (RGB
// interleaved) holds the proxy pixels they interpolate, proxy_frame is the proxy's image
// window (at its edges the edge pixels repeat); written as the tiers write (write_row: the
// alpha of `in`, where it has one, copied).
void upsample_proxy(const ConstImageView& proxy, const Window& proxy_frame, int factor, const ConstImageView& in,
                    const ImageView& out, const Window& out_window, int threads);

// The standard deviation of a field after the proxy's upsample at `factor` over the field's
// own (at every frame pixel, its RMS over the pixels), for a field whose neighbouring pixels
// correlate by lag1_correlation along x and along y (and by its square diagonally).
double proxy_upsampled_sigma_ratio(double lag1_correlation, int factor);

// Each film layer's exposure from rows of the input: the row's colour channels sanitised,
// then each layer's weighted sum times `scale`, held within [0, kMaxInput], in float. Grey
// input (grey_input: its first channel alone is read) weighs it by the sum of a layer's
// weights. With `blocks_of`, the rows are the preview's proxy's, each pixel's colours those
// block_mean_row gives from `in`.
class FilmExposure {
public:
    FilmExposure(const ConstImageView& in, const std::vector<std::array<double, 3>>& weights, bool grey_input,
                 double scale, const ProxyBlocks* blocks_of = nullptr);
    // Each layer's exposure at x0 ... x0 + width - 1 of row y into exposure[layer].
    void row(int y, int x0, int width, float* const* exposure) const;

private:
    const ConstImageView& in_;
    int layers_, colours_;
    float scale_;
    std::vector<float> weights_;     // 3 per layer
    std::vector<float> grey_scale_;  // per layer, for grey input
    const ProxyBlocks* blocks_of_;
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
