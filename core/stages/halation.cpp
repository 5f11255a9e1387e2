#include "core/stages/halation.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "core/simd.h"
#include "core/stages/filters.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

namespace {

template <typename V>
__attribute__((always_inline)) inline void lanes_of_halo(const float* in, const float* top, const float* bottom,
                                                          float ty, float strength, int c, float* out) {
    V i, t, b;
    simd::load(i, in + c);
    simd::load(t, top + c);
    simd::load(b, bottom + c);
    simd::store(out + c, i + strength * (t + ty * (b - t)));
}

// out[c] = in[c] + strength * (top[c] + ty (bottom[c] - top[c])): the halo between two
// coarse rows added to the exposure.
struct AddHaloRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* in, const float* top, const float* bottom, float ty,
                                                   float strength, int n, float* out) {
        int c = 0;
        for (; c + lanes <= n; c += lanes) {
            simd::prefetch_ahead(in + c, lanes * int(sizeof(float)));  // (a ring row read back, from memory)
            lanes_of_halo<typename simd::Lanes<lanes>::F>(in, top, bottom, ty, strength, c, out);
        }
        for (; c < n; ++c) lanes_of_halo<simd::Float1>(in, top, bottom, ty, strength, c, out);
    }
};

}  // namespace

std::vector<const std::vector<float>*> CoarseHalationStream::coarse_taps(
    const std::vector<const HalationKernel*>& kernels) {
    std::vector<const std::vector<float>*> taps;
    for (const HalationKernel* k : kernels) taps.push_back(k ? &k->taps : nullptr);
    return taps;
}

int CoarseHalationStream::decimation(const std::vector<const HalationKernel*>& kernels) {
    int d = 0;
    for (const HalationKernel* k : kernels) {
        if (!k) continue;
        if (d && k->decimation != d) throw std::invalid_argument("coarse halation: the planes' decimations differ");
        d = k->decimation;
    }
    return d;
}

CoarseHalationStream::CoarseHalationStream(const std::vector<const HalationKernel*>& kernels, const Window& out,
                                           const Window& frame, CoarseGaussianStream::Source source)
    : width_(out.width()), stream_(coarse_taps(kernels), decimation(kernels), out, frame, std::move(source)) {
    for (const HalationKernel* k : kernels) strengths_.push_back(k ? float(k->strength) : 0.0f);
}

void CoarseHalationStream::row(int y, float* const* result) {
    const CoarseGaussianStream::Row& r = stream_.row(y);
    for (size_t p = 0; p < strengths_.size(); ++p) {
        if (!r.above[p]) {
            std::copy_n(r.read[p], width_, result[p]);
            continue;
        }
        simd::dispatch<AddHaloRow>(r.read[p], r.above[p], r.below[p], r.t, strengths_[p], width_, result[p]);
    }
}

HalationKernel design_halation(double strength, double radius_um, double pixel_pitch_um, int decimation) {
    HalationKernel k;
    k.strength = strength;
    const double sigma_px = radius_um / pixel_pitch_um;
    // Coarsen only where the Gaussian spans several blocks.
    const CoarseGaussian g = design_coarse_gaussian(sigma_px, std::max(1, std::min(decimation, int(sigma_px / 2))));
    k.decimation = g.decimation;
    k.taps = g.taps;
    k.radius = g.radius_px;
    return k;
}

void apply_halation(const Plane& src, Plane& dst, const HalationKernel& kernel, const Window& frame, int threads) {
    const Window& w = dst.window;
    if (kernel.decimation > 1) {
        parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
            CoarseHalationStream halo({&kernel}, Window{w.x0, y_begin, w.x1, y_end}, frame,
                                      [&](int y, int x_begin, int x_end, float* const* rows) {
                                          const float* in = src.row(y) - src.window.x0;
                                          std::copy(in + x_begin, in + x_end, rows[0]);
                                      });
            for (int y = y_begin; y < y_end; ++y) {
                float* row = dst.row(y);
                halo.row(y, &row);
            }
        });
        return;
    }
    convolve_separable(src, dst, kernel.taps, frame, threads);
    const float strength = float(kernel.strength);
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const float* in = src.row(y) + (w.x0 - src.window.x0);
            float* out = dst.row(y);
            for (int x = 0; x < w.width(); ++x) out[x] = in[x] + strength * out[x];
        }
    });
}

}  // namespace darkroom
