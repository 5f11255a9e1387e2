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

// dst = separable convolution of src with taps (x then y), frame-clamped as above.
void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame, int threads);

}  // namespace darkroom
