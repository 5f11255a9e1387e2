// Linear filters shared by the stages: pixel-integrated Gaussians and separable
// convolution that clamps coordinates to the frame (so a window equals that window of
// the full frame, bit for bit).
#pragma once

#include <vector>

#include "core/image.h"

namespace darkroom {

// The 1D Gaussian of standard deviation sigma_px, each tap the integral over its pixel,
// truncated at 4 sigma and normalised to unit sum (one tap when sigma_px is negligible).
std::vector<float> pixel_integrated_gaussian(double sigma_px);

// One row: out[x] = sum_k taps[k] in[x + k] for x in [0, width), `in` holding width +
// taps - 1 values. Summed in float in the order of k for every x (vectorisable, and each
// value independent of where the row starts).
void convolve_row(const float* in, const std::vector<float>& taps, int width, float* out);
// One row of a vertical pass: out[x] = sum_k taps[k] rows[k][x].
void convolve_column(const float* const* rows, const std::vector<float>& taps, int width, float* out);

// dst = separable convolution of src with taps (x then y), frame-clamped as above.
void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame, int threads);

}  // namespace darkroom
