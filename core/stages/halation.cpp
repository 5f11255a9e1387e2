#include "core/stages/halation.h"

#include "core/stages/filters.h"

namespace darkroom {

HalationKernel design_halation(double strength, double radius_um, double pixel_pitch_um) {
    HalationKernel k;
    k.strength = strength;
    k.taps = pixel_integrated_gaussian(radius_um / pixel_pitch_um);
    k.radius = int(k.taps.size() / 2);
    return k;
}

void apply_halation(const Plane& src, Plane& dst, const HalationKernel& kernel, const Window& frame, int threads) {
    convolve_separable(src, dst, kernel.taps, frame, threads);
    const float strength = float(kernel.strength);
    for (int y = dst.window.y0; y < dst.window.y1; ++y) {
        const float* in = src.row(y) + (dst.window.x0 - src.window.x0);
        float* out = dst.row(y);
        for (int x = 0; x < dst.window.width(); ++x) out[x] = in[x] + strength * out[x];
    }
}

}  // namespace darkroom
