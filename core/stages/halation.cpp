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
    // Fine pixel x sits at u = (x + 0.5)/d - 0.5 = (2x + 1 - d)/2d on the coarse grid,
    // between blocks floor(u) and floor(u) + 1 (exact in integers).
    auto coarse_range = [&](int lo, int hi) {
        return std::make_pair(floor_div(2 * lo + 1 - d, 2 * d), floor_div(2 * (hi - 1) + 1 - d, 2 * d) + 2);
    };
    auto [cx0, cx1] = coarse_range(out.window.x0, out.window.x1);
    auto [cy0, cy1] = coarse_range(out.window.y0, out.window.y1);
    const Window blurred_window{cx0, cy0, cx1, cy1};
    const Window means_window = blurred_window.grown(r);
    Plane means(means_window), blurred(blurred_window);
    // Block means of the image extended past the frame by its edge pixels, as the Gaussian on
    // the pixels reads it (blocks past the frame too, so that the coarse Gaussian clamps
    // nothing of its own): each block's rows summed column by column (whole rows, in vector
    // registers), then its columns.
    const int px_begin = means_window.x0 * d, px_end = means_window.x1 * d;
    const int inside0 = std::clamp(px_begin, frame.x0, frame.x1), inside1 = std::clamp(px_end, frame.x0, frame.x1);
    parallel_for(means_window.y0, means_window.y1, threads, [&](int y_begin, int y_end) {
        std::vector<float> column_sums(size_t(px_end - px_begin));
        float* sums = column_sums.data() + (inside0 - px_begin);
        for (int by = y_begin; by < y_end; ++by) {
            for (int k = 0; k < d; ++k) {
                const float* in = src.row(std::clamp(by * d + k, frame.y0, frame.y1 - 1)) + (inside0 - src.window.x0);
                if (k == 0)
                    std::copy(in, in + (inside1 - inside0), sums);
                else
                    for (int i = 0; i < inside1 - inside0; ++i) sums[i] += in[i];
            }
            // The columns past the frame's edges are its edge columns.
            std::fill(column_sums.begin(), column_sums.begin() + (inside0 - px_begin), sums[0]);
            std::fill(column_sums.begin() + (inside1 - px_begin), column_sums.end(), sums[inside1 - 1 - inside0]);
            for (int bx = means_window.x0; bx < means_window.x1; ++bx) {
                float sum = 0;
                for (int x = bx * d; x < bx * d + d; ++x) sum += column_sums[size_t(x - px_begin)];
                means.at(bx, by) = sum / float(d * d);
            }
        }
    });
    convolve_separable(means, blurred, k.taps, means_window, threads);
    // Bilinear interpolation at each fine pixel's centre: first
    // along x, once per coarse row (the columns' blocks and weights are the same on every
    // row), then along y between the two rows a fine row falls between.
    const int width = out.window.width();
    std::vector<int> column0(width), column1(width);
    std::vector<float> tx(width);
    for (int x = out.window.x0; x < out.window.x1; ++x) {
        const int i = floor_div(2 * x + 1 - d, 2 * d), c = x - out.window.x0;
        tx[c] = float(2 * x + 1 - d - 2 * d * i) / float(2 * d);
        column0[c] = i - blurred_window.x0;
        column1[c] = i + 1 - blurred_window.x0;
    }
    Plane across = Plane::unset(Window{out.window.x0, blurred_window.y0, out.window.x1, blurred_window.y1});
    parallel_for(blurred_window.y0, blurred_window.y1, threads, [&](int y_begin, int y_end) {
        for (int j = y_begin; j < y_end; ++j) {
            const float* row = blurred.row(j);
            float* o = across.row(j);
            for (int c = 0; c < width; ++c) o[c] = row[column0[c]] + tx[c] * (row[column1[c]] - row[column0[c]]);
        }
    });
    const float strength = float(k.strength);
    parallel_for(out.window.y0, out.window.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const int j = floor_div(2 * y + 1 - d, 2 * d);
            const float ty = float(2 * y + 1 - d - 2 * d * j) / float(2 * d);
            const float* top = across.row(j);
            const float* bottom = across.row(j + 1);
            const float* in = src.row(y) + (out.window.x0 - src.window.x0);
            float* o = out.row(y);
            for (int c = 0; c < width; ++c) o[c] = in[c] + strength * (top[c] + ty * (bottom[c] - top[c]));
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
