// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "core/random.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/simd.h"

namespace darkroom {

// Quantiles z_i of the standard normal at (i + 0.5) / 2^16, by Newton's method on
// Phi(z) = erfc(-z/sqrt 2)/2, then scaled so the table's variance is exactly 1.
const float* normal_quantile_table() {
    static const std::vector<float> table = [] {
        const int n = 1 << 16;
        std::vector<double> z(n);
        for (int i = 0; i < n / 2; ++i) {
            // From 0, right of every root in the convex half z < 0: Newton converges monotonically.
            double p = (i + 0.5) / n, x = 0.0;
            for (int iteration = 0; iteration < 60; ++iteration) {
                double phi = 0.5 * std::erfc(-x / std::sqrt(2.0));
                double density = std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI);
                double step = (phi - p) / density;
                x -= step;
                if (std::abs(step) < 1e-14) break;
            }
            z[i] = x;
            z[n - 1 - i] = -x;
        }
        double variance = 0;
        for (double v : z) variance += v * v;
        variance /= n;
        std::vector<float> scaled(n);
        for (int i = 0; i < n; ++i) scaled[i] = float(z[i] / std::sqrt(variance));
        return scaled;
    }();
    return table.data();
}

namespace {

// The hashes in vectors of `lanes`, then one at a time; the quantiles looked up per lane
// (the indices through memory: a scalar load of each is cheaper than extracting it).
struct QuantileNormalRun {
    template <int lanes>
    __attribute__((always_inline)) static void run(uint32_t row_hash, int x0, int n, float* out) {
        using U = typename simd::Lanes<lanes>::U;
        const float* table = normal_quantile_table();
        U lane;
        for (int k = 0; k < lanes; ++k) lane[k] = uint32_t(k);
        int i = 0;
        for (; i + lanes <= n; i += lanes) {
            U h = uint32_t(x0 + i) + lane;
            mix32_in_place(h);
            h ^= row_hash;
            mix32_in_place(h);
            uint32_t index[lanes];
            simd::store_for_lanes(index, h >> 16);
            for (int k = 0; k < lanes; ++k) out[i + k] = table[index[k]];
        }
        for (; i < n; ++i) out[i] = table[mix32(row_hash ^ mix32(uint32_t(x0 + i))) >> 16];
    }
};

}  // namespace

void quantile_normal_run(uint32_t row_hash, int x0, int n, float* out) {
    simd::dispatch<QuantileNormalRun>(row_hash, x0, n, out);
}

}  // namespace darkroom
