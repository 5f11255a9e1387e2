#include <catch2/catch.hpp>
#include <cmath>

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
