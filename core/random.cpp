// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "core/random.h"

#include <cstdint>

#include "core/simd.h"

namespace darkroom {

namespace {

// The four bytes of each lane's hash summed (two at a time, in 16-bit halves), centred and scaled.
template <typename U, typename V>
__attribute__((always_inline)) inline V byte_sum_noise(const U& h) {
    const U pairs = (h & 0x00FF00FFu) + ((h >> 8) & 0x00FF00FFu);
    const U sum = (pairs & 0xFFFFu) + (pairs >> 16);
    // Converted as signed (the sum is at most 1020): AVX2 converts only signed integers to
    // floats, and an unsigned conversion there takes five more instructions a vector.
    using I = typename simd::Lanes<int(sizeof(U) / sizeof(uint32_t))>::I;
    return (__builtin_convertvector(I(sum), V) - kHashedNoiseMean) * kHashedNoiseScale;
}

// The noise of lanes whose columns' hashes (x kNoiseColumnStep) are `columns`: one piece of
// code for the vector blocks and the scalar tail.
template <typename U, typename V>
__attribute__((always_inline)) inline V hashed_noise_lanes(uint32_t row_hash, const U& columns) {
    U h = columns ^ row_hash;
    mix32_in_place(h);
    return byte_sum_noise<U, V>(h);
}

// Each field's noise at the lanes' columns, then each row's weighted sum of them.
template <typename U, typename V>
__attribute__((always_inline)) inline void mixed_noise_lanes(const uint32_t* row_hashes, int fields,
                                                             const NoiseMix* mixes, int rows, const U& columns,
                                                             float* const* out, int i) {
    V noise[kMaxNoiseFields];
    for (int f = 0; f < fields; ++f) noise[f] = hashed_noise_lanes<U, V>(row_hashes[f], columns);
    for (int o = 0; o < rows; ++o) {
        const NoiseMix& mix = mixes[o];
        V sum = mix.weight[0] * noise[mix.field[0]];
        for (int t = 1; t < mix.terms; ++t) sum += mix.weight[t] * noise[mix.field[t]];
        simd::store(out[o] + i, sum);
    }
}

// The hashes and their noise in vectors of `lanes`, then one at a time. A vector's column
// hashes are the last one's plus lanes kNoiseColumnStep (the same values modulo 2^32: an add
// where a multiply took a quarter of the run's time, Zen 3 AVX2).
struct MixedHashedNoiseRun {
    template <int lanes>
    __attribute__((always_inline)) static void run(const uint32_t* row_hashes, int fields, const NoiseMix* mixes,
                                                   int rows, int x0, int n, float* const* out) {
        using U = typename simd::Lanes<lanes>::U;
        auto column_hash = [x0](int i) { return (uint32_t(x0) + uint32_t(i)) * kNoiseColumnStep; };
        U columns;
        for (int k = 0; k < lanes; ++k) columns[k] = column_hash(k);
        int i = 0;
        for (; i + lanes <= n; i += lanes, columns += uint32_t(lanes) * kNoiseColumnStep)
            mixed_noise_lanes<U, typename simd::Lanes<lanes>::F>(row_hashes, fields, mixes, rows, columns, out, i);
        for (; i < n; ++i)
            mixed_noise_lanes<simd::Uint1, simd::Float1>(row_hashes, fields, mixes, rows, simd::Uint1{column_hash(i)},
                                                         out, i);
    }
};

}  // namespace

void hashed_noise_run(uint32_t row_hash, int x0, int n, float* out) {
    NoiseMix own;  // (1 x the noise: its value exactly)
    own.terms = 1, own.weight[0] = 1.0f;
    mixed_hashed_noise_run(&row_hash, 1, &own, 1, x0, n, &out);
}

void mixed_hashed_noise_run(const uint32_t* row_hashes, int fields, const NoiseMix* mixes, int rows, int x0, int n,
                            float* const* out) {
    simd::dispatch<MixedHashedNoiseRun>(row_hashes, fields, mixes, rows, x0, n, out);
}

}  // namespace darkroom
