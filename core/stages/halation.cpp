#include "core/stages/halation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel.h"
#include "core/stages/filters.h"

namespace darkroom {

namespace {

int floor_div(int a, int d) { return a >= 0 ? a / d : -((-a + d - 1) / d); }

// Halation on the coarse grid: out = src + strength * blur(src) on out.window.
void coarse_halation(const Plane& src, Plane& out, const HalationKernel& k, const Window& frame, int threads) {
    const int d = k.decimation, r = int(k.taps.size() / 2);
    const Window coarse_frame{floor_div(frame.x0, d), floor_div(frame.y0, d), floor_div(frame.x1 - 1, d) + 1,
                              floor_div(frame.y1 - 1, d) + 1};
    // Fine pixel x sits at u = (x + 0.5)/d - 0.5 = (2x + 1 - d)/2d on the coarse grid,
    // between blocks floor(u) and floor(u) + 1 (exact in integers).
    auto coarse_range = [&](int lo, int hi) {
        return std::make_pair(floor_div(2 * lo + 1 - d, 2 * d), floor_div(2 * (hi - 1) + 1 - d, 2 * d) + 2);
    };
    auto [cx0, cx1] = coarse_range(out.window.x0, out.window.x1);
    auto [cy0, cy1] = coarse_range(out.window.y0, out.window.y1);
    const Window blurred_window = Window{cx0, cy0, cx1, cy1}.intersected(coarse_frame);
    const Window means_window = blurred_window.grown(r).intersected(coarse_frame);
    Plane means(means_window), blurred(blurred_window);
    // Block means over the block's pixels inside the frame.
    parallel_for(means_window.y0, means_window.y1, threads, [&](int y_begin, int y_end) {
        for (int by = y_begin; by < y_end; ++by) {
            const int py0 = std::max(by * d, frame.y0), py1 = std::min(by * d + d, frame.y1);
            for (int bx = means_window.x0; bx < means_window.x1; ++bx) {
                const int px0 = std::max(bx * d, frame.x0), px1 = std::min(bx * d + d, frame.x1);
                float sum = 0;
                for (int y = py0; y < py1; ++y)
                    for (int x = px0; x < px1; ++x) sum += src.at(x, y);
                means.at(bx, by) = sum / float((py1 - py0) * (px1 - px0));
            }
        }
    });
    convolve_separable(means, blurred, k.taps, coarse_frame, threads);
    // Bilinear interpolation at each fine pixel's centre, clamped to the coarse frame; the
    // columns' blocks and weights are the same on every row.
    auto clamp_coarse = [&](int v, int lo, int hi) { return std::clamp(v, lo, hi - 1); };
    const int width = out.window.width();
    std::vector<int> column0(width), column1(width);
    std::vector<float> tx(width);
    for (int x = out.window.x0; x < out.window.x1; ++x) {
        const int i = floor_div(2 * x + 1 - d, 2 * d), c = x - out.window.x0;
        tx[c] = float(2 * x + 1 - d - 2 * d * i) / float(2 * d);
        column0[c] = clamp_coarse(i, coarse_frame.x0, coarse_frame.x1) - blurred_window.x0;
        column1[c] = clamp_coarse(i + 1, coarse_frame.x0, coarse_frame.x1) - blurred_window.x0;
    }
    const float strength = float(k.strength);
    parallel_for(out.window.y0, out.window.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const int j = floor_div(2 * y + 1 - d, 2 * d);
            const float ty = float(2 * y + 1 - d - 2 * d * j) / float(2 * d);
            const float* row0 = blurred.row(clamp_coarse(j, coarse_frame.y0, coarse_frame.y1));
            const float* row1 = blurred.row(clamp_coarse(j + 1, coarse_frame.y0, coarse_frame.y1));
            const float* in = src.row(y) + (out.window.x0 - src.window.x0);
            float* o = out.row(y);
            for (int c = 0; c < width; ++c) {
                const int i0 = column0[c], i1 = column1[c];
                const float top = row0[i0] + tx[c] * (row0[i1] - row0[i0]);
                const float bottom = row1[i0] + tx[c] * (row1[i1] - row1[i0]);
                o[c] = in[c] + strength * (top + ty * (bottom - top));
            }
        }
    });
}

}  // namespace

HalationKernel design_halation(double strength, double radius_um, double pixel_pitch_um, int decimation) {
    HalationKernel k;
    k.strength = strength;
    const double sigma_px = radius_um / pixel_pitch_um;
    // Coarsen only where the Gaussian spans several blocks; the block means and the
    // interpolation add d^2/12 + d^2/6 of variance, taken off the coarse Gaussian's.
    k.decimation = std::max(1, std::min(decimation, int(sigma_px / 2)));
    const int d = k.decimation;
    if (d == 1) {
        k.taps = pixel_integrated_gaussian(sigma_px);
        k.radius = int(k.taps.size() / 2);
    } else {
        k.taps = pixel_integrated_gaussian(std::sqrt(sigma_px * sigma_px - d * d / 4.0) / d);
        k.radius = (int(k.taps.size() / 2) + 2) * d;
    }
    return k;
}

void apply_halation(const Plane& src, Plane& dst, const HalationKernel& kernel, const Window& frame, int threads) {
    if (kernel.decimation > 1) {
        coarse_halation(src, dst, kernel, frame, threads);
        return;
    }
    convolve_separable(src, dst, kernel.taps, frame, threads);
    const float strength = float(kernel.strength);
    parallel_for(dst.window.y0, dst.window.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const float* in = src.row(y) + (dst.window.x0 - src.window.x0);
            float* out = dst.row(y);
            for (int x = 0; x < dst.window.width(); ++x) out[x] = in[x] + strength * out[x];
        }
    });
}

}  // namespace darkroom
