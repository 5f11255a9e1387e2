// Halation: light that crosses the emulsion, reflects off the back of the film base and
// exposes the emulsion again around where it came in. Modelled per layer as
//   H' = H + strength * (G_radius * H),
// G a normalised Gaussian of standard deviation radius_um on the film: the added light
// is `strength` times the exposure, spread out (the base reflects, it does not absorb, so
// halation raises the exposure of bright areas' surroundings and of the areas themselves).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/image.h"
#include "core/stages/coarse_gaussian.h"
#include "core/stages/filters.h"
#include "core/stock.h"

namespace darkroom {

struct HalationKernel {
    double strength = 0;
    int radius = 0;           // the halo in pixels: what a pixel's result reads around it
    std::vector<float> taps;  // 1D Gaussian, integrated over each pixel, unit sum
    // Fast tiers: the Gaussian is applied on a grid this many times coarser
    // (stages/coarse_gaussian.h). `taps` are then on the coarse grid.
    int decimation = 1;
    // Below this added fraction the stage cannot change an 8-bit or half-float result.
    static constexpr double kNoOpStrength = 1e-5;
    bool is_noop() const { return strength < kNoOpStrength; }
};

// strength is the stock's, already multiplied by the user's scale.
HalationKernel design_halation(double strength, double radius_um, double pixel_pitch_um, int decimation = 1);

// The fast tiers' halation (decimation > 1), streamed down the rows of `out` for one thread
// (CoarseGaussianStream, whose source reads the planes' rows): row y of each plane with its
// halo added, y increasing. A plane whose kernel is null passes through.
class CoarseHalationStream {
public:
    CoarseHalationStream(const std::vector<const HalationKernel*>& kernels, const Window& out, const Window& frame,
                         CoarseGaussianStream::Source source);
    void row(int y, float* const* result);

private:
    static std::vector<const std::vector<float>*> coarse_taps(const std::vector<const HalationKernel*>& kernels);
    static int decimation(const std::vector<const HalationKernel*>& kernels);
    std::vector<float> strengths_;  // per plane
    int width_;
    CoarseGaussianStream stream_;
};

// dst = src + strength * gauss(src) on dst.window, reading src with coordinates clamped to
// `frame`; src.window must cover (dst.window grown by the radius) intersected with frame.
void apply_halation(const Plane& src, Plane& dst, const HalationKernel& kernel, const Window& frame, int threads);

}  // namespace darkroom
