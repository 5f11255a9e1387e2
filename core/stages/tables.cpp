#include "core/stages/tables.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

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

LogAxisTable::LogAxisTable(const Curve& curve, int mantissa_bits) : shift_(23 - mantissa_bits) {
    const uint32_t step = 1u << shift_;
    first_bits_ = float_bits(positive_float(curve.x_min())) & ~(step - 1);
    last_bits_ = (float_bits(positive_float(curve.x_max())) + step - 1) & ~(step - 1);
    const uint32_t samples = ((last_bits_ - first_bits_) >> shift_) + 1;
    samples_.resize(samples + 1);
    for (uint32_t i = 0; i < samples; ++i)
        samples_[i] = float(curve(std::log10(double(bits_float(first_bits_ + (i << shift_))))));
    samples_[samples] = samples_[samples - 1];  // so the last sample interpolates to itself
}

namespace {

// The lookup of LogAxisTable at the lanes of v, in place (V one float or eight, U its
// uint32 lanes): one piece of code for vector blocks and scalar tails. (No vector passes
// through a call by value: its ABI would differ with and without AVX.)
template <typename V, typename U>
__attribute__((always_inline)) inline void log_axis_lookup(const float* samples, uint32_t first_bits,
                                                           uint32_t last_bits, int shift, V& v) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    // Non-negative floats order like their bit patterns; NaN and negatives count as 0.
    v = v > 0.0f ? v : V{} + 0.0f;
    U b;
    std::memcpy(&b, &v, sizeof b);
    b = b < first_bits ? U{} + first_bits : b;
    b = b > last_bits ? U{} + last_bits : b;
    b -= first_bits;
    const U i = b >> shift;
    const V t = __builtin_convertvector(b & ((1u << shift) - 1), V) * bits_float((127u - shift) << 23);  // * 2^-shift
    V lower, upper;
    for (int k = 0; k < lanes; ++k) lower[k] = samples[i[k]], upper[k] = samples[i[k] + 1];
    v = lower + t * (upper - lower);
}

using Float1 = float __attribute__((vector_size(4)));
using Bits1 = uint32_t __attribute__((vector_size(4)));

}  // namespace

float LogAxisTable::operator()(float v) const {
    Float1 lane{v};
    log_axis_lookup<Float1, Bits1>(samples_.data(), first_bits_, last_bits_, shift_, lane);
    return lane[0];
}

// The vector loops are free functions: clang 14 does not clone member functions.
__attribute__((target_clones("avx2", "default"))) void log_axis_row(const float* samples, uint32_t first_bits,
                                                                     uint32_t last_bits, int shift, const float* in,
                                                                     float* out, int n) {
    using Float8 = float __attribute__((vector_size(32)));
    using Bits8 = uint32_t __attribute__((vector_size(32)));
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        Float8 v;
        std::memcpy(&v, in + i, sizeof v);
        log_axis_lookup<Float8, Bits8>(samples, first_bits, last_bits, shift, v);
        std::memcpy(out + i, &v, sizeof v);
    }
    for (; i < n; ++i) {
        Float1 lane{in[i]};
        log_axis_lookup<Float1, Bits1>(samples, first_bits, last_bits, shift, lane);
        out[i] = lane[0];
    }
}

void LogAxisTable::apply_row(const float* in, float* out, int n) const {
    log_axis_row(samples_.data(), first_bits_, last_bits_, shift_, in, out, n);
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

using Exp2Lane = float __attribute__((vector_size(4)));
using Exp2Index = int32_t __attribute__((vector_size(4)));

}  // namespace

float fast_exp2(float x) {
    Exp2Lane lane{x};
    exp2_in_place<Exp2Lane, Exp2Index>(lane);
    return lane[0];
}

// Eight values at a time (GCC vector types; AVX2 where the processor has it).
__attribute__((target_clones("avx2", "default"))) void fast_exp2_row(float* values, int n) {
    using Vec = float __attribute__((vector_size(32)));
    using Int = int32_t __attribute__((vector_size(32)));
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        Vec x;
        std::memcpy(&x, values + i, sizeof x);
        exp2_in_place<Vec, Int>(x);
        std::memcpy(values + i, &x, sizeof x);
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
                for (int c = 0; c < 3; ++c) values_[(size_t(k) * nodes + j) * nodes + i][c] = float(out[c]);
            }
}

namespace {

// Trilinear interpolation of `values` (3 floats per node, x fastest) at the points of
// in[a][0 .. lanes), lanes the width of the vector type V (one float or eight): one piece
// of code for the vector blocks and the scalar tail, so both compute the same values.
template <typename V, typename I>
__attribute__((always_inline)) inline void trilinear(const float* values, int nodes, const float* lo,
                                                     const float* scale, const float* const* in, float* const* out) {
    constexpr int lanes = sizeof(V) / sizeof(float);
    I index[3];
    V t[3];
    for (int a = 0; a < 3; ++a) {
        V u;
        std::memcpy(&u, in[a], sizeof u);
        u = (u - lo[a]) * scale[a];
        u = u >= 0.0f ? u : V{} + 0.0f;  // NaN too: a density that is not a number reads the grid's first node
        u = u > float(nodes - 1) ? V{} + float(nodes - 1) : u;
        index[a] = __builtin_convertvector(u, I);
        index[a] = index[a] > nodes - 2 ? I{} + (nodes - 2) : index[a];
        t[a] = u - __builtin_convertvector(index[a], V);
    }
    const I base = ((index[2] * nodes + index[1]) * nodes + index[0]) * 3;
    const int dy = 3 * nodes, dz = 3 * nodes * nodes;
    auto corner = [&](V& v, int offset, int c) {
        for (int k = 0; k < lanes; ++k) v[k] = values[base[k] + offset + c];
    };
    for (int c = 0; c < 3; ++c) {
        V v000, v100, v010, v110, v001, v101, v011, v111;
        corner(v000, 0, c), corner(v100, 3, c), corner(v010, dy, c), corner(v110, dy + 3, c);
        corner(v001, dz, c), corner(v101, dz + 3, c), corner(v011, dz + dy, c), corner(v111, dz + dy + 3, c);
        const V x00 = v000 + t[0] * (v100 - v000), x10 = v010 + t[0] * (v110 - v010);
        const V x01 = v001 + t[0] * (v101 - v001), x11 = v011 + t[0] * (v111 - v011);
        const V y0 = x00 + t[1] * (x10 - x00), y1 = x01 + t[1] * (x11 - x01);
        const V result = y0 + t[2] * (y1 - y0);
        std::memcpy(out[c], &result, sizeof result);
    }
}

using Lane1 = float __attribute__((vector_size(4)));
using Index1 = int32_t __attribute__((vector_size(4)));

}  // namespace

void Table3D::operator()(const float* in, float* out) const {
    const float* in_rows[3] = {&in[0], &in[1], &in[2]};
    float* out_rows[3] = {&out[0], &out[1], &out[2]};
    trilinear<Lane1, Index1>(&values_[0][0], nodes_, lo_.data(), scale_.data(), in_rows, out_rows);
}

__attribute__((target_clones("avx2", "default"))) void trilinear_row(const float* values, int nodes, const float* lo,
                                                                      const float* scale, const float* const* in,
                                                                      float* const* out, int n) {
    using Lane8 = float __attribute__((vector_size(32)));
    using Index8 = int32_t __attribute__((vector_size(32)));
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const float* in_rows[3] = {in[0] + i, in[1] + i, in[2] + i};
        float* out_rows[3] = {out[0] + i, out[1] + i, out[2] + i};
        trilinear<Lane8, Index8>(values, nodes, lo, scale, in_rows, out_rows);
    }
    for (; i < n; ++i) {
        const float* in_rows[3] = {in[0] + i, in[1] + i, in[2] + i};
        float* out_rows[3] = {out[0] + i, out[1] + i, out[2] + i};
        trilinear<Lane1, Index1>(values, nodes, lo, scale, in_rows, out_rows);
    }
}

void Table3D::apply_row(const float* const* in, float* const* out, int n) const {
    trilinear_row(&values_[0][0], nodes_, lo_.data(), scale_.data(), in, out, n);
}

}  // namespace darkroom
