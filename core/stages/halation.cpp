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
        for (; c + lanes <= n; c += lanes) {
            simd::prefetch_ahead(in + c, lanes * int(sizeof(float)));  // (a ring row read back, from memory)
            lanes_of_halo<typename simd::Lanes<lanes>::F>(in, top, bottom, ty, strength, c, out);
        }
        for (; c < n; ++c) lanes_of_halo<simd::Float1>(in, top, bottom, ty, strength, c, out);
    }
};

// Fine pixel x sits at u = (x + 0.5)/d - 0.5 = (2x + 1 - d)/2d on the coarse grid, between
// blocks floor(u) and floor(u) + 1 (exact in integers); the blocks a range of pixels needs.
std::pair<int, int> coarse_range(int lo, int hi, int d) {
    return {floor_div(2 * lo + 1 - d, 2 * d), floor_div(2 * (hi - 1) + 1 - d, 2 * d) + 2};
}

}  // namespace

CoarseHalationStream::CoarseHalationStream(const std::vector<const HalationKernel*>& kernels, const Window& out,
                                           const Window& frame, Source source)
    : out_(out), frame_(frame), source_(std::move(source)), planes_(kernels.size()) {
    int r = 0;  // the largest coarse Gaussian's radius
    for (size_t p = 0; p < kernels.size(); ++p) {
        if (!kernels[p]) continue;
        if (d_ && kernels[p]->decimation != d_) throw std::invalid_argument("coarse halation: the planes' decimations differ");
        d_ = kernels[p]->decimation;
        r = std::max(r, int(kernels[p]->taps.size() / 2));
        planes_[p].strength = float(kernels[p]->strength);
        halated_.push_back(p);
    }
    if (halated_.empty()) throw std::invalid_argument("coarse halation: no plane has halation");
    auto [cx0, cx1] = coarse_range(out.x0, out.x1, d_);
    auto [cy0, cy1] = coarse_range(out.y0, out.y1, d_);
    blurred_window_ = {cx0, cy0, cx1, cy1};
    means_window_ = blurred_window_.grown(r);
    inside0_ = std::clamp(means_window_.x0 * d_, frame.x0, frame.x1);
    inside1_ = std::clamp(means_window_.x1 * d_, frame.x0, frame.x1);
    read_x0_ = std::min(std::max(out.x0, frame.x0), inside0_), read_x1_ = std::max(std::min(out.x1, frame.x1), inside1_);
    // The columns' blocks and weights of the interpolation along x (the same on every row).
    for (int x = out.x0; x < out.x1; ++x) {
        const int i = floor_div(2 * x + 1 - d_, 2 * d_), column = x - out.x0, block = i - blurred_window_.x0;
        tx_.push_back(float(2 * x + 1 - d_ - 2 * d_ * i) / float(2 * d_));
        if (column_runs_.empty() || column_runs_.back().block != block) column_runs_.push_back({column, column, block});
        column_runs_.back().end = column + 1;
    }
    std::vector<SeparableFilter> filters;
    for (size_t p : halated_) {
        PlaneHalo& plane = planes_[p];
        filters.push_back(SeparableFilter{{kernels[p]->taps}, {1.0f}});
        plane.column_sums.resize(size_t(means_window_.width()) * d_);
        for (auto& row : plane.across) row.resize(size_t(out.width()));
    }
    // Every plane's coarse rows from one stream, so that each fine row is read once for all;
    // two coarse rows summed at once (more would read further ahead, for a ring of fine rows
    // the deeper, and the coarse rows cost little).
    constexpr int kCoarseRowsTogether = 2;
    blur_ = std::make_unique<SeparableStream>(blurred_window_.width(), std::move(filters), means_window_.y0, means_window_.y1,
                                              blurred_window_.y1,
                                              [this](int by, float* const* means) { block_means(by, means); },
                                              kCoarseRowsTogether);
    // Output row y lies above coarse row j + 1 <= y / d + 1, whose blur (with the next one)
    // reads block rows to j + kCoarseRowsTogether + r, each d fine rows.
    slots_ = d_ * (r + 3 + kCoarseRowsTogether) + 2;
    ring_.resize(planes_.size());
    for (auto& ring : ring_) ring.resize(size_t(slots_) * size_t(read_x1_ - read_x0_));
    ring_rows_.resize(planes_.size());
}

float* CoarseHalationStream::ring_row(size_t plane, int y) {
    if (y < next_ - slots_ || y >= next_) throw std::logic_error("coarse halation: a row outside the stream's ring");
    return &ring_[plane][size_t(((y % slots_) + slots_) % slots_) * size_t(read_x1_ - read_x0_)];
}

// Reads fine rows up to y (within the frame) into the ring.
void CoarseHalationStream::read_to(int y) {
    if (!started_) {
        next_ = std::clamp(y, frame_.y0, frame_.y1 - 1);
        started_ = true;
    }
    for (; next_ <= y; ++next_) {
        for (size_t p = 0; p < planes_.size(); ++p)
            ring_rows_[p] = &ring_[p][size_t(((next_ % slots_) + slots_) % slots_) * size_t(read_x1_ - read_x0_)];
        source_(next_, read_x0_, read_x1_, ring_rows_.data());
    }
}

// Block means of the image extended past the frame by its edge pixels, as the Gaussian on
// the pixels reads it (blocks past the frame too, so that the coarse Gaussian clamps nothing
// of its own): the block row's d rows summed column by column (whole rows, in vector
// registers), then each block's d columns; for every halated plane, means[i] its row.
void CoarseHalationStream::block_means(int by, float* const* means) {
    const int d = d_, px_begin = means_window_.x0 * d, n = inside1_ - inside0_;
    for (int k = 0; k < d; ++k) {
        const int y = std::clamp(by * d + k, frame_.y0, frame_.y1 - 1);
        read_to(y);
        for (size_t p : halated_) {
            const float* in = ring_row(p, y) + (inside0_ - read_x0_);
            float* sums = planes_[p].column_sums.data() + (inside0_ - px_begin);
            if (k == 0)
                std::copy(in, in + n, sums);
            else
                simd::dispatch<AddRow>(sums, in, n);
        }
    }
    for (size_t i = 0; i < halated_.size(); ++i) {
        // The columns past the frame's edges are its edge columns.
        std::vector<float>& sums = planes_[halated_[i]].column_sums;
        std::fill(sums.begin(), sums.begin() + (inside0_ - px_begin), sums[inside0_ - px_begin]);
        std::fill(sums.begin() + (inside1_ - px_begin), sums.end(), sums[inside1_ - 1 - px_begin]);
        for (int bx = means_window_.x0; bx < means_window_.x1; ++bx) {
            float sum = 0;
            for (int x = bx * d; x < bx * d + d; ++x) sum += sums[size_t(x - px_begin)];
            means[i][bx - means_window_.x0] = sum / float(d * d);
        }
    }
}

// Coarse row j of every plane's blurred means, interpolated along x to out's columns (the
// last two rows are kept).
void CoarseHalationStream::interpolate(int j) {
    if (across_row_[j & 1] == j) return;
    const float* const* blurred_rows = blur_->row(j);
    for (size_t h = 0; h < halated_.size(); ++h) {
        float* row = planes_[halated_[h]].across[j & 1].data();
        // A run's two coarse values once, then a loop without indirection (which vectorises).
        for (const ColumnRun& run : column_runs_) {
            const float b0 = blurred_rows[h][run.block], step = blurred_rows[h][run.block + 1] - b0;
            for (int i = run.begin; i < run.end; ++i) row[i] = b0 + tx_[size_t(i)] * step;
        }
    }
    across_row_[j & 1] = j;
}

void CoarseHalationStream::row(int y, float* const* result) {
    // The coarse rows first: they read the fine rows below this one.
    const int j = floor_div(2 * y + 1 - d_, 2 * d_);
    interpolate(j);
    interpolate(j + 1);
    read_to(y);
    const float ty = float(2 * y + 1 - d_ - 2 * d_ * j) / float(2 * d_);  // the fine row's place between them
    for (size_t p = 0; p < planes_.size(); ++p) {
        const float* in = ring_row(p, y) + (out_.x0 - read_x0_);
        const PlaneHalo& plane = planes_[p];
        if (plane.column_sums.empty()) {
            std::copy_n(in, out_.width(), result[p]);
            continue;
        }
        simd::dispatch<AddHaloRow>(in, plane.across[j & 1].data(), plane.across[(j + 1) & 1].data(), ty,
                                   plane.strength, out_.width(), result[p]);
    }
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
