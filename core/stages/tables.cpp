#include "core/stages/tables.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

using simd::Float1;
using simd::Float8;
using simd::Int1;
using simd::Int8;
using simd::load;
using simd::store;
using simd::Uint1;
using simd::Uint8;

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
}

namespace {

// The four values of the 16-byte node at each lane's offset (in floats) into v[0..components).
// Eight lanes load each node whole and transpose them in registers (four nodes per 128-bit
// half), where lane-by-lane loads would insert the values one at a time; both load the same
// floats.
template <int components, typename V, typename I>
__attribute__((always_inline)) inline void node_values(const float* values, const I& offset, V* v) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    if constexpr (lanes == 8) {
        simd::Float4 n[8];
        for (int k = 0; k < 8; ++k) load(n[k], values + offset[k]);
        // Lanes k and k + 4 side by side: [a b c d | a b c d].
        const V p0 = __builtin_shufflevector(n[0], n[4], 0, 1, 2, 3, 4, 5, 6, 7);
        const V p1 = __builtin_shufflevector(n[1], n[5], 0, 1, 2, 3, 4, 5, 6, 7);
        const V p2 = __builtin_shufflevector(n[2], n[6], 0, 1, 2, 3, 4, 5, 6, 7);
        const V p3 = __builtin_shufflevector(n[3], n[7], 0, 1, 2, 3, 4, 5, 6, 7);
        const V ab01 = __builtin_shufflevector(p0, p1, 0, 8, 1, 9, 4, 12, 5, 13);  // a0 a1 b0 b1 | a4 a5 b4 b5
        const V cd01 = __builtin_shufflevector(p0, p1, 2, 10, 3, 11, 6, 14, 7, 15);
        const V ab23 = __builtin_shufflevector(p2, p3, 0, 8, 1, 9, 4, 12, 5, 13);
        const V cd23 = __builtin_shufflevector(p2, p3, 2, 10, 3, 11, 6, 14, 7, 15);
        v[0] = __builtin_shufflevector(ab01, ab23, 0, 1, 8, 9, 4, 5, 12, 13);
        v[1] = __builtin_shufflevector(ab01, ab23, 2, 3, 10, 11, 6, 7, 14, 15);
        v[2] = __builtin_shufflevector(cd01, cd23, 0, 1, 8, 9, 4, 5, 12, 13);
        if constexpr (components == 4) v[3] = __builtin_shufflevector(cd01, cd23, 2, 3, 10, 11, 6, 7, 14, 15);
    } else {
        for (int c = 0; c < components; ++c)
            for (int k = 0; k < lanes; ++k) v[c][k] = values[offset[k] + c];
    }
}

// The lookup of LogAxisTable at the lanes of v: f in place, and g into *g when asked (V
// one float or eight, U its uint32 lanes): one piece of code for vector blocks and scalar
// tails. (No vector passes through a call by value: its ABI would differ with and without AVX.)
template <typename V, typename U>
__attribute__((always_inline)) inline void log_axis_lookup(const float* nodes, uint32_t first_bits,
                                                           uint32_t last_bits, int shift, V& v, V* g) {
    // Non-negative floats order like their bit patterns; NaN and negatives count as 0.
    v = v > 0.0f ? v : V{} + 0.0f;
    U b;
    std::memcpy(&b, &v, sizeof b);
    b = b < first_bits ? U{} + first_bits : b;
    b = b > last_bits ? U{} + last_bits : b;
    b -= first_bits;
    const U offset = (b >> shift) * 4u;
    const V t = __builtin_convertvector(b & ((1u << shift) - 1), V) * bits_float((127u - shift) << 23);  // * 2^-shift
    V node[4];  // f_i, g_i, f_i+1, g_i+1
    node_values<4>(nodes, offset, node);
    v = node[0] + t * (node[2] - node[0]);
    if (g) *g = node[1] + t * (node[3] - node[1]);
}

}  // namespace

float LogAxisTable::operator()(float v) const {
    Float1 lane{v};
    log_axis_lookup<Float1, Uint1>(&nodes_[0][0], first_bits_, last_bits_, shift_, lane, nullptr);
    return lane[0];
}

// The vector loops are free functions: clang 14 does not clone member functions. g_out may
// be null (f only).
__attribute__((target_clones("avx2", "default"))) void log_axis_row(const float* nodes, uint32_t first_bits,
                                                                     uint32_t last_bits, int shift, const float* in,
                                                                     float* out, float* g_out, int n) {
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        Float8 v, g{};
        load(v, in + i);
        log_axis_lookup<Float8, Uint8>(nodes, first_bits, last_bits, shift, v, g_out ? &g : nullptr);
        store(out + i, v);
        if (g_out) store(g_out + i, g);
    }
    for (; i < n; ++i) {
        Float1 lane{in[i]}, g{};
        log_axis_lookup<Float1, Uint1>(nodes, first_bits, last_bits, shift, lane, g_out ? &g : nullptr);
        out[i] = lane[0];
        if (g_out) g_out[i] = g[0];
    }
}

void LogAxisTable::apply_row(const float* in, float* out, int n) const {
    log_axis_row(&nodes_[0][0], first_bits_, last_bits_, shift_, in, out, nullptr, n);
}

void LogAxisTable::apply_row(const float* in, float* f_out, float* g_out, int n) const {
    log_axis_row(&nodes_[0][0], first_bits_, last_bits_, shift_, in, f_out, g_out, n);
}

namespace {

// 2^x at the lanes of x, in place (V one float or eight, I its int32 lanes): one piece of
// code for fast_exp2 and the vector blocks of fast_exp2_row.
template <typename V, typename I>
__attribute__((always_inline)) inline void exp2_in_place(V& x) {
    x = x < -126.0f ? V{} - 126.0f : x;
    x = x > 126.0f ? V{} + 126.0f : x;
    const I whole = __builtin_convertvector(x + (x >= 0.0f ? V{} + 0.5f : V{} - 0.5f), I);  // nearest, by truncation
    const V f = (x - __builtin_convertvector(whole, V)) * 0.69314718f;  // |f| <= ln2 / 2: e^f to f^6
    const V p = 1.0f + f * (1.0f + f * (0.5f + f * (1.0f / 6 + f * (1.0f / 24 + f * (1.0f / 120 + f * (1.0f / 720))))));
    const I scale_bits = (whole + 127) << 23;
    V scale;
    std::memcpy(&scale, &scale_bits, sizeof scale);
    x = p * scale;
}

}  // namespace

float fast_exp2(float x) {
    Float1 lane{x};
    exp2_in_place<Float1, Int1>(lane);
    return lane[0];
}

// Eight values at a time (GCC vector types; AVX2 where the processor has it).
__attribute__((target_clones("avx2", "default"))) void fast_exp2_row(float* values, int n) {
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        Float8 x;
        load(x, values + i);
        exp2_in_place<Float8, Int8>(x);
        store(values + i, x);
    }
    for (; i < n; ++i) values[i] = fast_exp2(values[i]);
}

Table3D::Table3D(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int nodes, const Function& f)
    : nodes_(nodes) {
    std::array<double, 3> step;
    for (int a = 0; a < 3; ++a) {
        step[a] = (hi[a] - lo[a]) / (nodes - 1);
        lo_[a] = float(lo[a]);
        scale_[a] = float(1.0 / step[a]);
    }
    values_.resize(size_t(nodes) * nodes * nodes);
    for (int k = 0; k < nodes; ++k)
        for (int j = 0; j < nodes; ++j)
            for (int i = 0; i < nodes; ++i) {
                double in[3] = {lo[0] + i * step[0], lo[1] + j * step[1], lo[2] + k * step[2]}, out[3];
                f(in, out);
                values_[(size_t(k) * nodes + j) * nodes + i] = {float(out[0]), float(out[1]), float(out[2]), 0.0f};
            }
}

namespace {

// Tetrahedral interpolation of `values` (4 floats per node, 3 values and a pad, x fastest) at the points of
// in[a][0 .. lanes), lanes the width of the vector type V (one float or eight): one piece
// of code for the vector blocks and the scalar tail, so both compute the same values.
// The cell is split along its main diagonal into six tetrahedra; the one holding the point
// is walked from corner 000 to 111 one axis at a time, largest fraction first:
//   f = (1 - t_max) f000 + (t_max - t_mid) f_a + (t_mid - t_min) f_ab + t_min f111
// (Kasson, Nin, Plouffe & Hafner, "Performing color space conversions with three-dimensional
// linear interpolation", J. Electronic Imaging 4(3), 1995). Exact for linear functions,
// continuous across cells, and four corner loads per channel where trilinear needs eight.
template <typename V, typename I>
__attribute__((always_inline)) inline void tetrahedral(const float* values, int nodes, const float* lo,
                                                       const float* scale, const float* const* in, float* const* out) {
    I index[3];
    V t[3];
    for (int a = 0; a < 3; ++a) {
        V u;
        load(u, in[a]);
        u = (u - lo[a]) * scale[a];
        u = u >= 0.0f ? u : V{} + 0.0f;  // NaN too: a density that is not a number reads the grid's first node
        u = u > float(nodes - 1) ? V{} + float(nodes - 1) : u;
        index[a] = __builtin_convertvector(u, I);
        index[a] = index[a] > nodes - 2 ? I{} + (nodes - 2) : index[a];
        t[a] = u - __builtin_convertvector(index[a], V);
    }
    const I base = ((index[2] * nodes + index[1]) * nodes + index[0]) * 4;
    const int step[3] = {4, 4 * nodes, 4 * nodes * nodes};  // node offsets along x, y, z
    // The axes by their fractions: a the largest, c the smallest (ties in axis order; the
    // tetrahedra share the faces where fractions tie, so either choice gives the same value).
    const I x_ge_y = t[0] >= t[1], x_ge_z = t[0] >= t[2], y_ge_z = t[1] >= t[2];
    const I off_a = x_ge_y & x_ge_z ? I{} + step[0] : (y_ge_z ? I{} + step[1] : I{} + step[2]);
    const I off_c = ~x_ge_y & ~x_ge_z ? I{} + step[0] : (y_ge_z ? I{} + step[2] : I{} + step[1]);
    const V max_xy = t[0] > t[1] ? t[0] : t[1], min_xy = t[0] < t[1] ? t[0] : t[1];
    const V t_max = max_xy > t[2] ? max_xy : t[2], t_min = min_xy < t[2] ? min_xy : t[2];
    const V below_max = max_xy < t[2] ? max_xy : t[2];
    const V t_mid = min_xy > below_max ? min_xy : below_max;
    const int diagonal = step[0] + step[1] + step[2];
    V v000[3], v_a[3], v_ab[3], v111[3];
    node_values<3>(values, base, v000);
    node_values<3>(values, base + off_a, v_a);
    node_values<3>(values, base + (diagonal - off_c), v_ab);
    node_values<3>(values, base + diagonal, v111);
    const V w000 = 1.0f - t_max, w_a = t_max - t_mid, w_ab = t_mid - t_min;
    for (int c = 0; c < 3; ++c) {
        const V result = w000 * v000[c] + w_a * v_a[c] + w_ab * v_ab[c] + t_min * v111[c];
        store(out[c], result);
    }
}

}  // namespace

void Table3D::operator()(const float* in, float* out) const {
    const float* in_rows[3] = {&in[0], &in[1], &in[2]};
    float* out_rows[3] = {&out[0], &out[1], &out[2]};
    tetrahedral<Float1, Int1>(&values_[0][0], nodes_, lo_.data(), scale_.data(), in_rows, out_rows);
}

__attribute__((target_clones("avx2", "default"))) void tetrahedral_row(const float* values, int nodes, const float* lo,
                                                                      const float* scale, const float* const* in,
                                                                      float* const* out, int n) {
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const float* in_rows[3] = {in[0] + i, in[1] + i, in[2] + i};
        float* out_rows[3] = {out[0] + i, out[1] + i, out[2] + i};
        tetrahedral<Float8, Int8>(values, nodes, lo, scale, in_rows, out_rows);
    }
    for (; i < n; ++i) {
        const float* in_rows[3] = {in[0] + i, in[1] + i, in[2] + i};
        float* out_rows[3] = {out[0] + i, out[1] + i, out[2] + i};
        tetrahedral<Float1, Int1>(values, nodes, lo, scale, in_rows, out_rows);
    }
}

void Table3D::apply_row(const float* const* in, float* const* out, int n) const {
    tetrahedral_row(&values_[0][0], nodes_, lo_.data(), scale_.data(), in, out, n);
}

}  // namespace darkroom
