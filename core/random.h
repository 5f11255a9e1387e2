// Counter-based random numbers: a pure function of (seed, frame, stream, x, y).
//
// Philox4x32-10 from Salmon, Moraes, Dror & Shaw, "Parallel Random Numbers: As Easy as
// 1, 2, 3" (SC 2011): ten rounds of multiply-xor on a 128-bit counter under a 64-bit key.
// Grain keyed this way cannot depend on threads, tiles or render windows.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace darkroom {

using Philox4x32 = std::array<uint32_t, 4>;

// The product of a Philox word and a round multiplier, its high and low 32 bits: of one
// word, and of each 64-bit lane of a vector of words (each below 2^32).
inline void philox_multiply(uint32_t word, uint64_t multiplier, uint32_t& high, uint32_t& low) {
    const uint64_t product = multiplier * word;
    high = uint32_t(product >> 32);
    low = uint32_t(product);
}
template <typename V>
__attribute__((always_inline)) inline void philox_multiply(const V& word, uint64_t multiplier, V& high, V& low) {
    const V product = word * multiplier;
    high = product >> 32;
    low = product & 0xffffffffu;
}

// Philox4x32-10's rounds on its four words: W is uint32_t, or a vector of 64-bit lanes for
// draws with consecutive counters in its lanes.
template <typename W>
__attribute__((always_inline)) inline void philox4x32_10_rounds(W (&word)[4], uint32_t key0, uint32_t key1) {
    constexpr uint64_t kMul0 = 0xD2511F53u, kMul1 = 0xCD9E8D57u;     // round multipliers
    constexpr uint32_t kWeyl0 = 0x9E3779B9u, kWeyl1 = 0xBB67AE85u;   // key schedule increments
    for (int round = 0; round < 10; ++round) {
        W high0, low0, high1, low1;
        philox_multiply(word[0], kMul0, high0, low0);
        philox_multiply(word[2], kMul1, high1, low1);
        word[0] = high1 ^ word[1] ^ key0;
        word[1] = low1;
        word[2] = high0 ^ word[3] ^ key1;
        word[3] = low0;
        key0 += kWeyl0;
        key1 += kWeyl1;
    }
}

inline Philox4x32 philox4x32_10(Philox4x32 counter, uint32_t key0, uint32_t key1) {
    uint32_t word[4] = {counter[0], counter[1], counter[2], counter[3]};
    philox4x32_10_rounds(word, key0, key1);
    return {word[0], word[1], word[2], word[3]};
}

// Which independent noise field a draw belongs to (film layers, paper layers, ...).
struct NoiseKey {
    uint64_t seed = 0;
    int32_t frame = 0;
    uint32_t stream = 0;
    bool operator==(const NoiseKey& o) const { return seed == o.seed && frame == o.frame && stream == o.stream; }
};

// Uniform in (0, 1], never 0, from the top 24 bits.
inline double uniform_open0(uint32_t bits) { return ((bits >> 8) + 1.0) * (1.0 / 16777216.0); }

// Two independent standard normal draws for pixel (x, y) of the given field (Box-Muller).
inline std::array<double, 2> normal_pair(const NoiseKey& key, int x, int y) {
    Philox4x32 c = {uint32_t(x), uint32_t(y), uint32_t(key.frame), key.stream};
    Philox4x32 r = philox4x32_10(c, uint32_t(key.seed), uint32_t(key.seed >> 32));
    double radius = std::sqrt(-2.0 * std::log(uniform_open0(r[0])));
    double angle = 6.283185307179586 * uniform_open0(r[1]);
    return {radius * std::cos(angle), radius * std::sin(angle)};
}

inline float standard_normal(const NoiseKey& key, int x, int y) { return (float)normal_pair(key, x, y)[0]; }

// The fast tiers' noise: a 32-bit integer hash of (key, x, y), the murmur3 finaliser
// (Appleby, MurmurHash3, public domain) of the row's hash xor x times the golden ratio's
// 2^32 (a bijection of x), read as the sum of its four bytes, less their mean (510) and over
// their standard deviation (sqrt(4 (256^2 - 1) / 12)): zero mean and unit variance, within
// +-3.45, an excess kurtosis of -0.3 (four uniforms: Irwin-Hall), which the grain's filter
// then averages towards the normal's 0. Its second moments, which are all the grain's
// spectrum and amplitude depend on, are the normal noise's exactly.
// (In place and a template, so that core/random.cpp hashes the lanes of a vector type
// with it: a vector never passes through a call, whose ABI would differ with and without AVX.)
template <typename U32>
inline void mix32_in_place(U32& h) {
    h ^= h >> 16;
    h *= 0x85EBCA6Bu;
    h ^= h >> 13;
    h *= 0xC2B2AE35u;
    h ^= h >> 16;
}
inline uint32_t mix32(uint32_t h) {
    mix32_in_place(h);
    return h;
}
// The part of the hash that is the same along a row: pass it to hashed_noise_run (or, a
// field's, to mixed_hashed_noise_run).
inline uint32_t hashed_noise_row(const NoiseKey& key, int y) {
    uint32_t h = mix32(uint32_t(key.seed) ^ mix32(uint32_t(key.seed >> 32) ^ mix32(uint32_t(key.frame) ^
                                                                                  mix32(key.stream + 0x9E3779B9u))));
    return mix32(h ^ uint32_t(y));
}
constexpr uint32_t kNoiseColumnStep = 0x9E3779B9u;  // 2^32 / golden ratio, odd
constexpr float kHashedNoiseMean = 510.0f;                 // of the sum of four bytes: 4 x 255/2
constexpr float kHashedNoiseScale = 0.0067658751f;         // 1 / sqrt(4 (256^2 - 1) / 12)
// The noise at x = x0 ... x0 + n - 1 of a row into out, each the value above of
// mix32(row_hash ^ uint32(x) kNoiseColumnStep).
void hashed_noise_run(uint32_t row_hash, int x0, int n, float* out);

// A row of noise that is a weighted sum of several fields' (the fast tiers' film layers, whose
// grains the print's fold correlates: GrainModel::mixed_noise): weight[t] times the noise of
// field field[t], summed in the terms' order (one term of weight 1 is the field's own noise).
constexpr int kMaxNoiseFields = 3;
struct NoiseMix {
    int terms = 0;
    int field[kMaxNoiseFields] = {};
    float weight[kMaxNoiseFields] = {};
};
// Rows of mixed noise at x0 ... x0 + n - 1: out[o] mixes[o]'s sum of the fields whose row
// hashes are row_hashes[0 .. fields), each field's noise hashed once a pixel for all rows.
void mixed_hashed_noise_run(const uint32_t* row_hashes, int fields, const NoiseMix* mixes, int rows, int x0, int n,
                            float* const* out);

}  // namespace darkroom
