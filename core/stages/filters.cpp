#include "core/stages/filters.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/parallel.h"

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

// The loops below produce each output value as a sum over the taps in their order, in
// blocks of 64 values held in eight vector registers while the taps go by (the output is
// written once, and eight independent sums keep the vector units busy). Written with GCC's
// vector types, compiled for AVX2 where the processor has it: the same multiplies and adds
// in the same order as the baseline build, without FMA, so every machine computes the same
// pixels.
namespace {

using Vec = float __attribute__((vector_size(32)));
constexpr int kLanes = 8, kVecs = 8, kBlock = kLanes * kVecs;

// (No vector passes through a call: its ABI would differ with and without AVX.)
inline void load(Vec& v, const float* p) { std::memcpy(&v, p, sizeof v); }
inline void store(float* p, const Vec& v) { std::memcpy(p, &v, sizeof v); }

// out[x] += sum_k taps[k] row_of(k)[x] for x in [0, width).
template <typename RowOf>
__attribute__((always_inline)) inline void add_tap_sums(const std::vector<float>& taps, int width, float* __restrict out, RowOf row_of) {
    const int n = int(taps.size());
    const float* tap = taps.data();
    int x = 0;
    for (; x + kBlock <= width; x += kBlock) {
        Vec sum[kVecs];
        for (int v = 0; v < kVecs; ++v) load(sum[v], out + x + v * kLanes);
        for (int k = 0; k < n; ++k) {
            const Vec t = Vec{} + tap[k];
            const float* row = row_of(k) + x;
            for (int v = 0; v < kVecs; ++v) {
                Vec in;
                load(in, row + v * kLanes);
                sum[v] += t * in;
            }
        }
        for (int v = 0; v < kVecs; ++v) store(out + x + v * kLanes, sum[v]);
    }
    for (; x < width; ++x) {
        float sum = out[x];
        for (int k = 0; k < n; ++k) sum += tap[k] * row_of(k)[x];
        out[x] = sum;
    }
}

}  // namespace

__attribute__((target_clones("avx2", "default"))) void convolve_row(const float* in, const std::vector<float>& taps,
                                                                     int width, float* out) {
    std::fill_n(out, width, 0.0f);
    add_tap_sums(taps, width, out, [in](int k) { return in + k; });
}

__attribute__((target_clones("avx2", "default"))) void convolve_column_add(const float* const* rows,
                                                                            const std::vector<float>& taps, int width,
                                                                            float* out) {
    add_tap_sums(taps, width, out, [rows](int k) { return rows[k]; });
}

void filter_separable(const Window& out, const SeparableFilter& filter, int row_begin, int row_end, int threads,
                      const RowSource& source, const RowSink& sink) {
    // 64 rows of a 4K frame, with their halo, per term: about 1 MB, within L2.
    constexpr int kBandRows = 64;
    const int terms = int(filter.terms.size()), r = int(filter.terms[0].size() / 2), width = out.width();
    std::vector<std::vector<float>> vertical(terms);  // the sign folded into the vertical taps
    for (int t = 0; t < terms; ++t)
        for (float v : filter.terms[t]) vertical[t].push_back(filter.signs[t] * v);
    parallel_for(out.y0, out.y1, threads, [&](int y_begin, int y_end) {
        const int band_rows = kBandRows + 2 * r;
        std::vector<float> padded(width + 2 * r), filtered(width), horizontal(size_t(terms) * band_rows * width);
        std::vector<const float*> rows(2 * r + 1);
        for (int b0 = y_begin; b0 < y_end; b0 += kBandRows) {
            const int b1 = std::min(b0 + kBandRows, y_end);
            // Horizontal pass over the rows this band's vertical pass reads.
            const int h0 = std::max(b0 - r, row_begin), h1 = std::min(b1 + r, row_end);
            auto horizontal_row = [&](int t, int y) { return &horizontal[(size_t(t) * band_rows + (y - h0)) * width]; };
            for (int y = h0; y < h1; ++y) {
                source(y, padded.data());
                for (int t = 0; t < terms; ++t) convolve_row(padded.data(), filter.terms[t], width, horizontal_row(t, y));
            }
            for (int y = b0; y < b1; ++y) {
                std::fill(filtered.begin(), filtered.end(), 0.0f);
                for (int t = 0; t < terms; ++t) {
                    for (int k = -r; k <= r; ++k) rows[k + r] = horizontal_row(t, std::clamp(y + k, row_begin, row_end - 1));
                    convolve_column_add(rows.data(), vertical[t], width, filtered.data());
                }
                sink(y, filtered.data());
            }
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
        [&](int y, const float* filtered) { std::copy_n(filtered, w.width(), dst.row(y)); });
}

}  // namespace darkroom
