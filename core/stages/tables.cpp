#include "core/stages/tables.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

#include <xmmintrin.h>

#include "core/parallel.h"
#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

using simd::Float1;
using simd::Int1;
using simd::load;
using simd::store;
using simd::Uint1;

namespace {

uint32_t float_bits(float v) {
    uint32_t b;
    std::memcpy(&b, &v, 4);
    return b;
}

float bits_float(uint32_t b) {
    float v;
    std::memcpy(&v, &b, 4);
    return v;
}

// The positive float nearest 10^log_h, within the normal range.
float positive_float(double log_h) {
    return float(std::clamp(std::pow(10.0, log_h), double(std::numeric_limits<float>::min()),
                            double(std::numeric_limits<float>::max())));
}

}  // namespace

LogAxisTable::LogAxisTable(const Curve& curve, int mantissa_bits, const Function& g_of_f) : shift_(23 - mantissa_bits) {
    const uint32_t step = 1u << shift_;
    first_bits_ = float_bits(positive_float(curve.x_min())) & ~(step - 1);
    last_bits_ = (float_bits(positive_float(curve.x_max())) + step - 1) & ~(step - 1);
    const uint32_t samples = ((last_bits_ - first_bits_) >> shift_) + 1;
    std::vector<std::array<float, 2>> fg(samples + 1);
    for (uint32_t i = 0; i < samples; ++i) {
        const double f = curve(std::log10(double(bits_float(first_bits_ + (i << shift_)))));
        fg[i] = {float(f), g_of_f ? float(g_of_f(f)) : 0.0f};
    }
    fg[samples] = fg[samples - 1];  // so the last sample interpolates to itself
    nodes_.resize(samples);
    for (uint32_t i = 0; i < samples; ++i) nodes_[i] = {fg[i][0], fg[i][1], fg[i + 1][0], fg[i + 1][1]};
    for (int part = 0; part < 2; ++part) {
        std::vector<float>& row = part == 0 ? f_row_ : g_row_;
        row.assign(size_t(samples) + 1 + 2 * kWindowPad, fg[samples][size_t(part)]);
        for (uint32_t i = 0; i < samples; ++i) row[kWindowPad + i] = fg[i][size_t(part)];
        std::fill(row.begin(), row.begin() + kWindowPad, fg[0][size_t(part)]);
    }
}

LogAxisTable::Samples LogAxisTable::samples() const {
    return {&nodes_[0][0], f_row_.data() + kWindowPad, g_row_.data() + kWindowPad, first_bits_, last_bits_, shift_,
            simd::isa() != simd::Isa::baseline};
}

namespace {

// Index j of the in-lane interleaves of two vectors of `lanes` floats (b the second's lanes,
// counted from `lanes`), within each 128-bit block of four: the unpacks of x86's SSE.
constexpr int unpack_low(int j, int lanes) { return j / 4 * 4 + j % 4 / 2 + (j % 2) * lanes; }        // a0 b0 a1 b1
constexpr int unpack_high(int j, int lanes) { return j / 4 * 4 + 2 + j % 4 / 2 + (j % 2) * lanes; }   // a2 b2 a3 b3
constexpr int pairs_low(int j, int lanes) { return j / 4 * 4 + j % 2 + (j % 4 / 2) * lanes; }         // a0 a1 b0 b1
constexpr int pairs_high(int j, int lanes) { return j / 4 * 4 + 2 + j % 2 + (j % 4 / 2) * lanes; }    // a2 a3 b2 b3

template <typename V, size_t... J>
__attribute__((always_inline)) inline void in_lane_transpose(const V* p, V* v, std::index_sequence<J...>) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    const V ab01 = __builtin_shufflevector(p[0], p[1], unpack_low(J, lanes)...);   // a0 a1 b0 b1 per block
    const V cd01 = __builtin_shufflevector(p[0], p[1], unpack_high(J, lanes)...);  // c0 c1 d0 d1
    const V ab23 = __builtin_shufflevector(p[2], p[3], unpack_low(J, lanes)...);
    const V cd23 = __builtin_shufflevector(p[2], p[3], unpack_high(J, lanes)...);
    v[0] = __builtin_shufflevector(ab01, ab23, pairs_low(J, lanes)...);
    v[1] = __builtin_shufflevector(ab01, ab23, pairs_high(J, lanes)...);
    v[2] = __builtin_shufflevector(cd01, cd23, pairs_low(J, lanes)...);
    v[3] = __builtin_shufflevector(cd01, cd23, pairs_high(J, lanes)...);
}

// Two vectors side by side.
template <typename V, size_t... J>
__attribute__((always_inline)) inline auto concatenate(const V& a, const V& b, std::index_sequence<J...>) {
    return __builtin_shufflevector(a, b, int(J)...);
}

// The four values of the 16-byte node at each lane's offset (in floats) into v[0..components).
// Vectors of four, eight or sixteen lanes load each node whole and transpose them in
// registers (nodes k, k + 4, ... side by side, one per 128-bit block, then a 4x4 transpose
// within each block), where lane-by-lane loads would insert the values one at a time; all
// load the same floats.
template <int components, typename V, typename I>
__attribute__((always_inline)) inline void node_values(const float* values, const I& offset, V* v) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    if constexpr (lanes == 4 || lanes == 8 || lanes == 16) {
        int32_t at[lanes];
        simd::int32_lanes(at, offset);
        simd::Float4 n[lanes];
        for (int k = 0; k < lanes; ++k) load(n[k], values + at[k]);
        V p[4], t[4];
        for (int m = 0; m < 4; ++m) {
            if constexpr (lanes == 4) {
                p[m] = n[m];
            } else {
                const simd::Float8 low = concatenate(n[m], n[m + 4], std::make_index_sequence<8>());
                if constexpr (lanes == 8) {
                    p[m] = low;
                } else {
                    const simd::Float8 high = concatenate(n[m + 8], n[m + 12], std::make_index_sequence<8>());
                    p[m] = concatenate(low, high, std::make_index_sequence<16>());
                }
            }
        }
        in_lane_transpose(p, t, std::make_index_sequence<lanes>());
        for (int c = 0; c < components; ++c) v[c] = t[c];
    } else {
        for (int c = 0; c < components; ++c)
            for (int k = 0; k < lanes; ++k) v[c][k] = values[offset[k] + c];
    }
}

// Lane k of v in every lane.
template <int k, typename U, size_t... J>
__attribute__((always_inline)) inline U lane_everywhere(const U& v, std::index_sequence<J...>) {
    return __builtin_shufflevector(v, v, int(J * 0 + k)...);
}

// Whether any lane of v is `bound` or more: the comparison's lanes (all ones where so) read
// by the sign bits of each 16 bytes (SSE's movmskps, which every instruction set here has).
// (Was: the lanes ORed by halving shuffles, then compared: a longer chain before the branch
// that the lookups wait on; the H&D lookups 9-18 % faster so with AVX2 on a Zen 3, 3-8 %
// on a Xeon, the same with its AVX-512.) Sixteen lanes by AVX-512's unsigned comparison
// into a mask register, which the branch tests (kortest): three instructions where the
// quarters took ten, four of them extracts; eight by one 32-byte movmskps, where the
// quarters took an extract and two. By assembly, as simd::sqrt_lanes, so not with clang
// (whose kernels read no windows: window_values).
template <typename U>
__attribute__((always_inline)) inline bool any_lane_at_least(const U& v, uint32_t bound) {
#if !defined(__clang__)
    if constexpr (sizeof(U) == 64) {
        const U bounds = U{} + bound;
        uint16_t at_least;
        asm("vpcmpud $5, %2, %1, %0" : "=k"(at_least) : "v"(v), "v"(bounds));  // (5: not less than)
        return at_least != 0;
    }
#endif
    const U at_least = v >= bound;
#if !defined(__clang__)
    if constexpr (sizeof(U) == 32) {
        int signs;
        asm("vmovmskps %1, %0" : "=r"(signs) : "x"(at_least));
        return signs != 0;
    }
#endif
    simd::Float4 quarters[sizeof(U) / 16];
    std::memcpy(quarters, &at_least, sizeof at_least);
    int signs = 0;
    for (const simd::Float4& q : quarters) signs |= _mm_movemask_ps(q);
    return signs != 0;
}

// Where a vector's lanes' node indices lie within lanes/2 below and lanes/2 - 1 above its
// middle lane's (a smooth row's usually do), the values of their nodes as four permutes of a
// window of `lanes` consecutive samples of f and of g each, in place of a node load a lane and
// their transpose: the same floats. Otherwise (one lane, the baseline's four, SSE2 having no
// variable permute, or a compiler without GCC's variable shuffles) false.
template <typename U, typename V>
__attribute__((always_inline)) inline bool window_values(const LogAxisTable::Samples& table, const U& index, V* node) {
#if defined(__GNUC__) && !defined(__clang__)
    constexpr int lanes = sizeof(V) / sizeof(float);
    if constexpr (lanes == 8 || lanes == 16) {
        if (!table.permutes) return false;
        // From 0, or wrapped past 2^31 below the window (the rows hold kWindowPad samples past either end).
        const U in_window = index - (lane_everywhere<lanes / 2>(index, std::make_index_sequence<lanes>()) - lanes / 2);
        if (any_lane_at_least(in_window, lanes)) return false;
        const int first = int(index[lanes / 2]) - lanes / 2;
        V f, f_next, g, g_next;
        load(f, table.f_row + first);
        load(f_next, table.f_row + first + 1);
        load(g, table.g_row + first);
        load(g_next, table.g_row + first + 1);
        node[0] = __builtin_shuffle(f, in_window);
        node[1] = __builtin_shuffle(g, in_window);
        node[2] = __builtin_shuffle(f_next, in_window);
        node[3] = __builtin_shuffle(g_next, in_window);
        return true;
    }
#endif
    (void)table, (void)index, (void)node;
    return false;
}

// The lookup of LogAxisTable at the lanes of v (V any number of float lanes, U its uint32
// lanes): one piece of code for vector blocks and scalar tails. (No vector passes through a
// call by value: its ABI would differ with and without AVX.) In two steps: each lane's sample
// and its place within it (t from 0 to 1), then the samples' f and g, interpolated.
template <typename V, typename U>
__attribute__((always_inline)) inline void log_axis_position(const LogAxisTable::Samples& table, V v, U& index, V& t) {
    // Non-negative floats order like their bit patterns; NaN and negatives count as 0.
    v = v > 0.0f ? v : V{} + 0.0f;
    U b;
    std::memcpy(&b, &v, sizeof b);
    b = b < table.first_bits ? U{} + table.first_bits : b;
    b = b > table.last_bits ? U{} + table.last_bits : b;
    b -= table.first_bits;
    index = b >> table.shift;
    // The position within the sample, converted as signed (it is under 2^23; AVX2 converts
    // only signed integers to floats), times 2^-shift.
    using I = typename simd::Lanes<int(sizeof(U) / sizeof(uint32_t))>::I;
    t = __builtin_convertvector(I(b & ((1u << table.shift) - 1)), V) * bits_float((127u - table.shift) << 23);
}

template <typename V, typename U>
__attribute__((always_inline)) inline void log_axis_values(const LogAxisTable::Samples& table, const U& index,
                                                           const V& t, V& v, V* g) {
    V node[4];  // f_i, g_i, f_i+1, g_i+1
    if (!window_values(table, index, node)) node_values<4>(table.nodes, index * 4u, node);
    v = node[0] + t * (node[2] - node[0]);
    if (g) *g = node[1] + t * (node[3] - node[1]);
}

// Both steps: f in place, and g into *g when asked.
template <typename V, typename U>
__attribute__((always_inline)) inline void log_axis_lookup(const LogAxisTable::Samples& table, V& v, V* g) {
    U index;
    V t;
    log_axis_position<V, U>(table, v, index, t);
    log_axis_values<V, U>(table, index, t, v, g);
}

// max(floor, f + g noise), f in v, in place: a density with its grain.
template <typename V>
__attribute__((always_inline)) inline void add_grain(const V& g, const float* noise, float floor, V& v) {
    V n;
    load(n, noise);
    v = v + g * n;
    const V floors = V{} + floor;
    v = v > floors ? v : floors;  // as std::max(floor, v), NaN gives floor: in this form one max instruction
}

// The points a row's kernels take a block at a time, each of their steps a loop over the
// block (the H&D lookups' log_axis_blocks, TetrahedralRow): its rows in and out stay within L1.
constexpr int kRowBlock = 256;

// The lookups of a row, a block of points at a time: each vector's position, then its
// samples' values, each a loop over the block; finish(i, f, g) then takes the values at
// points i ... (g computed where with_g). (In one loop a vector's chain of dependent steps,
// from its exposure through the window's check to the store, was longer than the processor
// overlapped with the next one's: with grain 12-14 % faster with AVX2 on a Zen 3 in most
// runs, 3-16 % on a Xeon, 11-12 % with its AVX-512; without grain, as fast as in one loop
// (0.70 ns a value, Zen 3 AVX2); the same values.)
template <int lanes, typename Finish>
__attribute__((always_inline)) inline void log_axis_blocks(const LogAxisTable::Samples& table, const float* in, int n,
                                                           bool with_g, Finish finish) {
    using V = typename simd::Lanes<lanes>::F;
    using U = typename simd::Lanes<lanes>::U;
    int i = 0;
    while (n - i >= lanes) {
        const int vectors = std::min(n - i, kRowBlock) / lanes;
        U index[kRowBlock / lanes];
        V t[kRowBlock / lanes];
        for (int k = 0; k < vectors; ++k) {
            V v;
            load(v, in + i + k * lanes);
            log_axis_position<V, U>(table, v, index[k], t[k]);
        }
        for (int k = 0; k < vectors; ++k) {
            V v, g{};
            log_axis_values<V, U>(table, index[k], t[k], v, with_g ? &g : nullptr);
            finish(i + k * lanes, v, g);
        }
        i += vectors * lanes;
    }
    for (; i < n; ++i) {
        Float1 lane{in[i]}, g{};
        log_axis_lookup<Float1, Uint1>(table, lane, with_g ? &g : nullptr);
        finish(i, lane, g);
    }
}

// f at a row's points, and g where g_out is given.
struct LogAxisRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(LogAxisTable::Samples table, const float* in, float* out,
                                                   float* g_out, int n) {
        log_axis_blocks<lanes>(table, in, n, g_out != nullptr,
                               [&](int i, const auto& v, const auto& g) __attribute__((always_inline)) {
                                   store(out + i, v);
                                   if (g_out) store(g_out + i, g);
                               });
    }
};

// f with grain at a row's points.
struct LogAxisNoiseRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(LogAxisTable::Samples table, const float* in, const float* noise,
                                                   float floor, float* out, int n) {
        log_axis_blocks<lanes>(table, in, n, true, [&](int i, auto v, const auto& g) __attribute__((always_inline)) {
            add_grain(g, noise + i, floor, v);
            store(out + i, v);
        });
    }
};

}  // namespace

float LogAxisTable::operator()(float v) const {
    Float1 lane{v};
    log_axis_lookup<Float1, Uint1>(samples(), lane, nullptr);
    return lane[0];
}

void LogAxisTable::apply_row(const float* in, float* out, int n) const {
    simd::dispatch<LogAxisRow>(samples(), in, out, (float*)nullptr, n);
}

void LogAxisTable::apply_row(const float* in, float* f_out, float* g_out, int n) const {
    simd::dispatch<LogAxisRow>(samples(), in, f_out, g_out, n);
}

void LogAxisTable::apply_row_with_noise(const float* in, const float* noise, float floor, float* out, int n) const {
    simd::dispatch<LogAxisNoiseRow>(samples(), in, noise, floor, out, n);
}

namespace {

// Zero (either sign) is its own cube root, taken in the vectors: a print table's colours
// compressed to the gamut's faces have many zero channels, which std::cbrt a value at a time
// took as long as the vectors' roots.
struct CubeRoot {
    template <typename D, typename L>
    __attribute__((always_inline)) static void apply(const D& v, D& root) {
        cube_root_lanes<D, L>(v, root);
        root = v == 0.0 ? v : root;
    }
};

}  // namespace

void cube_root_row(const double* in, double* out, int n) {
    simd::map_doubles<CubeRoot>(in, out, n);
    for (int i = 0; i < n; ++i)
        if (!(in[i] >= std::numeric_limits<double>::min() && in[i] <= std::numeric_limits<double>::max()) &&
            in[i] != 0.0)
            out[i] = std::cbrt(in[i]);
}

Table3D::Table3D(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int nodes, Encoding encoding)
    : nodes_(nodes), lo_given_(lo), hi_given_(hi), cubed_(encoding == Encoding::cube_root) {
    for (int a = 0; a < 3; ++a) {
        lo_[a] = float(lo[a]);
        scale_[a] = float(1.0 / ((hi[a] - lo[a]) / (nodes - 1)));  // 1 / the node spacing
    }
    values_.resize(size_t(nodes) * nodes * nodes);
}

Table3D::Table3D(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int nodes, int threads,
                 const Function& f, Encoding encoding)
    : Table3D(lo, hi, nodes, encoding) {
    fill(threads, [&](int j, int k, double* out) {
        for (int i = 0; i < nodes; ++i) {
            const int node[3] = {i, j, k};
            double in[3];
            for (int a = 0; a < 3; ++a) in[a] = node_coordinate(lo[a], hi[a], nodes, node[a]);
            f(node, in, out + 3 * i);
        }
    });
}

Table3D Table3D::by_rows(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int nodes, int threads,
                         const RowFunction& f, Encoding encoding) {
    Table3D table(lo, hi, nodes, encoding);
    table.fill(threads, f);
    return table;
}

void Table3D::fill(int threads, const RowFunction& f) {
    // The planes of nodes along z shared among the threads, a row of nodes at a time.
    parallel_for(0, nodes_, threads, [&](int k_begin, int k_end) {
        std::vector<double> row(3 * size_t(nodes_)), roots(3 * size_t(nodes_));
        for (int k = k_begin; k < k_end; ++k)
            for (int j = 0; j < nodes_; ++j) {
                f(j, k, row.data());
                if (cubed_) cube_root_row(row.data(), roots.data(), 3 * nodes_);
                const std::vector<double>& value = cubed_ ? roots : row;
                for (int i = 0; i < nodes_; ++i)
                    values_[(size_t(k) * nodes_ + j) * nodes_ + i] = {float(value[3 * size_t(i)]),
                                                                       float(value[3 * size_t(i) + 1]),
                                                                       float(value[3 * size_t(i) + 2]), 0.0f};
            }
    });
}

namespace {

// Tetrahedral interpolation of `values` (4 floats per node, 3 values and a pad, x fastest) at the points of
// in[a][i .. i + lanes) into out[c][i ...), lanes the width of the vector type V (one float or more): one piece
// of code for the vector blocks and the scalar tail, so both compute the same values.
// The cell is split along its main diagonal into six tetrahedra; the one holding the point
// is walked from corner 000 to 111 one axis at a time, largest fraction first:
//   f = (1 - t_max) f000 + (t_max - t_mid) f_a + (t_mid - t_min) f_ab + t_min f111
// (Kasson, Nin, Plouffe & Hafner, "Performing color space conversions with three-dimensional
// linear interpolation", J. Electronic Imaging 4(3), 1995). Exact for linear functions,
// continuous across cells, and four corner loads per channel where trilinear needs eight.
// In two steps (TetrahedralRow runs them as loops of their own). First the cell and
// tetrahedron of each lane's point: the offsets (in floats) of its corners 000, a and ab (111
// is 000's plus the diagonal), and the four corners' weights.
template <typename V, typename I>
__attribute__((always_inline)) inline void cell_weights(int nodes, const float* lo, const float* scale,
                                                        const float* const* in, int i, I* corner, V* w) {
    I index[3];
    V t[3];
    // (The bounds as vectors, each held in its selection as it is compared: one min instruction.)
    const V last_node = V{} + float(nodes - 1);
    const I last_cell = I{} + (nodes - 2);
    for (int a = 0; a < 3; ++a) {
        V u;
        load(u, in[a] + i);
        u = (u - lo[a]) * scale[a];
        u = u >= 0.0f ? u : V{} + 0.0f;  // NaN too: a density that is not a number reads the grid's first node
        u = u < last_node ? u : last_node;
        index[a] = __builtin_convertvector(u, I);
        index[a] = index[a] < last_cell ? index[a] : last_cell;
        t[a] = u - __builtin_convertvector(index[a], V);
    }
    const I base = ((index[2] * nodes + index[1]) * nodes + index[0]) * 4;
    const int step[3] = {4, 4 * nodes, 4 * nodes * nodes};  // node offsets along x, y, z
    // The axes by their fractions: a the largest, c the smallest (ties in axis order; the
    // tetrahedra share the faces where fractions tie, so either choice gives the same value).
    // In integer arithmetic on the fractions' bit patterns (non-negative floats order as
    // integers): -1 where a >= b, else 0, and a choice by such a mask. (GCC does
    // comparisons whose results select between vectors lane by lane for AVX-512.)
    I bits[3];
    std::memcpy(bits, t, sizeof bits);
    auto at_least = [](const I& a, const I& b) { return ~((a - b) >> 31); };
    auto pick = [](const I& mask, const I& a, const I& b) { return b ^ ((a ^ b) & mask); };
    const I x_ge_y = at_least(bits[0], bits[1]), x_ge_z = at_least(bits[0], bits[2]), y_ge_z = at_least(bits[1], bits[2]);
    const I along_x = I{} + step[0], along_y = I{} + step[1], along_z = I{} + step[2];
    const I off_a = pick(x_ge_y & x_ge_z, along_x, pick(y_ge_z, along_y, along_z));
    const I off_c = pick(~x_ge_y & ~x_ge_z, along_x, pick(y_ge_z, along_z, along_y));
    const V max_xy = t[0] > t[1] ? t[0] : t[1], min_xy = t[0] < t[1] ? t[0] : t[1];
    const V t_max = max_xy > t[2] ? max_xy : t[2], t_min = min_xy < t[2] ? min_xy : t[2];
    const V below_max = max_xy < t[2] ? max_xy : t[2];
    const V t_mid = min_xy > below_max ? min_xy : below_max;
    const int diagonal = step[0] + step[1] + step[2];
    corner[0] = base, corner[1] = base + off_a, corner[2] = base + (diagonal - off_c);
    w[0] = 1.0f - t_max, w[1] = t_max - t_mid, w[2] = t_mid - t_min, w[3] = t_min;
}

// Then each lane's four corners' values weighted and summed (and cubed, kCubed), into out[c] + i.
template <typename V, typename I, bool kCubed>
__attribute__((always_inline)) inline void corner_sums(const float* values, int nodes, const I* corner, const V* w,
                                                       float* const* out, int i) {
    const int diagonal = 4 * (1 + nodes + nodes * nodes);
    V v000[3], v_a[3], v_ab[3], v111[3];
    node_values<3>(values, corner[0], v000);
    node_values<3>(values, corner[1], v_a);
    node_values<3>(values, corner[2], v_ab);
    node_values<3>(values + diagonal, corner[0], v111);
    for (int c = 0; c < 3; ++c) {
        const V v = w[0] * v000[c] + w[1] * v_a[c] + w[2] * v_ab[c] + w[3] * v111[c];
        store(out[c] + i, kCubed ? v * v * v : v);
    }
}

// Both steps.
template <typename V, typename I, bool kCubed>
__attribute__((always_inline)) inline void tetrahedral(const float* values, int nodes, const float* lo,
                                                       const float* scale, const float* const* in, float* const* out,
                                                       int i) {
    I corner[3];
    V w[4];
    cell_weights<V, I>(nodes, lo, scale, in, i, corner, w);
    corner_sums<V, I, kCubed>(values, nodes, corner, w, out, i);
}

// The table at a row of points, a block of points at a time: each vector's cell and
// weights, then its corners' sum, each a loop over the block. (In one loop a point's chain of
// dependent steps, from its coordinates to the store, was longer than the processor could
// overlap with the next point's: the weights apart 13-15 % faster with AVX2 on a Zen 3, 25 %
// on a Xeon, 11-25 % with its AVX-512; the same values.)
struct TetrahedralRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* values, int nodes, const float* lo, const float* scale,
                                                   bool cubed, const float* const* in, float* const* out, int n) {
        if (cubed)
            blocks<lanes, true>(values, nodes, lo, scale, in, out, n);
        else
            blocks<lanes, false>(values, nodes, lo, scale, in, out, n);
    }
    template <int lanes, bool kCubed>
    __attribute__((always_inline)) static void blocks(const float* values, int nodes, const float* lo,
                                                      const float* scale, const float* const* in, float* const* out,
                                                      int n) {
        using V = typename simd::Lanes<lanes>::F;
        using I = typename simd::Lanes<lanes>::I;
        for (int begin = 0; begin < n; begin += kRowBlock) {
            const int end = std::min(n, begin + kRowBlock);
            const int vectors = (end - begin) / lanes;
            I corner[kRowBlock / lanes][3];
            V w[kRowBlock / lanes][4];
            for (int k = 0; k < vectors; ++k) cell_weights<V, I>(nodes, lo, scale, in, begin + k * lanes, corner[k], w[k]);
            for (int k = 0; k < vectors; ++k)
                corner_sums<V, I, kCubed>(values, nodes, corner[k], w[k], out, begin + k * lanes);
            for (int i = begin + vectors * lanes; i < end; ++i)
                tetrahedral<Float1, Int1, kCubed>(values, nodes, lo, scale, in, out, i);
        }
    }
};

}  // namespace

void Table3D::operator()(const float* in, float* out) const {
    const float* in_rows[3] = {&in[0], &in[1], &in[2]};
    float* out_rows[3] = {&out[0], &out[1], &out[2]};
    if (cubed_)
        tetrahedral<Float1, Int1, true>(&values_[0][0], nodes_, lo_.data(), scale_.data(), in_rows, out_rows, 0);
    else
        tetrahedral<Float1, Int1, false>(&values_[0][0], nodes_, lo_.data(), scale_.data(), in_rows, out_rows, 0);
}

void Table3D::apply_row(const float* const* in, float* const* out, int n) const {
    simd::dispatch<TetrahedralRow>(&values_[0][0], nodes_, lo_.data(), scale_.data(), cubed_, in, out, n);
}

}  // namespace darkroom
