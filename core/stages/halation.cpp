#include "core/stages/halation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
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

int floor_div(int a, int d) { return a >= 0 ? a / d : -((-a + d - 1) / d); }

// The row loops, in vectors of any width then one value at a time (core/simd.h): the same
// float operations on every value.
template <typename V>
__attribute__((always_inline)) inline void lanes_of_sum(float* sums, const float* in, int i) {
    V s, v;
    simd::load(s, sums + i);
    simd::load(v, in + i);
    simd::store(sums + i, s + v);
}

// sums[i] += in[i].
struct AddRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(float* sums, const float* in, int n) {
        int i = 0;
        for (; i + lanes <= n; i += lanes) lanes_of_sum<typename simd::Lanes<lanes>::F>(sums, in, i);
        for (; i < n; ++i) lanes_of_sum<simd::Float1>(sums, in, i);
    }
};

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
        for (; c + lanes <= n; c += lanes)
            lanes_of_halo<typename simd::Lanes<lanes>::F>(in, top, bottom, ty, strength, c, out);
        for (; c < n; ++c) lanes_of_halo<simd::Float1>(in, top, bottom, ty, strength, c, out);
    }
};

// Fine pixel x sits at u = (x + 0.5)/d - 0.5 = (2x + 1 - d)/2d on the coarse grid, between
// blocks floor(u) and floor(u) + 1 (exact in integers); the blocks a range of pixels needs.
std::pair<int, int> coarse_range(int lo, int hi, int d) {
    return {floor_div(2 * lo + 1 - d, 2 * d), floor_div(2 * (hi - 1) + 1 - d, 2 * d) + 2};
}

}  // namespace

CoarseHalation::CoarseHalation(const std::vector<const HalationKernel*>& kernels, const Window& out,
                               const Window& frame, int threads, const Reader& read)
    : out_(out) {
    const int d = kernels[0]->decimation;
    struct Part {
        Window means_window, blurred_window;
        int inside0, inside1;  // the columns of the frame its block means read
    };
    std::vector<Part> parts;
    Window reads{frame.x1, frame.y1, frame.x0, frame.y0};  // the union of what the parts read
    for (const HalationKernel* k : kernels) {
        if (k->decimation != d) throw std::invalid_argument("coarse halation: the planes' decimations differ");
        auto [cx0, cx1] = coarse_range(out.x0, out.x1, d);
        auto [cy0, cy1] = coarse_range(out.y0, out.y1, d);
        Part part;
        part.blurred_window = {cx0, cy0, cx1, cy1};
        part.means_window = part.blurred_window.grown(int(k->taps.size() / 2));
        part.inside0 = std::clamp(part.means_window.x0 * d, frame.x0, frame.x1);
        part.inside1 = std::clamp(part.means_window.x1 * d, frame.x0, frame.x1);
        reads = {std::min(reads.x0, part.inside0), std::min(reads.y0, part.means_window.y0),
                 std::max(reads.x1, part.inside1), std::max(reads.y1, part.means_window.y1)};
        parts.push_back(part);
    }
    // Block means of the image extended past the frame by its edge pixels, as the Gaussian on
    // the pixels reads it (blocks past the frame too, so that the coarse Gaussian clamps
    // nothing of its own): each block's rows summed column by column (whole rows, in vector
    // registers), then its columns. Every plane's rows come from one read of each fine row.
    std::vector<Plane> means;
    for (const Part& part : parts) means.emplace_back(part.means_window);
    parallel_for(reads.y0, reads.y1, threads, [&](int by_begin, int by_end) {
        const size_t planes = parts.size();
        std::vector<std::vector<float>> column_sums(planes), row(planes);
        std::vector<float*> rows(planes);
        for (size_t p = 0; p < planes; ++p) {
            column_sums[p].resize(size_t(parts[p].means_window.width()) * d);
            row[p].resize(size_t(reads.x1 - reads.x0));
            rows[p] = row[p].data();
        }
        for (int by = by_begin; by < by_end; ++by) {
            for (int k = 0; k < d; ++k) {
                read(std::clamp(by * d + k, frame.y0, frame.y1 - 1), reads.x0, reads.x1, rows.data());
                for (size_t p = 0; p < planes; ++p) {
                    const Part& part = parts[p];
                    if (by < part.means_window.y0 || by >= part.means_window.y1) continue;
                    const float* in = rows[p] + (part.inside0 - reads.x0);
                    float* sums = column_sums[p].data() + (part.inside0 - part.means_window.x0 * d);
                    if (k == 0)
                        std::copy(in, in + (part.inside1 - part.inside0), sums);
                    else
                        simd::dispatch<AddRow>(sums, in, part.inside1 - part.inside0);
                }
            }
            for (size_t p = 0; p < planes; ++p) {
                const Part& part = parts[p];
                if (by < part.means_window.y0 || by >= part.means_window.y1) continue;
                // The columns past the frame's edges are its edge columns.
                std::vector<float>& sums = column_sums[p];
                const int px_begin = part.means_window.x0 * d;
                std::fill(sums.begin(), sums.begin() + (part.inside0 - px_begin), sums[part.inside0 - px_begin]);
                std::fill(sums.begin() + (part.inside1 - px_begin), sums.end(), sums[part.inside1 - 1 - px_begin]);
                for (int bx = part.means_window.x0; bx < part.means_window.x1; ++bx) {
                    float sum = 0;
                    for (int x = bx * d; x < bx * d + d; ++x) sum += sums[size_t(x - px_begin)];
                    means[p].at(bx, by) = sum / float(d * d);
                }
            }
        }
    });
    // Bilinear interpolation at each fine pixel's centre: first along x, once per coarse row
    // (the columns' blocks and weights are the same on every row), here; then along y
    // between the two rows a fine row falls between, in add().
    const int width = out.width();
    std::vector<int> column0(width), column1(width);
    std::vector<float> tx(width);
    for (size_t p = 0; p < parts.size(); ++p) {
        const Window& bw = parts[p].blurred_window;
        for (int x = out.x0; x < out.x1; ++x) {
            const int i = floor_div(2 * x + 1 - d, 2 * d), c = x - out.x0;
            tx[c] = float(2 * x + 1 - d - 2 * d * i) / float(2 * d);
            column0[c] = i - bw.x0;
            column1[c] = i + 1 - bw.x0;
        }
        Plane blurred(bw);
        convolve_separable(means[p], blurred, kernels[p]->taps, parts[p].means_window, threads);
        Plane across = Plane::unset(Window{out.x0, bw.y0, out.x1, bw.y1});
        parallel_for(bw.y0, bw.y1, threads, [&](int y_begin, int y_end) {
            for (int j = y_begin; j < y_end; ++j) {
                const float* row = blurred.row(j);
                float* o = across.row(j);
                for (int c = 0; c < width; ++c) o[c] = row[column0[c]] + tx[c] * (row[column1[c]] - row[column0[c]]);
            }
        });
        planes_.push_back({float(kernels[p]->strength), d, std::move(across)});
    }
}

void CoarseHalation::add(size_t plane, int y, const float* in, float* out) const {
    const Interpolated& p = planes_[plane];
    const int d = p.decimation;
    const int j = floor_div(2 * y + 1 - d, 2 * d);
    const float ty = float(2 * y + 1 - d - 2 * d * j) / float(2 * d);
    simd::dispatch<AddHaloRow>(in, p.across.row(j), p.across.row(j + 1), ty, p.strength, out_.width(), out);
}

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
    const Window& w = dst.window;
    auto src_row = [&](int y) { return src.row(y) + (w.x0 - src.window.x0); };
    if (kernel.decimation > 1) {
        const CoarseHalation halo({&kernel}, w, frame, threads, [&](int y, int x_begin, int x_end, float* const* rows) {
            std::copy(src.row(y) + (x_begin - src.window.x0), src.row(y) + (x_end - src.window.x0), rows[0]);
        });
        parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
            for (int y = y_begin; y < y_end; ++y) halo.add(0, y, src_row(y), dst.row(y));
        });
        return;
    }
    convolve_separable(src, dst, kernel.taps, frame, threads);
    const float strength = float(kernel.strength);
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const float* in = src_row(y);
            float* out = dst.row(y);
            for (int x = 0; x < w.width(); ++x) out[x] = in[x] + strength * out[x];
        }
    });
}

}  // namespace darkroom
