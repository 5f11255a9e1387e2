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
    // Block means over the block's pixels inside the frame: its rows summed column by column
    // (whole rows, in vector registers), then its columns.
    parallel_for(means_window.y0, means_window.y1, threads, [&](int y_begin, int y_end) {
        const int px_begin = std::max(means_window.x0 * d, frame.x0), px_end = std::min(means_window.x1 * d, frame.x1);
        std::vector<float> column_sums(size_t(px_end - px_begin));
        for (int by = y_begin; by < y_end; ++by) {
            const int py0 = std::max(by * d, frame.y0), py1 = std::min(by * d + d, frame.y1);
            const float* first = src.row(py0) + (px_begin - src.window.x0);
            std::copy_n(first, column_sums.size(), column_sums.begin());
            for (int y = py0 + 1; y < py1; ++y) {
                const float* in = src.row(y) + (px_begin - src.window.x0);
                for (size_t i = 0; i < column_sums.size(); ++i) column_sums[i] += in[i];
            }
            for (int bx = means_window.x0; bx < means_window.x1; ++bx) {
                const int px0 = std::max(bx * d, frame.x0), px1 = std::min(bx * d + d, frame.x1);
                float sum = 0;
                for (int x = px0; x < px1; ++x) sum += column_sums[size_t(x - px_begin)];
                means.at(bx, by) = sum / float((py1 - py0) * (px1 - px0));
            }
        }
    });
    convolve_separable(means, blurred, k.taps, coarse_frame, threads);
    // Bilinear interpolation at each fine pixel's centre, clamped to the coarse frame: first
    // along x, once per coarse row (the columns' blocks and weights are the same on every
    // row), then along y between the two rows a fine row falls between.
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
            const float* top = across.row(clamp_coarse(j, coarse_frame.y0, coarse_frame.y1));
            const float* bottom = across.row(clamp_coarse(j + 1, coarse_frame.y0, coarse_frame.y1));
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
