// Grain with a profile's statistics, added to a clean image.
//
// Per channel c: out = in + sigma_c(in) * g_c, where g_c is unit-variance noise with the
// channel's autocorrelation (white noise through the zero-phase kernel of
// design_grain_kernel) and the channels' grain is correlated at lag 0 as the profile says
// (the white fields are mixed by a Cholesky factor before filtering). The white noise is
// a pure function of (seed, frame, channel, absolute pixel), so any window of a frame gets
// the pixels of that window of the full frame, whatever the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "core/plate/grain_profile.h"
#include "core/plate/noise_spectrum.h"
#include "core/stages/filters.h"

namespace darkroom {

// Noise streams of plate grain (channel c uses kPlateGrainStream + c), distinct from the
// film model's layer streams.
constexpr uint32_t kPlateGrainStream = 0x706c0000u;

// The energy a channel's kernel may leave out of its separable terms: the synthesised field
// then differs from the exact 2D convolution's by a field of at most 1e-4 of its variance
// (1 % of its standard deviation, below the analysis' own 2 % error on sigma; tested). The
// terms stream down the rows in float vectors (SeparableStream), about 4x faster on a 4K
// frame than the direct 2D sum in double they replace (docs/guides/plate-matching.md).
constexpr double kGrainKernelResidualEnergy = 1e-4;

// A channel's response curve for per-pixel use: GrainChannel::sigma_at's values exactly, the
// segment found from a grid over the levels' range (the segment a cell starts in, then the
// levels past it) where bisection, with its unpredictable branches, took a tenth of grain
// apply's time on a plate's noisy levels.
class ResponseLookup {
public:
    explicit ResponseLookup(const GrainChannel& channel);
    double sigma_at(double level) const;  // level finite

private:
    GrainChannel curve_;                  // the level and sigma of the channel
    std::vector<uint32_t> cell_segment_;  // per cell: the segment holding its start
    double cells_per_level_ = 0;
};

// What synthesis precomputes from a profile: reuse it across frames and tiles.
struct GrainSynthesisPlan {
    GrainProfile profile;
    std::vector<ResponseLookup> responses;  // per channel
    std::vector<GrainKernel> kernels;      // per channel: the 2D filter of its autocorrelation
    std::vector<SeparableFilter> filters;  // per channel: its kernel as separable terms
    std::vector<double> mixing;        // channels x channels, lower triangular, row-major
    int halo_px = 0;                   // the largest kernel radius: noise is drawn this far outside
};

// Adjustments of a profile's grain for matching by eye, per channel (R, G, B; a grey profile
// takes the first): sigma times `gain`; the grain `size` times larger (the autocorrelation
// stretched, bilinear between lags; white grain stays white); and the response tilted by
// 2^(tilt * t), t from -1/2 at the profile's lowest level to 1/2 at its highest (tilt: stops
// of sigma across the measured range; constant beyond it, as the response is).
constexpr double kMinGrainSizeScale = 0.25, kMaxGrainSizeScale = 8, kMaxResponseTilt = 8;
struct GrainControls {
    std::array<double, 3> gain{1.0, 1.0, 1.0}, size{1.0, 1.0, 1.0};
    double tilt = 0;
};
GrainProfile adjusted_grain_profile(const GrainProfile& profile, const GrainControls& controls);

GrainSynthesisPlan plan_grain_synthesis(const GrainProfile& profile, const GrainControls& controls = {});

// The white noise of a channel's plate grain at pixels x0 ... x0 + n - 1 of row y: standard
// normal, a pure function of (seed, frame, channel, absolute pixel); Box-Muller's two
// independent values of one Philox draw serve pixels 2k and 2k + 1 (half the draws).
void plate_grain_white_noise(uint64_t seed, int frame, int channel, int x0, int n, int y, double* out);

// Throws std::invalid_argument naming both counts unless a profile of `profile_channels`
// channels can grain an image of `colour_channels` colour channels (as many, or one).
void require_profile_fits(int profile_channels, int colour_channels);

// Adds grain to the colour channels of `image` in place (colour_channel_count: further
// channels, e.g. alpha and depth, are left alone): a profile of as many channels, one per
// channel, or a grey profile (one channel), its one field on each. `image.window` is its
// place in the frame. Pixels are read only at their own position, so the caller needs no
// image halo; non-finite pixels are left unchanged. Throws as require_profile_fits.
void apply_grain_profile(const GrainSynthesisPlan& plan, const ImageView& image, uint64_t seed, int frame,
                         int threads);
void apply_grain_profile(const GrainProfile& profile, const ImageView& image, uint64_t seed, int frame, int threads);

}  // namespace darkroom
