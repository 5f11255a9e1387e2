#include "core/stages/filters.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "core/parallel.h"
#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

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

// The loops below produce each output value as a sum over the taps in one fixed order, in
// blocks of eight vectors held in registers while the taps go by (the output is written
// once, and eight independent sums keep the vector units busy), then single vectors, then
// one value at a time: the same multiplies and adds in the same order for every value,
// whatever the lane count (core/simd.h).
namespace {

using simd::load;
using simd::store;
constexpr int kVecs = 8;

// out[x] (+)= sum_k taps[k] row_of(k)[x] for x in [0, width): added to out when
// `accumulate`, else summed from 0 in registers (the same additions, without a pass that
// clears out first). Symmetric taps (taps[k] == taps[n-1-k], as every filter here has) are
// folded: the two inputs a tap shares are added before the one multiply, which saves a
// quarter of the arithmetic.
template <int lanes, int vecs, bool accumulate, typename RowOf>
__attribute__((always_inline)) inline int tap_blocks(const float* tap, int n, int pairs, int x, int width,
                                                     float* __restrict out, RowOf row_of) {
    using Vec = typename simd::Lanes<lanes>::F;
    constexpr int block = lanes * vecs;
    for (; x + block <= width; x += block) {
        Vec sum[vecs];
        for (int v = 0; v < vecs; ++v)
            if (accumulate)
                load(sum[v], out + x + v * lanes);
            else
                sum[v] = Vec{};
        for (int k = 0; k < pairs; ++k) {
            const Vec t = Vec{} + tap[k];
            const float *row = row_of(k) + x, *mirror = row_of(n - 1 - k) + x;
            for (int v = 0; v < vecs; ++v) {
                Vec in, in_mirror;
                load(in, row + v * lanes);
                load(in_mirror, mirror + v * lanes);
                sum[v] += t * (in + in_mirror);
            }
        }
        for (int k = pairs; k < n - pairs; ++k) {
            const Vec t = Vec{} + tap[k];
            const float* row = row_of(k) + x;
            for (int v = 0; v < vecs; ++v) {
                Vec in;
                load(in, row + v * lanes);
                sum[v] += t * in;
            }
        }
        for (int v = 0; v < vecs; ++v) store(out + x + v * lanes, sum[v]);
    }
    return x;
}

template <int lanes, bool accumulate, typename RowOf>
__attribute__((always_inline)) inline void tap_sums(const float* tap, int n, int width, float* __restrict out,
                                                    RowOf row_of) {
    const bool symmetric = std::equal(tap, tap + n / 2, std::reverse_iterator<const float*>(tap + n));
    const int pairs = symmetric ? n / 2 : 0;  // taps k and n-1-k for k < pairs; then k in [pairs, n - pairs)
    int x = tap_blocks<lanes, kVecs, accumulate>(tap, n, pairs, 0, width, out, row_of);
    x = tap_blocks<lanes, 1, accumulate>(tap, n, pairs, x, width, out, row_of);
    tap_blocks<1, 1, accumulate>(tap, n, pairs, x, width, out, row_of);
}

struct ConvolveRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* in, const float* taps, int n, int width, float* out) {
        tap_sums<lanes, false>(taps, n, width, out, [in](int k) { return in + k; });
    }
};

template <bool accumulate>
struct ConvolveColumn {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* const* rows, const float* taps, int n, int width,
                                                   float* out) {
        tap_sums<lanes, accumulate>(taps, n, width, out, [rows](int k) { return rows[k]; });
    }
};

}  // namespace

void convolve_row(const float* in, const std::vector<float>& taps, int width, float* out) {
    simd::dispatch<ConvolveRow>(in, taps.data(), int(taps.size()), width, out);
}

void convolve_column(const float* const* rows, const std::vector<float>& taps, int width, float* out) {
    simd::dispatch<ConvolveColumn<false>>(rows, taps.data(), int(taps.size()), width, out);
}

void convolve_column_add(const float* const* rows, const std::vector<float>& taps, int width, float* out) {
    simd::dispatch<ConvolveColumn<true>>(rows, taps.data(), int(taps.size()), width, out);
}

void filter_separable(const Window& out, const SeparableFilter& filter, int row_begin, int row_end, int threads,
                      const RowSource& source, const RowTarget& target, const RowSink& sink) {
    const int terms = int(filter.terms.size()), r = int(filter.terms[0].size() / 2), width = out.width();
    std::vector<std::vector<float>> vertical(terms);  // the sign folded into the vertical taps
    for (int t = 0; t < terms; ++t)
        for (float v : filter.terms[t]) vertical[t].push_back(filter.signs[t] * v);
    parallel_for(out.y0, out.y1, threads, [&](int y_begin, int y_end) {
        // The horizontal results of the 2r + 1 rows the vertical pass reads, in a ring: each
        // row is filtered once per thread (a 4K row of 17 taps: about 300 KB per term, within
        // L2). Rows are a cache line more than the width apart: at widths of a power of two,
        // rows exactly 2^k bytes apart share the L1 cache's sets and would evict each other.
        const int slots = 2 * r + 1;
        const size_t stride = size_t(width) + 16;
        std::vector<float> padded(width + 2 * r), filtered(width), ring(size_t(terms) * slots * stride);
        auto ring_row = [&](int t, int y) { return &ring[(size_t(t) * slots + ((y % slots) + slots) % slots) * stride]; };
        std::vector<const float*> rows(slots);
        int next = std::max(y_begin - r, row_begin);  // the next row to filter horizontally
        for (int y = y_begin; y < y_end; ++y) {
            for (; next <= std::min(y + r, row_end - 1); ++next) {
                source(next, padded.data());
                for (int t = 0; t < terms; ++t) convolve_row(padded.data(), filter.terms[t], width, ring_row(t, next));
            }
            float* result = target ? target(y) : filtered.data();
            for (int t = 0; t < terms; ++t) {
                for (int k = -r; k <= r; ++k) rows[k + r] = ring_row(t, std::clamp(y + k, row_begin, row_end - 1));
                (t == 0 ? convolve_column : convolve_column_add)(rows.data(), vertical[t], width, result);
            }
            if (sink) sink(y, result);
        }
    });
}

void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame,
                        int threads) {
    convolve_separable(src, dst, SeparableFilter{{taps}, {1.0f}}, frame, threads);
}

void convolve_separable(const Plane& src, Plane& dst, const SeparableFilter& filter, const Window& frame,
                        int threads) {
    const int r = int(filter.terms[0].size() / 2);
    const Window& w = dst.window;
    filter_separable(
        w, filter, frame.y0, frame.y1, threads,
        [&](int y, float* padded) {
            // The row from x = w.x0 - r, its ends held at the frame's edge pixels.
            auto in = [&](int x) { return src.row(y) + (x - src.window.x0); };
            const int first = w.x0 - r, last = w.x1 + r;  // padded covers [first, last)
            const int inside0 = std::max(first, frame.x0), inside1 = std::min(last, frame.x1);
            // (The edge pixels are read only where the row reaches past them: a window's source
            // plane need not hold them.)
            if (first < inside0) std::fill(padded, padded + (inside0 - first), *in(frame.x0));
            std::copy(in(inside0), in(inside1), padded + (inside0 - first));
            if (inside1 < last) std::fill(padded + (inside1 - first), padded + (last - first), *in(frame.x1 - 1));
        },
        [&](int y) { return dst.row(y); }, nullptr);
}

}  // namespace darkroom
