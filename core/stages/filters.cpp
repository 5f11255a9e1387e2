#include "core/stages/filters.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"

namespace darkroom {

std::vector<float> pixel_integrated_gaussian(double sigma_px) {
    int radius = sigma_px < 1e-3 ? 0 : (int)std::ceil(4.0 * sigma_px);
    auto cdf = [&](double x) { return 0.5 * std::erfc(-x / (sigma_px * std::sqrt(2.0))); };
    std::vector<double> w;
    double sum = 0;
    for (int i = -radius; i <= radius; ++i) {
        w.push_back(radius == 0 ? 1.0 : cdf(i + 0.5) - cdf(i - 0.5));
        sum += w.back();
    }
    std::vector<float> taps;
    for (double v : w) taps.push_back(float(v / sum));
    return taps;
}

// AVX2 where the processor has it (the same multiplies and adds in the same order as the
// baseline build, without FMA, so every machine computes the same pixels).
__attribute__((target_clones("avx2", "default"))) void convolve_row(const float* __restrict in,
                                                                     const std::vector<float>& taps, int width,
                                                                     float* __restrict out) {
    std::fill_n(out, width, 0.0f);
    for (size_t k = 0; k < taps.size(); ++k) {
        const float tap = taps[k];
        const float* __restrict shifted = in + k;
        for (int x = 0; x < width; ++x) out[x] += tap * shifted[x];
    }
}

__attribute__((target_clones("avx2", "default"))) void convolve_column(const float* const* rows,
                                                                        const std::vector<float>& taps, int width,
                                                                        float* __restrict out) {
    std::fill_n(out, width, 0.0f);
    for (size_t k = 0; k < taps.size(); ++k) {
        const float tap = taps[k];
        const float* __restrict row = rows[k];
        for (int x = 0; x < width; ++x) out[x] += tap * row[x];
    }
}

void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame,
                        int threads) {
    const int r = int(taps.size() / 2);
    const Window& w = dst.window;
    // Horizontal pass over the rows the vertical pass reads (clamped to the frame).
    Window hw = Window{w.x0, w.y0 - r, w.x1, w.y1 + r}.intersected(Window{w.x0, frame.y0, w.x1, frame.y1});
    Plane horizontal(hw);
    parallel_for(hw.y0, hw.y1, threads, [&](int y_begin, int y_end) {
        std::vector<float> padded(w.width() + 2 * r);
        for (int y = y_begin; y < y_end; ++y) {
            const float* in = src.row(y);
            for (int i = 0; i < (int)padded.size(); ++i)
                padded[i] = in[std::clamp(w.x0 - r + i, frame.x0, frame.x1 - 1) - src.window.x0];
            convolve_row(padded.data(), taps, w.width(), horizontal.row(y));
        }
    });
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        std::vector<const float*> rows(taps.size());
        for (int y = y_begin; y < y_end; ++y) {
            for (int k = -r; k <= r; ++k) rows[k + r] = horizontal.row(std::clamp(y + k, frame.y0, frame.y1 - 1));
            convolve_column(rows.data(), taps, w.width(), dst.row(y));
        }
    });
}

}  // namespace darkroom
