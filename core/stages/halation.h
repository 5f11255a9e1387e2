// Halation: light that crosses the emulsion, reflects off the back of the film base and
// exposes the emulsion again around where it came in. Modelled per layer as
//   H' = H + strength * (G_radius * H),
// G a normalised Gaussian of standard deviation radius_um on the film: the added light
// is `strength` times the exposure, spread out (the base reflects, it does not absorb, so
// halation raises the exposure of bright areas' surroundings and of the areas themselves).
#pragma once

#include <functional>
#include <vector>

#include "core/image.h"
#include "core/stock.h"

namespace darkroom {

struct HalationKernel {
    double strength = 0;
    int radius = 0;           // the halo in pixels: what a pixel's result reads around it
    std::vector<float> taps;  // 1D Gaussian, integrated over each pixel, unit sum
    // Fast tiers: the Gaussian is applied on a grid this many times coarser (blocks aligned
    // to the frame's origin, so every window agrees): block means of the image extended past
    // the frame by its edge pixels (as the exact filter reads it), the Gaussian with its
    // variance reduced by the blocks' and the interpolation's (d^2/12 + d^2/6), then
    // bilinear interpolation back to the pixels. `taps` are then on the coarse grid.
    int decimation = 1;
    // Below this added fraction the stage cannot change an 8-bit or half-float result.
    static constexpr double kNoOpStrength = 1e-5;
    bool is_noop() const { return strength < kNoOpStrength; }
};

// strength is the stock's, already multiplied by the user's scale.
HalationKernel design_halation(double strength, double radius_um, double pixel_pitch_um, int decimation = 1);

// The fast tiers' halation of planes whose kernels have the same decimation (> 1), prepared
// for the window `out`: the coarse grid's blurred block means, interpolated along x.
// read(y, x_begin, x_end, rows) writes each plane's row y (within the frame) at x in
// [x_begin, x_end), which lies within the frame; several planes read each row once.
class CoarseHalation {
public:
    using Reader = std::function<void(int y, int x_begin, int x_end, float* const* rows)>;
    CoarseHalation(const std::vector<const HalationKernel*>& kernels, const Window& out, const Window& frame,
                   int threads, const Reader& read);
    // out[x] = in[x] + strength * halo at (x, y), for the columns of `out` (in and out start at
    // its first column; y one of its rows).
    void add(size_t plane, int y, const float* in, float* out) const;

private:
    struct Interpolated {
        float strength;
        int decimation;
        Plane across;  // the blurred coarse rows interpolated to out's columns
    };
    Window out_;
    std::vector<Interpolated> planes_;
};

// dst = src + strength * gauss(src) on dst.window, reading src with coordinates clamped to
// `frame`; src.window must cover (dst.window grown by the radius) intersected with frame.
void apply_halation(const Plane& src, Plane& dst, const HalationKernel& kernel, const Window& frame, int threads);

}  // namespace darkroom
