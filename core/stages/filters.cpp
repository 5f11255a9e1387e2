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

void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame,
                        int threads) {
    const int r = int(taps.size() / 2);
    const Window& w = dst.window;
    // Horizontal pass over the rows the vertical pass reads (clamped to the frame).
    Window hw = Window{w.x0, w.y0 - r, w.x1, w.y1 + r}.intersected(Window{w.x0, frame.y0, w.x1, frame.y1});
    Plane horizontal(hw);
    parallel_for(hw.y0, hw.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const float* in = src.row(y);
            float* out = horizontal.row(y);
            for (int x = w.x0; x < w.x1; ++x) {
                double acc = 0;
                for (int k = -r; k <= r; ++k)
                    acc += double(taps[k + r]) * in[std::clamp(x + k, frame.x0, frame.x1 - 1) - src.window.x0];
                out[x - w.x0] = float(acc);
            }
        }
    });
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            float* out = dst.row(y);
            for (int x = 0; x < w.width(); ++x) {
                double acc = 0;
                for (int k = -r; k <= r; ++k)
                    acc += double(taps[k + r]) * horizontal.row(std::clamp(y + k, frame.y0, frame.y1 - 1))[x];
                out[x] = float(acc);
            }
        }
    });
}

}  // namespace darkroom
