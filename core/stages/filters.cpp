#include "core/stages/filters.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <type_traits>

#include "core/parallel.h"
#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

std::vector<float> pixel_integrated_gaussian(double sigma_px) {
    return pixel_integrated_gaussian(sigma_px, sigma_px < 1e-3 ? 0 : (int)std::ceil(4.0 * sigma_px));
}

std::vector<float> pixel_integrated_gaussian(double sigma_px, int radius) {
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
// kTaps: n, known when compiled (the taps then symmetric), so that the loops over the taps
// unroll; 0: n and pairs as given.
// kCentred: then centre times centre_rows[o][x] is added to each sum last.
template <int lanes, int vecs, int outputs, bool accumulate, bool kCentred, int kTaps, typename RowOf>
__attribute__((always_inline)) inline int tap_blocks(const float* tap, int n, int pairs, int x, int width,
                                                     float* const* __restrict out, RowOf row_of, float centre,
                                                     const float* const* centre_rows) {
    if constexpr (kTaps > 0) n = kTaps, pairs = kTaps / 2;
    using Vec = typename simd::Lanes<lanes>::F;
    constexpr int block = lanes * vecs;
    // With kTaps known, the taps' vectors are set once, before the loop (the compiler would
    // load them again each block: the stores to `out` might change them).
    Vec kept_tap[kTaps > 0 ? kTaps : 1];
    if constexpr (kTaps > 0)
        for (int k = 0; k < kTaps; ++k) kept_tap[k] = Vec{} + tap[k];
    auto tap_vec = [&](int k) __attribute__((always_inline)) {
        if constexpr (kTaps > 0)
            return kept_tap[k];
        else
            return Vec{} + tap[k];
    };
    for (; x + block <= width; x += block) {
        Vec sum[outputs][vecs];
        for (int o = 0; o < outputs; ++o)
            for (int v = 0; v < vecs; ++v)
                if (accumulate)
                    load(sum[o][v], out[o] + x + v * lanes);
                else
                    sum[o][v] = Vec{};
        for (int k = 0; k < pairs; ++k) {
            const Vec t = tap_vec(k);
            for (int o = 0; o < outputs; ++o) {
                const float *row = row_of(k + o) + x, *mirror = row_of(n - 1 - k + o) + x;
                for (int v = 0; v < vecs; ++v) {
                    Vec in, in_mirror;
                    load(in, row + v * lanes);
                    load(in_mirror, mirror + v * lanes);
                    sum[o][v] += t * (in + in_mirror);
                }
            }
        }
        for (int k = pairs; k < n - pairs; ++k) {
            const Vec t = tap_vec(k);
            for (int o = 0; o < outputs; ++o) {
                const float* row = row_of(k + o) + x;
                for (int v = 0; v < vecs; ++v) {
                    Vec in;
                    load(in, row + v * lanes);
                    sum[o][v] += t * in;
                }
            }
        }
        if constexpr (kCentred) {
            const Vec c = Vec{} + centre;
            for (int o = 0; o < outputs; ++o)
                for (int v = 0; v < vecs; ++v) {
                    Vec pixel;
                    load(pixel, centre_rows[o] + x + v * lanes);
                    sum[o][v] += c * pixel;
                }
        }
        for (int o = 0; o < outputs; ++o)
            for (int v = 0; v < vecs; ++v) store(out[o] + x + v * lanes, sum[o][v]);
    }
    return x;
}

// A row's inputs from x on: row_of(k) = in + k (a horizontal pass).
struct RowFrom {
    const float* in;
    const float* operator()(int k) const { return in + k; }
};

// Lanes k ... k + lanes - 1 of the consecutive vectors v[0], v[1], ... (k known when compiled).
template <int k, typename V, size_t... J>
__attribute__((always_inline)) inline V shifted(const V* v, std::index_sequence<J...>) {
    constexpr int lanes = sizeof...(J);
    if constexpr (k % lanes == 0)
        return v[k / lanes];
    else
        return __builtin_shufflevector(v[k / lanes], v[k / lanes + 1], (k % lanes + int(J))...);
}

// tap_blocks for a horizontal pass of kTaps symmetric taps, not accumulated: each block's inputs
// loaded once as whole vectors and each tap's window of them shifted in registers (one
// instruction with AVX-512), where tap_blocks loads each tap's window from memory, which
// straddles two cache lines (a 4K frame's MTF and the couplers' coarse Gaussian were bound by
// those loads). The same sums in the same order. Blocks only while their last vector lies
// within the row's width + kTaps - 1 values.
template <int lanes, int vecs, int kTaps, size_t... K>
__attribute__((always_inline)) inline int shifted_row_blocks(const float* tap, int x, int width, float* __restrict out,
                                                             const float* in, std::index_sequence<K...>) {
    using Vec = typename simd::Lanes<lanes>::F;
    constexpr int block = lanes * vecs, pairs = kTaps / 2;
    constexpr int chunks = vecs + (kTaps - 1 + lanes - 1) / lanes;  // the vectors a block reads
    const Vec kept_tap[kTaps] = {(Vec{} + tap[K])...};
    for (; x + chunks * lanes <= width + kTaps - 1; x += block) {
        Vec chunk[chunks];
        for (int c = 0; c < chunks; ++c) load(chunk[c], in + x + c * lanes);
        Vec sum[vecs];
        for (int v = 0; v < vecs; ++v) sum[v] = Vec{};
        (
            [&] {
                if constexpr (int(K) < pairs)
                    for (int v = 0; v < vecs; ++v)
                        sum[v] += kept_tap[K] * (shifted<int(K)>(chunk + v, std::make_index_sequence<lanes>()) +
                                                 shifted<kTaps - 1 - int(K)>(chunk + v, std::make_index_sequence<lanes>()));
            }(),
            ...);
        for (int v = 0; v < vecs; ++v)
            sum[v] += kept_tap[pairs] * shifted<pairs>(chunk + v, std::make_index_sequence<lanes>());
        for (int v = 0; v < vecs; ++v) store(out + x + v * lanes, sum[v]);
    }
    return x;
}

// A horizontal pass's blocks by shifted_row_blocks where it applies (AVX-512, kTaps known
// and odd, written, not added): the x the other loops go on from.
template <int lanes, bool adds, int kTaps, typename RowOf>
__attribute__((always_inline)) inline int shifted_row_start(const float* tap, int width, float* const* out,
                                                            const RowOf& row_of) {
    if constexpr (std::is_same_v<RowOf, RowFrom> && kTaps > 0 && kTaps % 2 == 1 && lanes == 16 && !adds)
        return shifted_row_blocks<lanes, kVecs, kTaps>(tap, 0, width, out[0], row_of.in,
                                                       std::make_index_sequence<kTaps>());
    (void)tap, (void)width, (void)out, (void)row_of;
    return 0;
}

// out[o][x] (+)= sum_k taps[k] row_of(k + o)[x] for each of `outputs` outputs (1, or 2 or 4: a
// column pass's consecutive rows, which share all but a few of their input rows, so that
// each is read from memory once for all).
template <int lanes, int outputs, bool accumulate, bool kCentred = false, typename RowOf>
__attribute__((always_inline)) inline void tap_sums(const float* tap, int n, int width, float* const* __restrict out,
                                                    RowOf row_of, float centre = 0,
                                                    const float* const* centre_rows = nullptr) {
    const bool symmetric = std::equal(tap, tap + n / 2, std::reverse_iterator<const float*>(tap + n));
    const int pairs = symmetric ? n / 2 : 0;  // taps k and n-1-k for k < pairs; then k in [pairs, n - pairs)
    // (taps: std::integral_constant, kTaps. Inlined like the rest: a lambda called from
    // three places was otherwise compiled apart, for the default target, SSE2, and the AVX2
    // kernels called that.)
    auto run = [&](auto taps) __attribute__((always_inline)) {
        constexpr int kTaps = decltype(taps)::value;
        int x = shifted_row_start<lanes, accumulate || kCentred, kTaps>(tap, width, out, row_of);
        x = tap_blocks<lanes, kVecs / outputs, outputs, accumulate, kCentred, kTaps>(tap, n, pairs, x, width, out,
                                                                                     row_of, centre, centre_rows);
        x = tap_blocks<lanes, 1, outputs, accumulate, kCentred, kTaps>(tap, n, pairs, x, width, out, row_of, centre,
                                                                       centre_rows);
        tap_blocks<1, 1, outputs, accumulate, kCentred, kTaps>(tap, n, pairs, x, width, out, row_of, centre, centre_rows);
    };
    // The fast tiers' kernels: the MTF's 5 taps where tapered (up to 7 where not; preview's 3
    // to 5), the grain's 3, the DIR couplers' 11 on their coarse grid at a 4K frame's pitch.
    if (symmetric && n == 11)
        run(std::integral_constant<int, 11>());
    else if (symmetric && n == 7)
        run(std::integral_constant<int, 7>());
    else if (symmetric && n == 5)
        run(std::integral_constant<int, 5>());
    else if (symmetric && n == 3)
        run(std::integral_constant<int, 3>());
    else
        run(std::integral_constant<int, 0>());
}

struct ConvolveRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* in, const float* taps, int n, int width, float* out) {
        tap_sums<lanes, 1, false>(taps, n, width, &out, RowFrom{in});
    }
};

template <int outputs, bool accumulate, bool centred = false>
struct ConvolveColumn {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* const* rows, const float* taps, int n, int width,
                                                   float* const* out, float centre = 0,
                                                   const float* const* centre_rows = nullptr) {
        tap_sums<lanes, outputs, accumulate, centred>(taps, n, width, out, [rows](int k) { return rows[k]; }, centre,
                                                      centre_rows);
    }
};

// convolve_columns with its group's size, accumulation and centre known when compiled.
template <int outputs>
void columns_of(const float* const* rows, const float* taps, int n, int width, float* const* out, bool add,
                float centre, const float* const* centre_rows) {
    if (centre_rows)
        add ? simd::dispatch<ConvolveColumn<outputs, true, true>>(rows, taps, n, width, out, centre, centre_rows)
            : simd::dispatch<ConvolveColumn<outputs, false, true>>(rows, taps, n, width, out, centre, centre_rows);
    else
        add ? simd::dispatch<ConvolveColumn<outputs, true>>(rows, taps, n, width, out, 0.0f, centre_rows)
            : simd::dispatch<ConvolveColumn<outputs, false>>(rows, taps, n, width, out, 0.0f, centre_rows);
}

}  // namespace

void convolve_row(const float* in, const std::vector<float>& taps, int width, float* out) {
    simd::dispatch<ConvolveRow>(in, taps.data(), int(taps.size()), width, out);
}

void convolve_columns(const float* const* rows, const std::vector<float>& taps, int width, float* const* out,
                      int outputs, bool add, float centre, const float* const* centre_rows) {
    const float* t = taps.data();
    const int n = int(taps.size());
    if (outputs == 4)
        columns_of<4>(rows, t, n, width, out, add, centre, centre_rows);
    else if (outputs == 2)
        columns_of<2>(rows, t, n, width, out, add, centre, centre_rows);
    else if (outputs == 1)
        columns_of<1>(rows, t, n, width, out, add, centre, centre_rows);
    else
        throw std::invalid_argument("convolve_columns: 1, 2 or 4 rows at once");
}

// Lower-triangular L with L L^T = m (n x n, row-major), or false if m is not positive
// semi-definite. A zero pivot (fully correlated channels) gives a zero column.
static bool cholesky(const std::vector<double>& m, int n, std::vector<double>& l) {
    l.assign((size_t)n * n, 0.0);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j <= i; ++j) {
            double sum = m[(size_t)i * n + j];
            for (int k = 0; k < j; ++k) sum -= l[(size_t)i * n + k] * l[(size_t)j * n + k];
            if (i == j) {
                if (sum < -1e-9) return false;
                l[(size_t)i * n + i] = std::sqrt(std::max(sum, 0.0));
            } else {
                double pivot = l[(size_t)j * n + j];
                l[(size_t)i * n + j] = pivot > 1e-6 ? sum / pivot : 0.0;
            }
        }
    return true;
}

std::vector<double> white_noise_mixing(const std::vector<double>& field_correlation,
                                       const std::vector<double>& kernel_overlap, int n) {
    std::vector<double> mix_correlation((size_t)n * n), l;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const size_t ab = (size_t)a * n + b;
            const double m = a == b ? 1.0 : field_correlation[ab] / std::max(kernel_overlap[ab], 1e-6);
            mix_correlation[ab] = std::clamp(m, -1.0, 1.0);
        }
    while (!cholesky(mix_correlation, n, l))
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b)
                if (a != b) mix_correlation[(size_t)a * n + b] *= 0.99;
    return l;
}

// Eigenvalues and orthonormal eigenvectors of a symmetric n x n matrix `a` (row-major, used
// as scratch) by cyclic Jacobi rotations: each rotation zeroes one off-diagonal element, and
// sweeps repeat until the off-diagonal part is negligible. Exact to rounding for the small,
// nearly opposite eigenvalues of a kernel's residual too, where power iteration stalls.
// vectors[i * n + k] is component i of eigenvector k.
void symmetric_eigen(std::vector<double>& a, int n, std::vector<double>& values, std::vector<double>& vectors) {
    vectors.assign(size_t(n) * n, 0.0);
    for (int i = 0; i < n; ++i) vectors[size_t(i) * n + i] = 1.0;
    auto at = [&](int i, int j) -> double& { return a[size_t(i) * n + j]; };
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0, diagonal = 0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) (i == j ? diagonal : off) += at(i, j) * at(i, j);
        if (!(off > 1e-30 * diagonal)) break;
        for (int p = 0; p < n; ++p)
            for (int q = p + 1; q < n; ++q) {
                const double apq = at(p, q);
                if (apq == 0) continue;
                // The rotation's tangent t = s / c zeroes a'_pq: t^2 + 2 theta t - 1 = 0,
                // its smaller root (a rotation of at most 45 degrees).
                const double theta = (at(q, q) - at(p, p)) / (2 * apq);
                const double t = std::abs(theta) > 1e150 ? 0.5 / theta
                                                         : std::copysign(1.0, theta) / (std::abs(theta) + std::sqrt(theta * theta + 1));
                const double c = 1 / std::sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < n; ++k) {
                    const double kp = at(k, p), kq = at(k, q);
                    at(k, p) = c * kp - s * kq;
                    at(k, q) = s * kp + c * kq;
                }
                for (int k = 0; k < n; ++k) {
                    const double pk = at(p, k), qk = at(q, k);
                    at(p, k) = c * pk - s * qk;
                    at(q, k) = s * pk + c * qk;
                }
                for (int k = 0; k < n; ++k) {
                    double& vp = vectors[size_t(k) * n + p];
                    double& vq = vectors[size_t(k) * n + q];
                    const double kp = vp, kq = vq;
                    vp = c * kp - s * kq;
                    vq = s * kp + c * kq;
                }
            }
    }
    values.resize(n);
    for (int i = 0; i < n; ++i) values[i] = at(i, i);
}

SeparableFilter separable_approximation(const std::vector<double>& taps, int r, double residual_energy) {
    const int side = 2 * r + 1;
    auto tap = [&](int row, int column) { return taps[size_t(row) * side + column]; };
    // K = U S V^T from the eigen-decomposition of K^T K = V S^2 V^T; u_k = K v_k / s_k.
    std::vector<double> gram(size_t(side) * side, 0.0), squares, v;
    for (int a = 0; a < side; ++a)
        for (int b = 0; b < side; ++b)
            for (int row = 0; row < side; ++row) gram[size_t(a) * side + b] += tap(row, a) * tap(row, b);
    symmetric_eigen(gram, side, squares, v);
    std::vector<int> order(side);
    for (int k = 0; k < side; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](int i, int j) { return squares[i] > squares[j]; });
    double energy = 0;
    for (double t : taps) energy += t * t;
    SeparableFilter filter;
    double left = energy;  // the energy of the terms not yet kept: sum of their s_k^2
    for (int k : order) {
        if (!(left > residual_energy * energy) || !(squares[k] > 0)) break;
        const double s = std::sqrt(squares[k]), root = std::sqrt(s);  // each pass carries sqrt(s)
        std::vector<float> along_x(side), along_y(side);
        for (int i = 0; i < side; ++i) {
            double u = 0;
            for (int column = 0; column < side; ++column) u += tap(i, column) * v[size_t(column) * side + k];
            along_x[i] = float(v[size_t(i) * side + k] * root);
            along_y[i] = float(u / s * root);
        }
        filter.terms.push_back(std::move(along_x));
        filter.vertical_terms.push_back(std::move(along_y));
        filter.signs.push_back(1.0f);
        left -= squares[k];
    }
    return filter;
}

SeparableStream::SeparableStream(int width, std::vector<SeparableFilter> filters, int row_begin, int row_end,
                                 int rows_end, Source source, int rows_together, int rows_kept)
    : width_(width), radius_(0), row_begin_(row_begin), row_end_(row_end), rows_end_(rows_end),
      rows_together_(rows_together), filters_(std::move(filters)), source_(std::move(source)) {
    if (rows_together < 1 || rows_together > kMaxRowsTogether)
        throw std::invalid_argument("separable stream: 1 to 4 rows summed together");
    for (const SeparableFilter& f : filters_) radius_ = std::max(radius_, f.radius());
    slots_ = 2 * radius_ + rows_together_;
    // Asked for row y', the stream writes output rows to y' + rows_together - 1, and input rows
    // to R past them (an identity's output rows are its input rows).
    output_slots_ = std::max(rows_together_, rows_kept + rows_together_ - 1);
    identity_slots_ = std::max(slots_, output_slots_ + radius_);
    // Rows are a cache line more than the width apart: at widths of a power of two, rows
    // exactly 2^k bytes apart share the L1 cache's sets and would evict each other.
    stride_ = size_t(width) + 16;
    padded_stride_ = size_t(width) + 2 * radius_ + 16;
    for (const SeparableFilter& f : filters_) {
        std::vector<std::vector<float>> vertical;
        for (size_t t = 0; t < f.terms.size(); ++t) {
            vertical.emplace_back();
            for (float v : f.vertical_terms.empty() ? f.terms[t] : f.vertical_terms[t]) vertical.back().push_back(f.signs[t] * v);
        }
        vertical_.push_back(std::move(vertical));
        centre_.push_back({f.centre});
        ring_.emplace_back(f.terms.size() * slots_ * stride_);
        padded_.emplace_back(size_t(padded_slots(f)) * padded_stride_);
        output_.emplace_back(size_t(output_slots_) * stride_);
        for (int o = 0; o < rows_together_; ++o) out_rows_[o].push_back(nullptr);
    }
    padded_rows_.resize(filters_.size());
    column_.resize(slots_);
}

// A plane whose output reads its input rows themselves (a centre, or the identity) keeps them
// in a ring as its terms' rows are kept; the others' input rows are read once, as they arrive.
bool SeparableStream::keeps_input_rows(const SeparableFilter& f) { return f.centre != 0 || f.terms.empty(); }

// The input rows a plane keeps: the identity's are its output rows, kept as long as those.
int SeparableStream::padded_slots(const SeparableFilter& f) const {
    return f.is_identity() ? identity_slots_ : keeps_input_rows(f) ? slots_ : 1;
}

float* SeparableStream::ring_row(size_t plane, int term, int y) {
    return &ring_[plane][(size_t(term) * slots_ + floor_mod(y, slots_)) * stride_];
}

float* SeparableStream::padded_row(size_t plane, int y) {
    const int slots = padded_slots(filters_[plane]);
    const size_t slot = size_t(floor_mod(y, slots));
    return &padded_[plane][slot * padded_stride_];
}

float* const* SeparableStream::row(int y) {
    if (y >= group_y_ && y < group_y_ + group_rows_) return out_rows_[y - group_y_].data();
    if (!started_) {
        next_ = std::max(y - radius_, row_begin_);
        started_ = true;
    }
    // This row and the next ones asked for, up to rows_together_.
    const int rows = std::clamp(rows_end_ - y, 1, rows_together_);
    for (; next_ <= std::min(y + rows - 1 + radius_, row_end_ - 1); ++next_) {
        for (size_t p = 0; p < filters_.size(); ++p) padded_rows_[p] = padded_row(p, next_);
        source_(next_, padded_rows_.data());
        for (size_t p = 0; p < filters_.size(); ++p) {
            const SeparableFilter& f = filters_[p];
            const float* in = padded_rows_[p] + (radius_ - f.radius());  // the plane's own halo
            for (size_t t = 0; t < f.terms.size(); ++t) convolve_row(in, f.terms[t], width_, ring_row(p, int(t), next_));
        }
    }
    for (size_t p = 0; p < filters_.size(); ++p) {
        const SeparableFilter& f = filters_[p];
        if (f.is_identity()) {  // (its input rows outlive the group: the ring holds identity_slots_)
            for (int o = 0; o < rows; ++o) out_rows_[o][p] = padded_row(p, y + o) + radius_;
            continue;
        }
        for (int o = 0; o < rows; ++o)
            out_rows_[o][p] = &output_[p][size_t(floor_mod(y + o, output_slots_)) * stride_];
        const float* pixels[kMaxRowsTogether];  // the rows' own input pixels, for the centre
        for (int o = 0; o < rows; ++o) pixels[o] = padded_row(p, y + o) + radius_;
        if (f.terms.empty()) {
            for (int o = 0; o < rows; ++o) convolve_columns(&pixels[o], centre_[p], width_, &out_rows_[o][p], 1, false);
            continue;
        }
        const int r = f.radius();
        for (size_t t = 0; t < f.terms.size(); ++t) {
            for (int k = -r; k <= r + rows - 1; ++k)
                column_[k + r] = ring_row(p, int(t), std::clamp(y + k, row_begin_, row_end_ - 1));
            // After the last term's taps, the centre: one order of the sum for every row.
            const bool last = t + 1 == f.terms.size() && f.centre != 0;
            // The rows in runs of 4, 2 and 1, each value summed alike in any of them.
            for (int o = 0; o < rows;) {
                const int run = rows - o >= 4 ? 4 : rows - o >= 2 ? 2 : 1;
                float* out[kMaxRowsTogether];  // (the plane's own output rows)
                for (int i = 0; i < run; ++i) out[i] = out_rows_[o + i][p];
                convolve_columns(column_.data() + o, vertical_[p][t], width_, out, run, t > 0, f.centre,
                                 last ? pixels + o : nullptr);
                o += run;
            }
        }
    }
    group_y_ = y, group_rows_ = rows;
    return out_rows_[0].data();
}

void filter_separable(const Window& out, const SeparableFilter& filter, int row_begin, int row_end, int threads,
                      const RowSource& source, const RowTarget& target, const RowSink& sink) {
    const int width = out.width();
    parallel_for(out.y0, out.y1, threads, [&](int y_begin, int y_end) {
        SeparableStream stream(width, {filter}, row_begin, row_end, y_end,
                               [&](int y, float* const* padded) { source(y, padded[0]); });
        for (int y = y_begin; y < y_end; ++y) {
            const float* filtered = stream.row(y)[0];
            if (target) {
                float* kept = target(y);
                std::copy_n(filtered, width, kept);
                filtered = kept;
            }
            if (sink) sink(y, filtered);
        }
    });
}

void hold_frame_edges(float* padded, int first, int last, const Window& frame) {
    const int inside0 = std::max(first, frame.x0), inside1 = std::min(last, frame.x1);
    if (first < inside0) std::fill(padded, padded + (inside0 - first), padded[inside0 - first]);
    if (inside1 < last) std::fill(padded + (inside1 - first), padded + (last - first), padded[inside1 - 1 - first]);
}

void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame,
                        int threads) {
    convolve_separable(src, dst, SeparableFilter{{taps}, {1.0f}}, frame, threads);
}

void convolve_separable(const Plane& src, Plane& dst, const SeparableFilter& filter, const Window& frame,
                        int threads) {
    const int r = filter.radius();
    const Window& w = dst.window;
    filter_separable(
        w, filter, frame.y0, frame.y1, threads,
        [&](int y, float* padded) {
            // The row from x = w.x0 - r, its ends held at the frame's edge pixels. (Those are
            // read only where the row reaches past them: a window's source plane need not hold them.)
            const int first = w.x0 - r, last = w.x1 + r;  // padded covers [first, last)
            const int inside0 = std::max(first, frame.x0), inside1 = std::min(last, frame.x1);
            const float* in = src.row(y) + (inside0 - src.window.x0);
            std::copy(in, in + (inside1 - inside0), padded + (inside0 - first));
            hold_frame_edges(padded, first, last, frame);
        },
        [&](int y) { return dst.row(y); }, nullptr);
}

}  // namespace darkroom
