#include "core/stages/tables.h"

#include <algorithm>
#include <cmath>
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

float LogAxisTable::operator()(float v) const {
    // Non-negative floats order like their bit patterns; NaN and negatives count as 0.
    const uint32_t b = std::clamp(float_bits(v > 0.0f ? v : 0.0f), first_bits_, last_bits_) - first_bits_;
    const uint32_t i = b >> shift_;
    const float t = float(b & ((1u << shift_) - 1)) * bits_float((127u - shift_) << 23);  // * 2^-shift
    return samples_[i] + t * (samples_[i + 1] - samples_[i]);
}

float fast_exp2(float x) {
    x = std::clamp(x, -126.0f, 126.0f);
    const int whole = int(x + (x >= 0.0f ? 0.5f : -0.5f));  // nearest, by truncation (inline)
    const float f = (x - float(whole)) * 0.69314718f;       // |f| <= ln2 / 2: e^f to f^6
    const float p =
        1.0f + f * (1.0f + f * (0.5f + f * (1.0f / 6 + f * (1.0f / 24 + f * (1.0f / 120 + f * (1.0f / 720))))));
    return p * bits_float(uint32_t(whole + 127) << 23);
}

// The same operations as fast_exp2, eight values at a time (GCC vector types; AVX2 where
// the processor has it).
__attribute__((target_clones("avx2", "default"))) void fast_exp2_row(float* values, int n) {
    using Vec = float __attribute__((vector_size(32)));
    using Int = int32_t __attribute__((vector_size(32)));
    constexpr int kLanes = 8;
    int i = 0;
    for (; i + kLanes <= n; i += kLanes) {
        Vec x;
        std::memcpy(&x, values + i, sizeof x);
        x = x < -126.0f ? Vec{} - 126.0f : x;
        x = x > 126.0f ? Vec{} + 126.0f : x;
        const Int whole = __builtin_convertvector(x + (x >= 0.0f ? Vec{} + 0.5f : Vec{} - 0.5f), Int);
        const Vec f = (x - __builtin_convertvector(whole, Vec)) * 0.69314718f;
        const Vec p = 1.0f + f * (1.0f + f * (0.5f + f * (1.0f / 6 + f * (1.0f / 24 + f * (1.0f / 120 + f * (1.0f / 720))))));
        const Int scale_bits = (whole + 127) << 23;
        Vec scale;
        std::memcpy(&scale, &scale_bits, sizeof scale);
        const Vec result = p * scale;
        std::memcpy(values + i, &result, sizeof result);
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

void Table3D::operator()(const float* in, float* out) const {
    int index[3];
    float t[3];
    for (int a = 0; a < 3; ++a) {
        float u = std::clamp((in[a] - lo_[a]) * scale_[a], 0.0f, float(nodes_ - 1));
        index[a] = std::min(int(u), nodes_ - 2);
        t[a] = u - float(index[a]);
    }
    const size_t n = size_t(nodes_), base = (index[2] * n + index[1]) * n + index[0];
    const std::array<float, 3>* v = &values_[base];
    const size_t dy = n, dz = n * n;
    for (int c = 0; c < 3; ++c) {
        float x00 = v[0][c] + t[0] * (v[1][c] - v[0][c]);
        float x10 = v[dy][c] + t[0] * (v[dy + 1][c] - v[dy][c]);
        float x01 = v[dz][c] + t[0] * (v[dz + 1][c] - v[dz][c]);
        float x11 = v[dz + dy][c] + t[0] * (v[dz + dy + 1][c] - v[dz + dy][c]);
        float y0 = x00 + t[1] * (x10 - x00), y1 = x01 + t[1] * (x11 - x01);
        out[c] = y0 + t[2] * (y1 - y0);
    }
}

}  // namespace darkroom
