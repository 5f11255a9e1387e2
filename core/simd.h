// Vector types for the hot loops (GCC and clang vector extensions), their unaligned loads
// and stores, and the dispatch that runs each loop at the widest vectors the processor has.
//
// A hot loop is written once, for any lane count, as a kernel: a struct whose static
// member template run<lanes>(args...) is always inlined. dispatch<Kernel>(args...) runs it
// compiled for AVX-512 (16 float lanes), AVX2 (8) or the baseline (8, in SSE2 halves),
// chosen once per process. No build uses FMA (a product and a sum round separately, and
// the project builds with -ffp-contract=off), and every loop works lane by lane, so every
// processor and lane count computes the same values: each kernel is tested bit for bit
// against its one-lane definition, and whole renders against each other on every ISA the
// test machine has (tests/core/test_simd.cpp).
//
// A vector never passes through a call by value (its ABI differs with and without AVX):
// kernels take pointers and scalars, and their helpers take references and are inlined.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace darkroom::simd {

// The vector types of `lanes` floats (and as many int32, uint32, int64 and double lanes).
template <int lanes>
struct Lanes {
    typedef float F __attribute__((vector_size(4 * lanes)));
    typedef int32_t I __attribute__((vector_size(4 * lanes)));
    typedef uint32_t U __attribute__((vector_size(4 * lanes)));
    typedef int64_t L __attribute__((vector_size(8 * lanes)));
    typedef double D __attribute__((vector_size(8 * lanes)));
};
using Float8 = Lanes<8>::F;
using Float4 = Lanes<4>::F;
// One lane: the scalar tails run the same lane-generic code as the vector blocks.
using Float1 = Lanes<1>::F;
using Int1 = Lanes<1>::I;
using Uint1 = Lanes<1>::U;
using Double1 = Lanes<1>::D;

// v = the values at p, one vector move. (memcpy into an array of vectors was merged by GCC
// into one copy through the stack in 16-byte halves, and the 32-byte reads that followed
// stalled on store forwarding.)
template <typename V, typename T>
__attribute__((always_inline)) inline void load(V& v, const T* p) {
    typedef V Unaligned __attribute__((aligned(alignof(T)), may_alias));
    v = *reinterpret_cast<const Unaligned*>(p);
}

template <typename T, typename V>
__attribute__((always_inline)) inline void store(T* p, const V& v) {
    typedef V Unaligned __attribute__((aligned(alignof(T)), may_alias));
    *reinterpret_cast<Unaligned*>(p) = v;
}

// The int32 lanes of v into `lanes`, to be read one at a time: two at a time by 64-bit
// register moves, each pair split by a shift. (Storing the vector and loading the lanes back
// waited on store forwarding, which stalls for the lanes past a vector's first 16 bytes: the
// 3D table's lookups are 5 % faster this way with AVX2 on a Zen 3, 25 % with AVX-512 on a
// Xeon; an extract a lane costs two instructions.)
template <int n, typename I>
__attribute__((always_inline)) inline void int32_lanes(int32_t (&lanes)[n], const I& v) {
    static_assert(n % 2 == 0 && sizeof(I) == 4 * n, "an even number of int32 lanes");
    typename Lanes<n / 2>::L pairs;
    std::memcpy(&pairs, &v, sizeof pairs);
    for (int k = 0; k < n / 2; ++k) {
        const int64_t pair = pairs[k];
        lanes[2 * k] = int32_t(pair);  // (x86 is little-endian: lane 2k is the low half)
        lanes[2 * k + 1] = int32_t(pair >> 32);
    }
}

// Asks for the cache lines of the `bytes` from p + kPrefetchAheadBytes on, to be read (or,
// for_writing, written) a few iterations later, for a loop that streams a row from memory:
// the hardware's prefetchers stop at each 4 KB page, so a 4K frame's row would otherwise
// wait on memory at every page (measured: the exposure's input reads and the result's
// writes, README). A hint only: no value changes; the address is formed as an integer, and
// one past the buffer does not fault.
constexpr int kPrefetchAheadBytes = 4096;
template <bool for_writing = false>
__attribute__((always_inline)) inline void prefetch_ahead(const void* p, int bytes) {
    const uintptr_t ahead = reinterpret_cast<uintptr_t>(p) + kPrefetchAheadBytes;
    for (int b = 0; b < bytes; b += 64) __builtin_prefetch(reinterpret_cast<const void*>(ahead + b), for_writing);
}

// The instruction sets the kernels are compiled for, narrowest first.
enum class Isa { baseline, avx2, avx512 };
const char* isa_name(Isa isa);
// The widest this processor runs (AVX-512 needs its F, BW, DQ and VL parts).
Isa widest_isa();
// The one dispatch uses: the widest, unless lowered by set_isa or by the environment
// variable DARKROOM_ISA (baseline, avx2 or avx512) when the process starts, so that tests
// and the benchmark can compare the instruction sets in one process.
Isa isa();
// Uses `isa`, or the widest this processor runs if that is narrower; returns the one used.
Isa set_isa(Isa isa);

// The lanes each instruction set's kernels use.
constexpr int kAvx512Lanes = 16, kAvx2Lanes = 8, kBaselineLanes = 8;

template <typename Kernel, typename... Args>
__attribute__((target("avx512f,avx512bw,avx512dq,avx512vl"))) void run_avx512(Args... args) {
    Kernel::template run<kAvx512Lanes>(args...);
}
template <typename Kernel, typename... Args>
__attribute__((target("avx2"))) void run_avx2(Args... args) {
    Kernel::template run<kAvx2Lanes>(args...);
}
template <typename Kernel, typename... Args>
void run_baseline(Args... args) {
    Kernel::template run<kBaselineLanes>(args...);
}

template <typename Kernel, typename... Args>
void dispatch(Args... args) {
    switch (isa()) {
        case Isa::avx512: run_avx512<Kernel>(args...); return;
        case Isa::avx2: run_avx2<Kernel>(args...); return;
        case Isa::baseline: run_baseline<Kernel>(args...); return;
    }
}

}  // namespace darkroom::simd
