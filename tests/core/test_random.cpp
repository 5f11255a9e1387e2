#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "core/random.h"

using namespace darkroom;

TEST_CASE("Philox4x32-10 matches the published known-answer vectors", "[random]") {
    // Random123 kat_vectors (Salmon et al. 2011): philox4x32 10 rounds.
    CHECK(philox4x32_10({0, 0, 0, 0}, 0, 0) == Philox4x32{0x6627e8d5u, 0xe169c58du, 0xbc57ac4cu, 0x9b00dbd8u});
    CHECK(philox4x32_10({0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu}, 0xffffffffu, 0xffffffffu) ==
          Philox4x32{0x408f276du, 0x41c83b0eu, 0xa20bc7c6u, 0x6d5451fdu});
    CHECK(philox4x32_10({0x243f6a88u, 0x85a308d3u, 0x13198a2eu, 0x03707344u}, 0xa4093822u, 0x299f31d0u) ==
          Philox4x32{0xd16cfe09u, 0x94fdccebu, 0x5001e420u, 0x24126ea1u});
}

TEST_CASE("normal draws are a pure function of key and pixel, with unit variance", "[random]") {
    NoiseKey key{42, 7, 1};
    CHECK(standard_normal(key, 10, 20) == standard_normal(key, 10, 20));
    CHECK(standard_normal(key, 10, 20) != standard_normal(NoiseKey{42, 8, 1}, 10, 20));
    CHECK(standard_normal(key, 10, 20) != standard_normal(NoiseKey{42, 7, 2}, 10, 20));
    double sum = 0, sum2 = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        double v = standard_normal(key, i % 1000, i / 1000);
        sum += v, sum2 += v * v;
    }
    double mean = sum / n, var = sum2 / n - mean * mean;
    CHECK(std::abs(mean) < 5.0 / std::sqrt(n));
    CHECK(var == Approx(1.0).margin(0.01));
}

TEST_CASE("hashed quantile noise is the quantile at the hash of each pixel, with unit variance", "[random]") {
    const uint32_t row = quantile_normal_row(NoiseKey{42, 7, 1}, 3);
    const float* table = normal_quantile_table();
    // A run starting anywhere holds the definition's value at each x (vector lanes and tail alike).
    std::vector<float> run(1003);
    quantile_normal_run(row, -500, int(run.size()), run.data());
    for (int i = 0; i < int(run.size()); ++i) REQUIRE(run[i] == table[mix32(row ^ mix32(uint32_t(i - 500))) >> 16]);
    std::vector<float> part(13);
    quantile_normal_run(row, -3, 13, part.data());
    for (int i = 0; i < 13; ++i) REQUIRE(part[i] == run[497 + i]);
    double sum = 0, sum2 = 0;
    const int n = 200000;
    std::vector<float> values(n);
    quantile_normal_run(row, 0, n, values.data());
    for (float v : values) sum += v, sum2 += double(v) * v;
    const double mean = sum / n, var = sum2 / n - mean * mean;
    CHECK(std::abs(mean) < 5.0 / std::sqrt(n));
    CHECK(var == Approx(1.0).margin(0.01));
    CHECK(quantile_normal_row(NoiseKey{42, 7, 1}, 3) != quantile_normal_row(NoiseKey{42, 8, 1}, 3));
}
