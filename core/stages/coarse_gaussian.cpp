#include "core/stages/coarse_gaussian.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

namespace {

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

// log2 v for v > 0 by the bits of its float, 2^-23 (bits(v) - bits(1)): e + m for
// v = 2^e (1 + m), 0 <= m < 1, which is log2 v less log2(1 + m) - m, within [0, 0.0861]
// (Mitchell's approximation: a conversion, no logarithm), on the lanes of a vector (v >= floor
// after the selection). Its inverse by the same bits: so a mean of pseudo logarithms taken
// back is the geometric mean within a factor 2^+-0.0861 (their errors' spread), and the value
// itself where all are the same (up to the float's rounding of the bits, 2^-17 relative).
constexpr int32_t kBitsOfOne = 0x3F800000;
template <typename V>
__attribute__((always_inline)) inline V pseudo_log2_lanes(V v, float floor) {
    using I = typename simd::Lanes<int(sizeof(V) / sizeof(float))>::I;
    v = v >= floor ? v : V{} + floor;  // (NaN too: its comparison is false)
    I bits;
    std::memcpy(&bits, &v, sizeof bits);
    return __builtin_convertvector(bits - kBitsOfOne, V) * 0x1p-23f;
}
template <typename V>
__attribute__((always_inline)) inline V exp2_of_pseudo_log2_lanes(V l) {
    using I = typename simd::Lanes<int(sizeof(V) / sizeof(float))>::I;
    const I bits = __builtin_convertvector(l * 0x1p23f, I) + kBitsOfOne;
    V v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
}

// sums[i] = (first) or += pseudo_log2(max(in[i], floor)).
template <typename V>
__attribute__((always_inline)) inline void lanes_of_log_sum(float* sums, const float* in, float floor, bool first,
                                                            int i) {
    V v;
    simd::load(v, in + i);
    V l = pseudo_log2_lanes(v, floor);
    if (!first) {
        V s;
        simd::load(s, sums + i);
        l = s + l;
    }
    simd::store(sums + i, l);
}
struct AddPseudoLog2Row {
    template <int lanes>
    __attribute__((always_inline)) static void run(float* sums, const float* in, float floor, bool first, int n) {
        int i = 0;
        for (; i + lanes <= n; i += lanes)
            lanes_of_log_sum<typename simd::Lanes<lanes>::F>(sums, in, floor, first, i);
        for (; i < n; ++i) lanes_of_log_sum<simd::Float1>(sums, in, floor, first, i);
    }
};

// row[i] = exp2_of_pseudo_log2(row[i]).
struct Exp2OfPseudoLog2Row {
    template <int lanes>
    __attribute__((always_inline)) static void run(float* row, int n) {
        int i = 0;
        for (; i + lanes <= n; i += lanes) {
            typename simd::Lanes<lanes>::F l;
            simd::load(l, row + i);
            simd::store(row + i, exp2_of_pseudo_log2_lanes(l));
        }
        for (; i < n; ++i) row[i] = exp2_of_pseudo_log2_lanes(simd::Float1{row[i]})[0];
    }
};

// Grids of d up to kMaxRunDecimation (the DIR couplers' and halation's): the values of a
// vector of blocks spread to the d vectors of their fine columns by permutes, and the d
// vectors of a row's column sums gathered to its blocks likewise; the same operations as the
// scalar loops, for every d.
constexpr int kMaxRunDecimation = 8;

// Fine vector v's lanes j, of the fine columns of `lanes` blocks from the first: each its
// block's value, block (v lanes + j) / d.
template <int d, int v, typename V, size_t... J>
__attribute__((always_inline)) inline V spread_to_columns(const V& blocks, std::index_sequence<J...>) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    return __builtin_shufflevector(blocks, blocks, ((v * lanes + int(J)) / d)...);
}

// What the interpolation along x does with each fine column's value: writes it, or
// (multiply) writes the column of `in` times it.
template <bool multiply, typename V>
__attribute__((always_inline)) inline void put(const float* in, float* out, const V& v) {
    if constexpr (!multiply) {
        simd::store(out, v);
    } else {
        V o;
        simd::load(o, in);
        simd::store(out, o * v);
    }
}

// The d fine vectors of `lanes` blocks: each lane b0 + t step of its block, t its column's weight.
template <bool multiply, int d, typename V, size_t... Vs>
__attribute__((always_inline)) inline void put_columns(const V& b0, const V& step, const V* weights, const float* in,
                                                       float* out, std::index_sequence<Vs...>) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    constexpr auto lane_indices = std::make_index_sequence<lanes>();
    (put<multiply>(in + int(Vs) * lanes, out + int(Vs) * lanes,
                   V(spread_to_columns<d, int(Vs)>(b0, lane_indices) +
                     weights[Vs] * spread_to_columns<d, int(Vs)>(step, lane_indices))),
     ...);
}

// The coarse row's value at column k: coarse[k], or (between rows) above[k] + t (below[k] - above[k]),
// the row interpolated along y on the way (fused with its use, so no row of it is stored).
struct CoarseRow {
    const float* above;
    const float* below;  // null: above is the row itself
    float t;
    template <typename V>
    __attribute__((always_inline)) V at(int k) const {
        V lo;
        simd::load(lo, above + k);
        if (!below) return lo;
        V hi;
        simd::load(hi, below + k);
        return lo + t * (hi - lo);
    }
    CoarseRow from(int block) const { return {above + block, below ? below + block : nullptr, t}; }
};

// out[d k + m] = c[k] + t[m] (c[k + 1] - c[k]) (multiply: times in[d k + m]), m < d, k < blocks, c
// the coarse row: d fine columns per block, interpolated along x.
template <bool multiply, int d>
struct InterpolateRuns {
    template <int lanes>
    __attribute__((always_inline)) static void run(CoarseRow coarse, const float* t, int blocks, const float* in,
                                                   float* out) {
        using V = typename simd::Lanes<lanes>::F;
        int k = 0;
        if constexpr (lanes > 1) {
            float pattern[d * lanes];  // fine column i's weight t[i % d]; vector v's from v lanes
            for (int i = 0; i < d * lanes; ++i) pattern[i] = t[i % d];
            V weights[d];
            for (int v = 0; v < d; ++v) simd::load(weights[v], pattern + v * lanes);
            for (; k + lanes <= blocks; k += lanes) {
                // (multiplying: a ring row read back, from memory)
                if constexpr (multiply) simd::prefetch_ahead(in + d * k, d * lanes * int(sizeof(float)));
                const V b0 = coarse.at<V>(k), step = coarse.at<V>(k + 1) - b0;
                put_columns<multiply, d>(b0, step, weights, in + d * k, out + d * k, std::make_index_sequence<d>());
            }
        }
        for (; k < blocks; ++k) {
            const simd::Float1 b0 = coarse.at<simd::Float1>(k), step = coarse.at<simd::Float1>(k + 1) - b0;
            for (int m = 0; m < d; ++m) put<multiply>(in + d * k + m, out + d * k + m, simd::Float1{b0 + t[m] * step});
        }
    }
};

// Lane j of `partial` from the vectors `in` from q on: sums[d j + m] where it lies in in[q].
template <int d, int m, int q, typename V, size_t... J>
__attribute__((always_inline)) inline V gather_column(const V& partial, const V* in, std::index_sequence<J...> lanes) {
    if constexpr (q == d) {
        return partial;
    } else {
        constexpr int n = sizeof(V) / sizeof(float);
        const V merged = __builtin_shufflevector(
            partial, in[q], ((d * int(J) + m) / n == q ? n + (d * int(J) + m) % n : int(J))...);
        return gather_column<d, m, q + 1>(merged, in, lanes);
    }
}

// The sum 0 + sums[d j] + ... + sums[d j + d - 1] of each block j of a vector's, from the d
// vectors of its column sums.
template <int d, typename V, size_t... Ms>
__attribute__((always_inline)) inline V block_sums(const V* in, std::index_sequence<Ms...>) {
    constexpr auto lanes = std::make_index_sequence<sizeof(V) / sizeof(float)>();
    V sum = V{} + 0.0f;
    ((sum = sum + gather_column<d, int(Ms), 0>(in[0], in, lanes)), ...);
    return sum;
}

// means[k] = (0 + sums[d k] + ... + sums[d k + d - 1]) / d^2, k < blocks: the means of d x d
// blocks from their column sums.
template <int d>
struct BlockMeans {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* sums, int blocks, float* means) {
        using V = typename simd::Lanes<lanes>::F;
        int k = 0;
        if constexpr (lanes > 1)
            for (; k + lanes <= blocks; k += lanes) {
                V in[d];
                for (int v = 0; v < d; ++v) simd::load(in[v], sums + d * k + v * lanes);
                simd::store(means + k, block_sums<d>(in, std::make_index_sequence<d>()) / float(d * d));
            }
        for (; k < blocks; ++k) {
            simd::Float1 sum = simd::Float1{} + 0.0f;
            for (int m = 0; m < d; ++m) sum = sum + simd::Float1{sums[d * k + m]};
            means[k] = (sum / float(d * d))[0];
        }
    }
};

// Kernel<d> dispatched for the decimation d in [2, kMaxRunDecimation].
template <template <int> class Kernel, int d = 2, typename... Args>
void dispatch_decimation(int decimation, Args... args) {
    if (decimation == d)
        simd::dispatch<Kernel<d>>(args...);
    else if constexpr (d < kMaxRunDecimation)
        dispatch_decimation<Kernel, d + 1>(decimation, args...);
    else
        throw std::logic_error("coarse Gaussian: a decimation past the vector kernels'");
}
template <int d>
using InterpolateRunsWritten = InterpolateRuns<false, d>;
template <int d>
using InterpolateRunsMultiplied = InterpolateRuns<true, d>;

// Fine pixel x sits at u = (x + 0.5)/d - 0.5 = (2x + 1 - d)/2d on the coarse grid, between
// blocks floor(u) and floor(u) + 1 (exact in integers); the blocks a range of pixels needs.
std::pair<int, int> coarse_range(int lo, int hi, int d) {
    return {floor_div(2 * lo + 1 - d, 2 * d), floor_div(2 * (hi - 1) + 1 - d, 2 * d) + 2};
}

}  // namespace

namespace {

// The coarse taps of standard deviation coarse_sigma, truncated as design_coarse_gaussian's.
std::vector<float> coarse_taps(double coarse_sigma, double coarse_reach_sigmas) {
    return coarse_reach_sigmas > 0
               ? pixel_integrated_gaussian(coarse_sigma, int(std::ceil(coarse_reach_sigmas * coarse_sigma - 0.5)))
               : pixel_integrated_gaussian(coarse_sigma);
}

// The largest difference between a unit step spread by the pixels' Gaussian (`exact_step`: its
// value at x - edge, from -radius to radius) and by `taps` on a grid of d as the stream spreads
// it (block means, edge pixels past the ends, the taps, interpolation at the pixels' places),
// over every place of the step within a block: in one dimension, where the 2D filters are
// separable.
double worst_step_error(const std::vector<double>& exact_step, const std::vector<float>& taps, int d) {
    const int exact_radius = int(exact_step.size() / 2), r = int(taps.size() / 2);
    const int margin = exact_radius + (r + 2) * d;  // (no filter reads past the ends from within)
    const int width = 2 * (margin + d), blocks = width / d;
    double worst = 0;
    for (int edge = width / 2; edge < width / 2 + d; ++edge) {
        std::vector<double> means(size_t(blocks + 2 * r));  // (past the ends: the edge blocks)
        for (int b = -r; b < blocks + r; ++b) {
            const int clamped = std::clamp(b, 0, blocks - 1);
            means[size_t(b + r)] = double(std::clamp(clamped * d + d - edge, 0, d)) / d;
        }
        std::vector<double> spread(static_cast<size_t>(blocks));
        for (int b = 0; b < blocks; ++b)
            for (int k = -r; k <= r; ++k) spread[size_t(b)] += taps[size_t(k + r)] * means[size_t(b + k + r)];
        for (int x = margin; x < width - margin; ++x) {
            const int i = floor_div(2 * x + 1 - d, 2 * d);
            const double t = double(2 * x + 1 - d - 2 * d * i) / (2 * d);
            const double coarse = spread[size_t(i)] + t * (spread[size_t(i + 1)] - spread[size_t(i)]);
            const int offset = std::clamp(x - edge, -exact_radius - 1, exact_radius);
            const double exact = offset < -exact_radius ? 0.0 : exact_step[size_t(offset + exact_radius)];
            worst = std::max(worst, std::abs(coarse - exact));
        }
    }
    return worst;
}

}  // namespace

CoarseGaussian design_coarse_gaussian(double sigma_px, int decimation, double coarse_reach_sigmas) {
    CoarseGaussian g;
    g.decimation = std::max(1, decimation);
    const int d = g.decimation;
    if (d == 1) {
        g.taps = pixel_integrated_gaussian(sigma_px);
        g.radius_px = int(g.taps.size() / 2);
        return g;
    }
    if (!(2 * sigma_px > d)) throw std::logic_error("a coarse Gaussian narrower than its grid");
    // The coarse Gaussian's width that spreads a step closest to the pixels' Gaussian (golden-section
    // search). Matching their variances instead (the blocks and the interpolation add about d^2/3)
    // is as close on grids fine against sigma, but on one of 1.2 sigma the few taps' shape
    // matters: its step was 0.072 off, against 0.039 (docs/model/dir-couplers.md).
    const std::vector<float> exact = pixel_integrated_gaussian(sigma_px);
    std::vector<double> exact_step(exact.size());  // at x - edge: the sum of the taps from edge - x on
    double sum = 0;
    for (size_t n = 0; n < exact.size(); ++n) exact_step[n] = sum += exact[exact.size() - 1 - n];
    auto error = [&](double coarse_sigma) {
        return worst_step_error(exact_step, coarse_taps(coarse_sigma, coarse_reach_sigmas), d);
    };
    // (From a Gaussian of one tap to the whole sigma on the grid; 30 steps narrow it 1e-6 times.)
    const double golden = (std::sqrt(5.0) - 1) / 2;
    double lo = 0.2, hi = sigma_px / d;
    double a = hi - golden * (hi - lo), b = lo + golden * (hi - lo), error_a = error(a), error_b = error(b);
    for (int i = 0; i < 30; ++i) {
        if (error_a < error_b) {
            hi = b, b = a, error_b = error_a;
            a = hi - golden * (hi - lo), error_a = error(a);
        } else {
            lo = a, a = b, error_a = error_b;
            b = lo + golden * (hi - lo), error_b = error(b);
        }
    }
    g.coarse_sigma = error_a < error_b ? a : b;
    g.taps = coarse_taps(g.coarse_sigma, coarse_reach_sigmas);
    g.radius_px = (int(g.taps.size() / 2) + 2) * d;
    return g;
}

CoarseGaussianStream::CoarseGaussianStream(const std::vector<const std::vector<float>*>& coarse_taps, int decimation,
                                           const Window& out, const Window& frame, Input input,
                                           CoarseMap means_map, CoarseMap blurred_map,
                                           std::vector<float> geometric_floors)
    : out_(out),
      frame_(frame),
      means_map_(std::move(means_map)),
      blurred_map_(std::move(blurred_map)),
      geometric_floors_(std::move(geometric_floors)),
      planes_(coarse_taps.size()),
      d_(decimation) {
    if (d_ < 2) throw std::invalid_argument("coarse Gaussian: a decimation below 2");
    if (Source* source = std::get_if<Source>(&input))
        source_ = std::move(*source);
    else
        lent_ = std::move(std::get<LentRows>(input));
    int r = 0;  // the largest coarse Gaussian's radius
    for (size_t p = 0; p < coarse_taps.size(); ++p)
        if (coarse_taps[p]) {
            r = std::max(r, int(coarse_taps[p]->size() / 2));
            blurred_.push_back(p);
        }
    if (blurred_.empty()) throw std::invalid_argument("coarse Gaussian: no plane is blurred");
    if (!geometric_floors_.empty() && geometric_floors_.size() != blurred_.size())
        throw std::invalid_argument("coarse Gaussian: a geometric mean's floor for each blurred plane");
    auto [cx0, cx1] = coarse_range(out.x0, out.x1, d_);
    auto [cy0, cy1] = coarse_range(out.y0, out.y1, d_);
    blurred_window_ = {cx0, cy0, cx1, cy1};
    means_window_ = blurred_window_.grown(r);
    inside0_ = std::clamp(means_window_.x0 * d_, frame.x0, frame.x1);
    inside1_ = std::clamp(means_window_.x1 * d_, frame.x0, frame.x1);
    read_x0_ = std::min(std::max(out.x0, frame.x0), inside0_);
    read_x1_ = std::max(std::min(out.x1, frame.x1), inside1_);
    // The columns' blocks and weights of the interpolation along x (the same on every row).
    for (int x = out.x0; x < out.x1; ++x) {
        const int i = floor_div(2 * x + 1 - d_, 2 * d_), column = x - out.x0, block = i - blurred_window_.x0;
        tx_.push_back(float(2 * x + 1 - d_ - 2 * d_ * i) / float(2 * d_));
        if (column_runs_.empty() || column_runs_.back().block != block) column_runs_.push_back({column, column, block});
        column_runs_.back().end = column + 1;
    }
    if (d_ <= kMaxRunDecimation) {  // the whole runs (d columns each), from the first on or the second
        auto whole = [&](size_t r) {
            return r < column_runs_.size() && column_runs_[r].end - column_runs_[r].begin == d_;
        };
        size_t r = whole(0) ? 0 : 1;
        whole_runs_[0] = r;
        while (whole(r)) ++r;
        whole_runs_[1] = r;
    }
    std::vector<SeparableFilter> filters;
    for (size_t p : blurred_) {
        PlaneRows& plane = planes_[p];
        filters.push_back(SeparableFilter{{*coarse_taps[p]}, {1.0f}});
        plane.column_sums.resize(size_t(means_window_.width()) * d_);
    }
    // Every plane's coarse rows from one stream, so that each fine row is read once for all.
    blur_ = std::make_unique<SeparableStream>(
        blurred_window_.width(), std::move(filters), means_window_.y0, means_window_.y1, blurred_window_.y1,
        [this](int by, float* const* means) { block_means(by, means); }, kCoarseRowsTogether, kCoarseRowsKept);
    // Output row y lies above coarse row j + 1 (j d <= y), whose blur (with the rows summed
    // with it) reads block rows to j + kCoarseRowsTogether + r, the last of them ending at fine
    // row y + (kCoarseRowsTogether + r + 1) d - 1: the ring holds row y to that one (ring_row
    // refuses a row that has left it).
    slots_ = rows_kept(r, d_);
    if (lent_.row) {
        ring_rows_.resize(size_t(slots_) * planes_.size());
    } else {
        ring_.resize(planes_.size());
        for (auto& ring : ring_) ring.resize(size_t(slots_) * size_t(read_x1_ - read_x0_));
        ring_rows_.resize(planes_.size());
    }
    row_.read.resize(planes_.size());
    row_.above.assign(planes_.size(), nullptr);
    row_.below.assign(planes_.size(), nullptr);
}

float* CoarseGaussianStream::ring_row(size_t plane, int y) {
    if (y < next_ - slots_ || y >= next_) throw std::logic_error("coarse Gaussian: a row outside the stream's ring");
    const size_t slot = size_t(floor_mod(y, slots_));
    if (lent_.row) return ring_rows_[slot * planes_.size() + plane];
    return &ring_[plane][slot * size_t(read_x1_ - read_x0_)];
}

// Reads fine rows up to y (within the frame) into the ring (or keeps the lent rows' places).
void CoarseGaussianStream::read_to(int y) {
    if (!started_) {
        next_ = std::clamp(y, frame_.y0, frame_.y1 - 1);
        started_ = true;
    }
    for (; next_ <= y; ++next_) {
        if (lent_.row) {
            float* const* rows = lent_.row(next_);
            const size_t slot = size_t(floor_mod(next_, slots_));
            for (size_t p = 0; p < planes_.size(); ++p)
                ring_rows_[slot * planes_.size() + p] = rows[p] + (read_x0_ - lent_.x0);
            continue;
        }
        for (size_t p = 0; p < planes_.size(); ++p)
            ring_rows_[p] = &ring_[p][size_t(floor_mod(next_, slots_)) * size_t(read_x1_ - read_x0_)];
        source_(next_, read_x0_, read_x1_, ring_rows_.data());
    }
}

// Block means of the image extended past the frame by its edge pixels, as the Gaussian on
// the pixels reads it (blocks past the frame too, so that the coarse Gaussian clamps nothing
// of its own): the block row's d rows summed column by column (whole rows, in vector
// registers), then each block's d columns; for every blurred plane, means[i] its row. Geometric
// means likewise from the values' pseudo logarithms.
void CoarseGaussianStream::block_means(int by, float* const* means) {
    const int d = d_, px_begin = means_window_.x0 * d, n = inside1_ - inside0_;
    for (int k = 0; k < d; ++k) {
        const int y = std::clamp(by * d + k, frame_.y0, frame_.y1 - 1);
        read_to(y);
        for (size_t i = 0; i < blurred_.size(); ++i) {
            const size_t p = blurred_[i];
            const float* in = ring_row(p, y) + (inside0_ - read_x0_);
            float* sums = planes_[p].column_sums.data() + (inside0_ - px_begin);
            if (!geometric_floors_.empty())
                simd::dispatch<AddPseudoLog2Row>(sums, in, geometric_floors_[i], k == 0, n);
            else if (k == 0)
                std::copy(in, in + n, sums);
            else
                simd::dispatch<AddRow>(sums, in, n);
        }
    }
    for (size_t i = 0; i < blurred_.size(); ++i) {
        // The columns past the frame's edges are its edge columns.
        std::vector<float>& sums = planes_[blurred_[i]].column_sums;
        std::fill(sums.begin(), sums.begin() + (inside0_ - px_begin), sums[inside0_ - px_begin]);
        std::fill(sums.begin() + (inside1_ - px_begin), sums.end(), sums[inside1_ - 1 - px_begin]);
        if (d <= kMaxRunDecimation) {
            dispatch_decimation<BlockMeans>(d, static_cast<const float*>(sums.data()), means_window_.width(),
                                            means[i]);
        } else {
            for (int bx = means_window_.x0; bx < means_window_.x1; ++bx) {
                float sum = 0;
                for (int x = bx * d; x < bx * d + d; ++x) sum += sums[size_t(x - px_begin)];
                means[i][bx - means_window_.x0] = sum / float(d * d);
            }
        }
        if (!geometric_floors_.empty()) simd::dispatch<Exp2OfPseudoLog2Row>(means[i], means_window_.width());
    }
    if (means_map_) means_map_(means, means_window_.width());
}

// Coarse row j of every plane's blurred means, mapped (the last two rows are kept, in the blur's
// own rows: it keeps them while rows to j + 1 are asked for).
void CoarseGaussianStream::keep_coarse(int j) {
    if (coarse_row_[j & 1] == j) return;
    float* const* blurred_rows = blur_->row(j);  // (the stream's to change: it reads them no more)
    if (blurred_map_) blurred_map_(blurred_rows, blurred_window_.width());
    for (size_t b = 0; b < blurred_.size(); ++b) planes_[blurred_[b]].coarse[j & 1] = blurred_rows[b];
    coarse_row_[j & 1] = j;
}

// Coarse row j of every plane, interpolated along x to out's columns (the last two rows are kept).
void CoarseGaussianStream::interpolate(int j) {
    if (across_row_[j & 1] == j) return;
    keep_coarse(j);
    for (size_t b = 0; b < blurred_.size(); ++b) {
        std::vector<float>& row = planes_[blurred_[b]].across[j & 1];
        row.resize(size_t(out_.width()));  // (only row() asks for them)
        along_x<false>(planes_[blurred_[b]].coarse[j & 1], nullptr, 0.0f, nullptr, row.data());
    }
    across_row_[j & 1] = j;
}

void CoarseGaussianStream::multiply_by_interpolated(const float* above, const float* below, float t,
                                                    const float* fine, float* out) const {
    along_x<true>(above, below, t, fine, out);
}

// The whole runs (d columns each) in vectors; the partial ones at the edges (and every run
// past the vector kernels' decimations) a run's two coarse values once, then a loop without
// indirection (which vectorises).
template <bool multiply>
void CoarseGaussianStream::along_x(const float* above, const float* below, float t, const float* in,
                                   float* out) const {
    const CoarseRow coarse{above, below, t};
    if (whole_runs_[1] > whole_runs_[0]) {
        const ColumnRun& run = column_runs_[whole_runs_[0]];
        const int blocks = int(whole_runs_[1] - whole_runs_[0]);
        const float* weights = tx_.data() + run.begin;
        if constexpr (multiply)
            dispatch_decimation<InterpolateRunsMultiplied>(d_, coarse.from(run.block), weights, blocks,
                                                           in + run.begin, out + run.begin);
        else  // (out in place of in, never read)
            dispatch_decimation<InterpolateRunsWritten>(d_, coarse.from(run.block), weights, blocks,
                                                        static_cast<const float*>(out + run.begin), out + run.begin);
    }
    auto runs = [&](size_t first, size_t last) {
        for (size_t r = first; r < last; ++r) {
            const ColumnRun& run = column_runs_[r];
            // (In plain floats: GCC vectorises the loop over a run, not one of one-lane vectors.)
            const float b0 = coarse.at<simd::Float1>(run.block)[0],
                        step = coarse.at<simd::Float1>(run.block + 1)[0] - b0;
            for (int i = run.begin; i < run.end; ++i) {
                const float v = b0 + tx_[size_t(i)] * step;
                if constexpr (multiply)
                    out[i] = in[i] * v;
                else
                    out[i] = v;
            }
        }
    };
    runs(0, whole_runs_[0]);
    runs(whole_runs_[1], column_runs_.size());
}

const CoarseGaussianStream::Row& CoarseGaussianStream::row(int y) { return read_row(y, true); }

const CoarseGaussianStream::Row& CoarseGaussianStream::coarse_row(int y) { return read_row(y, false); }

const CoarseGaussianStream::Row& CoarseGaussianStream::read_row(int y, bool across) {
    // The coarse rows first: they read the fine rows below this one.
    const int j = floor_div(2 * y + 1 - d_, 2 * d_);
    for (int k : {j, j + 1}) {
        if (across)
            interpolate(k);
        else
            keep_coarse(k);
    }
    read_to(y);
    row_.t = float(2 * y + 1 - d_ - 2 * d_ * j) / float(2 * d_);  // the fine row's place between them
    for (size_t p = 0; p < planes_.size(); ++p) {
        row_.read[p] = ring_row(p, y) + (out_.x0 - read_x0_);
        if (planes_[p].column_sums.empty()) continue;
        row_.above[p] = across ? planes_[p].across[j & 1].data() : planes_[p].coarse[j & 1];
        row_.below[p] = across ? planes_[p].across[(j + 1) & 1].data() : planes_[p].coarse[(j + 1) & 1];
    }
    return row_;
}

}  // namespace darkroom
