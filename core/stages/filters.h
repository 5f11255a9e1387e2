// Linear filters shared by the stages: pixel-integrated Gaussians and separable
// convolution that clamps coordinates to the frame (so a window equals that window of
// the full frame, bit for bit).
#pragma once

#include <functional>
#include <vector>

#include "core/image.h"

namespace darkroom {

// The 1D Gaussian of standard deviation sigma_px, each tap the integral over its pixel,
// truncated at 4 sigma and normalised to unit sum (one tap when sigma_px is negligible).
std::vector<float> pixel_integrated_gaussian(double sigma_px);

// One row: out[x] = sum_k taps[k] in[x + k] for x in [0, width), `in` holding width +
// taps - 1 values. Summed in float in one order for every x (vectorisable, and each value
// independent of where the row starts): the order of k, except that symmetric taps sum
// taps[k] (in[x + k] + in[x + n-1-k]) for k < n/2 first, then the middle tap.
void convolve_row(const float* in, const std::vector<float>& taps, int width, float* out);
// One row of a vertical pass: out[x] = sum_k taps[k] rows[k][x], or added to out.
void convolve_column(const float* const* rows, const std::vector<float>& taps, int width, float* out);
void convolve_column_add(const float* const* rows, const std::vector<float>& taps, int width, float* out);

// A sum of separable filters, sum_t sign_t (taps_t in x, then taps_t in y), all of 2r + 1
// taps, streamed row by row so that the horizontal results stay in cache (a ring of the
// 2r + 1 rows the vertical pass reads, each row filtered once per thread):
//   source(y, padded) writes input row y, the width + 2r values from x = out.x0 - r;
//   target(y), when given, is where output row y of `out` is written (else a scratch row);
//   sink(y, filtered), when given, then receives that row.
// The vertical pass reads rows clamped to [row_begin, row_end). Each output value is summed
// in one fixed order (terms, then taps), whatever the threads.
using RowSource = std::function<void(int y, float* padded)>;
using RowTarget = std::function<float*(int y)>;
using RowSink = std::function<void(int y, const float* filtered)>;
struct SeparableFilter {
    std::vector<std::vector<float>> terms;
    std::vector<float> signs;  // +1 or -1 per term
};
void filter_separable(const Window& out, const SeparableFilter& filter, int row_begin, int row_end, int threads,
                      const RowSource& source, const RowTarget& target, const RowSink& sink);

// dst = separable convolution of src with taps (x then y), frame-clamped as above.
void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame, int threads);
// dst = a sum of separable filters of src, frame-clamped as above.
void convolve_separable(const Plane& src, Plane& dst, const SeparableFilter& filter, const Window& frame, int threads);

}  // namespace darkroom
