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

namespace {

// The definition (core/random.h): the four bytes of mix32(row ^ x step) summed, centred, scaled.
float hashed_noise_at(uint32_t row, int x) {
    const uint32_t h = mix32(row ^ (uint32_t(x) * kNoiseColumnStep));
    const int sum = int(h & 0xFF) + int((h >> 8) & 0xFF) + int((h >> 16) & 0xFF) + int(h >> 24);
    return (float(sum) - kHashedNoiseMean) * kHashedNoiseScale;
}

}  // namespace

TEST_CASE("hashed noise is the centred byte sum of each pixel's hash, with the normal's mean and variance",
          "[random]") {
    const uint32_t row = hashed_noise_row(NoiseKey{42, 7, 1}, 3);
    // A run starting anywhere holds the definition's value at each x (vector lanes and tail alike).
    std::vector<float> run(1003);
    hashed_noise_run(row, -500, int(run.size()), run.data());
    for (int i = 0; i < int(run.size()); ++i) REQUIRE(run[i] == hashed_noise_at(row, i - 500));
    std::vector<float> part(13);
    hashed_noise_run(row, -3, 13, part.data());
    for (int i = 0; i < 13; ++i) REQUIRE(part[i] == run[497 + i]);

    // The distribution itself, exactly: the sum of four uniform bytes (their counts convolved)
    // has mean 510 and variance 4 (256^2 - 1) / 12, so the noise mean 0 and variance 1.
    std::vector<double> ways(1);
    ways[0] = 1;
    for (int byte = 0; byte < 4; ++byte) {
        std::vector<double> next(ways.size() + 255, 0.0);
        for (size_t s = 0; s < ways.size(); ++s)
            for (int b = 0; b < 256; ++b) next[s + size_t(b)] += ways[s];
        ways = next;
    }
    double mean = 0, var = 0, fourth = 0;
    for (size_t s = 0; s < ways.size(); ++s) {
        const double p = ways[s] / 4294967296.0, v = (double(s) - kHashedNoiseMean) * kHashedNoiseScale;
        mean += p * v, var += p * v * v, fourth += p * v * v * v * v;
    }
    CHECK(std::abs(mean) < 1e-12);
    CHECK(var == Approx(1.0).epsilon(1e-6));
    CHECK(fourth / (var * var) - 3 == Approx(-0.3).epsilon(1e-4));  // Irwin-Hall of four: -6/5 / 4

    // The hash spreads a row's values over that distribution: sample moments within their errors.
    double sum = 0, sum2 = 0, sum4 = 0;
    const int n = 400000;
    std::vector<float> values(n);
    hashed_noise_run(row, 0, n, values.data());
    for (float v : values) sum += v, sum2 += double(v) * v, sum4 += double(v) * v * v * v;
    const double sample_mean = sum / n, sample_var = sum2 / n - sample_mean * sample_mean;
    CHECK(std::abs(sample_mean) < 5.0 / std::sqrt(n));
    CHECK(sample_var == Approx(1.0).margin(0.01));
    CHECK(sum4 / n == Approx(2.7).margin(0.05));  // the fourth moment: 3 - 0.3
    // Neighbours along the row and across rows are uncorrelated.
    const uint32_t next_row = hashed_noise_row(NoiseKey{42, 7, 1}, 4);
    std::vector<float> below(n);
    hashed_noise_run(next_row, 0, n, below.data());
    double along = 0, across = 0;
    for (int i = 0; i + 1 < n; ++i) along += double(values[i]) * values[i + 1], across += double(values[i]) * below[i];
    CHECK(std::abs(along / n) < 5.0 / std::sqrt(n));
    CHECK(std::abs(across / n) < 5.0 / std::sqrt(n));
    CHECK(hashed_noise_row(NoiseKey{42, 7, 1}, 3) != hashed_noise_row(NoiseKey{42, 8, 1}, 3));
}
