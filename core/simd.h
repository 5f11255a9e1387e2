// Vector types for the hot loops (GCC and clang vector extensions), their unaligned loads
// and stores, and the dispatch that runs each loop at the widest vectors the processor has.
//
// A hot loop is written once, for any lane count, as a kernel: a struct whose static
// member template run<lanes>(args...) is always inlined. dispatch<Kernel>(args...) runs it
// compiled for AVX-512 (16 float lanes), AVX2 (8) or the baseline's SSE2 (4),
// chosen once per process (dispatch_doubles: a kernel of doubles, a register's width of
// them: 8, 4 or 2). No build uses FMA (a product and a sum round separately, and
// the project builds with -ffp-contract=off), and every loop works lane by lane, so every
// processor and lane count computes the same values: each kernel is tested bit for bit
// against its one-lane definition, and whole renders against each other on every ISA the
// test machine has (tests/core/test_simd.cpp).
//
// A vector never passes through a call by value (its ABI differs with and without AVX):
// kernels take pointers and scalars, and their helpers take references and are inlined.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>

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

// Lanes picked from `count` vectors v[0] ... v[count - 1] (count >= 2) into `result`: lane j
// is lane Pick::lane(j) of v[Pick::vector(j)], by count - 1 shuffles of two vectors (each
// takes the lanes of the next vector). Pick's functions are constexpr.
template <typename Pick, int count, typename V, size_t... J>
__attribute__((always_inline)) inline void picked(const V* v, V& result, std::index_sequence<J...> j) {
    constexpr int lanes = sizeof...(J);
    if constexpr (count == 2) {
        result = __builtin_shufflevector(v[0], v[1], (Pick::vector(J) < 2 ? Pick::vector(J) * lanes + Pick::lane(J) : 0)...);
    } else {
        V before;
        picked<Pick, count - 1>(v, before, j);
        result = __builtin_shufflevector(before, v[count - 1],
                                         (Pick::vector(J) == count - 1 ? lanes + Pick::lane(J) : int(J))...);
    }
}

// Asks for the cache lines of the `bytes` from p + kPrefetchAheadBytes on, to be read (or,
// for_writing, written) a few iterations later, for a loop that streams a row from memory:
// the hardware's prefetchers stop at each 4 KB page, so a 4K frame's row would otherwise
// wait on memory at every page (measured: the exposure's input reads and the result's
// writes, docs/development/quality-tiers.md). A hint only: no value changes; the address is formed as an integer, and
// one past the buffer does not fault.
constexpr int kPrefetchAheadBytes = 4096;
template <bool for_writing = false>
__attribute__((always_inline)) inline void prefetch_ahead(const void* p, int bytes) {
    const uintptr_t ahead = reinterpret_cast<uintptr_t>(p) + kPrefetchAheadBytes;
    for (int b = 0; b < bytes; b += 64) __builtin_prefetch(reinterpret_cast<const void*>(ahead + b), for_writing);
}

// Whether any lane of a mask of int64 lanes (a comparison of doubles) is set.
template <typename L>
__attribute__((always_inline)) inline bool any_lane(const L& mask) {
    bool set = false;
    for (size_t l = 0; l < sizeof(L) / sizeof(int64_t); ++l) set = set || mask[l] != 0;
    return set;
}

// Added to a double of magnitude under 2^51 (and taken away), it rounds it to an integer,
// which the sum then holds in its low bits.
constexpr double kRoundToInteger = 0x1.8p52;

// 2^n for integer-valued lanes n within a normal double's exponents (|n| < 1023), from its bits.
template <typename D, typename L>
__attribute__((always_inline)) inline void power_of_two(const D& n, D& power) {
    const D shifted = n + kRoundToInteger;
    L bits;
    std::memcpy(&bits, &shifted, sizeof bits);
    bits = (bits - int64_t(0x4338000000000000) + 1023) << 52;  // (0x4338... is kRoundToInteger's bits)
    std::memcpy(&power, &bits, sizeof power);
}

// result = e^x in each double lane (D the lanes, L as many int64), within 1 ulp of std::exp
// (every 1e-4 from -746 to 709.78: tests/core/test_simd.cpp), for the spectral stages'
// transmittances, where std::exp a sample was a third of the high tier's time and most of the
// fast tiers' table build. x = k ln 2 + r with |r| <= ln 2 / 2 (ln 2 in two parts, the first
// with trailing zero bits so that k times it is exact: fdlibm's split), e^r by its Taylor
// series to r^13 (truncation under 0.05 ulp), and 2^k as the product of two powers of two
// built from their bits, so that results down to the subnormals and up to the largest double
// need no special case; x is clamped to [-746, 710], beyond which e^x is 0 or +inf anyway.
// NaN stays NaN. Lane by lane without FMA, so every processor computes the same values.
template <typename D, typename L>
__attribute__((always_inline)) inline void exp_lanes(const D& x, D& result) {
    constexpr double kLog2e = 1.4426950408889634, kLn2High = 6.93147180369123816490e-01,
                     kLn2Low = 1.90821492927058770002e-10;
    constexpr double kInverseFactorial[14] = {1.0,
                                              1.0,
                                              1.0 / 2,
                                              1.0 / 6,
                                              1.0 / 24,
                                              1.0 / 120,
                                              1.0 / 720,
                                              1.0 / 5040,
                                              1.0 / 40320,
                                              1.0 / 362880,
                                              1.0 / 3628800,
                                              1.0 / 39916800,
                                              1.0 / 479001600,
                                              1.0 / 6227020800};
    D clamped = x < -746.0 ? D{} - 746.0 : x;
    clamped = clamped > 710.0 ? D{} + 710.0 : clamped;
    const D k = (clamped * kLog2e + kRoundToInteger) - kRoundToInteger;
    const D r = (clamped - k * kLn2High) - k * kLn2Low;
    // The terms from r^4 on by Estrin's scheme (in pairs, then pairs of pairs by r^2, r^4 and
    // r^8), the first four by Horner's, which keeps the sum within 1 ulp: the chain of
    // dependent steps is 14 long where Horner's alone is 26 (the loops were bound by it).
    const D r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
    D pair[5];
    for (int n = 0; n < 5; ++n) pair[n] = r * kInverseFactorial[2 * n + 5] + kInverseFactorial[2 * n + 4];
    D p = (pair[0] + pair[1] * r2) + (pair[2] + pair[3] * r2) * r4 + pair[4] * r8;
    for (int n = 3; n >= 0; --n) p = p * r + kInverseFactorial[n];
    // 2^k = 2^k1 2^(k - k1), each factor's exponent within a normal double's.
    const D k1 = (k * 0.5 + kRoundToInteger) - kRoundToInteger, k2 = k - k1;
    D power1, power2;
    power_of_two<D, L>(k1, power1), power_of_two<D, L>(k2, power2);
    result = p * power1 * power2;
}

// result = tanh(x) in each double lane for x >= 0, as (1 - e^-2x) / (1 + e^-2x) by exp_lanes:
// within 3.5e-16 of std::tanh absolutely (tests/core/test_simd.cpp; relatively more near 0,
// where the difference cancels: the gamut compression, its user, adds it to 0.8, and took
// std::tanh a lane at a time). 1 from x = 373 on (e^-746 is 0); NaN stays NaN.
template <typename D, typename L>
__attribute__((always_inline)) inline void tanh_lanes(const D& x, D& result) {
    D e;
    exp_lanes<D, L>(x * -2.0, e);
    result = (1.0 - e) / (1.0 + e);
}

// root = the square root of each double lane of x (D: Lanes<n>::D), correctly rounded as
// std::sqrt, one instruction for each register width the kernels run at. (By assembly: an
// intrinsic inlines only into a function compiled for its instruction set, and the kernels'
// bodies are compiled for none. Clang checks an operand's width against the instruction set
// of the function the assembly is written in, so there, and for one lane, the lanes take
// std::sqrt one at a time: the same values.)
#if defined(__clang__)
constexpr bool kSqrtByAssembly = false;
#else
constexpr bool kSqrtByAssembly = true;
#endif
template <typename D>
__attribute__((always_inline)) inline void sqrt_lanes(const D& x, D& root) {
    if constexpr (kSqrtByAssembly && sizeof(D) == 16)
        asm("sqrtpd %1, %0" : "=x"(root) : "x"(x));
    else if constexpr (kSqrtByAssembly && sizeof(D) > 16)
        asm("vsqrtpd %1, %0" : "=v"(root) : "v"(x));
    else
        for (size_t k = 0; k < sizeof(D) / sizeof(double); ++k) root[k] = std::sqrt(x[k]);
}

// result = the lanes of x truncated toward zero, in int64 lanes (as many as D has): one
// instruction for AVX-512's width (vcvttpd2qq). Narrower registers have none, and GCC
// converts such lanes one at a time, so there through int32 lanes: |x| must be under 2^31.
template <typename D, typename L>
__attribute__((always_inline)) inline void truncate_lanes(const D& x, L& result) {
    if constexpr (sizeof(D) == 64) {
        result = __builtin_convertvector(x, L);
    } else {
        typedef int32_t I __attribute__((vector_size(sizeof(D) / 2)));
        result = __builtin_convertvector(__builtin_convertvector(x, I), L);
    }
}

// result = log10(v) in each double lane, within 4 ulp (3.6e-15) of std::log10 (measured
// against it from 1e-30 to 1e30), for positive normal v (the print table's grid, where
// std::log10 a node and layer took a third of its build). v = 2^e m, m within [sqrt(1/2),
// sqrt(2)): ln m = 2 atanh(s), s = (m - 1) / (m + 1), |s| <= 0.172, by its odd series to s^23
// (the rest under 1e-19 of it). Lane by lane without FMA, as exp_lanes.
template <typename D, typename L>
__attribute__((always_inline)) inline void log10_lanes(const D& v, D& result) {
    constexpr double kLog10Of2 = 0.30102999566398120, kTwoOverLn10 = 0.86858896380650366,
                     kSqrt2 = 1.4142135623730951;
    D m, exponent;
    L bits;
    std::memcpy(&bits, &v, sizeof bits);
    // The exponent as a double (its 11 bits under 2^52's, less 2^52 + 1023), and m in [1, 2).
    const L exponent_bits = ((bits >> 52) & 0x7FF) | int64_t(0x4330000000000000);
    std::memcpy(&exponent, &exponent_bits, sizeof exponent);
    exponent -= 0x1p52 + 1023;
    bits = (bits & int64_t(0x000FFFFFFFFFFFFF)) | int64_t(0x3FF0000000000000);
    std::memcpy(&m, &bits, sizeof m);
    const D above = m > kSqrt2 ? D{} + 1.0 : D{};
    m = m * (1.0 - 0.5 * above), exponent += above;
    const D s = (m - 1.0) / (m + 1.0), s2 = s * s;
    D series = D{} + 1.0 / 23;
    for (int k = 21; k >= 1; k -= 2) series = series * s2 + 1.0 / k;
    result = exponent * kLog10Of2 + s * series * kTwoOverLn10;
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

// The lanes each instruction set's kernels use: a register's width of floats, and of doubles
// for kernels of doubles. (In vectors wider than the registers GCC makes comparisons and
// selects scalar, storing and reloading the lanes: the baseline's kernels at 8 lanes, in SSE2
// halves, took 4-6x AVX2's time for the 4K fast frame; at 4, 1.6-2.5x.)
constexpr int kAvx512Lanes = 16, kAvx2Lanes = 8, kBaselineLanes = 4;
constexpr int kAvx512Doubles = 8, kAvx2Doubles = 4, kBaselineDoubles = 2;

template <typename Kernel, int lanes = kAvx512Lanes, typename... Args>
__attribute__((target("avx512f,avx512bw,avx512dq,avx512vl"))) void run_avx512(Args... args) {
    Kernel::template run<lanes>(args...);
}
template <typename Kernel, int lanes = kAvx2Lanes, typename... Args>
__attribute__((target("avx2"))) void run_avx2(Args... args) {
    Kernel::template run<lanes>(args...);
}
template <typename Kernel, int lanes = kBaselineLanes, typename... Args>
void run_baseline(Args... args) {
    Kernel::template run<lanes>(args...);
}

// (lanes: the widths run<> is given, the floats' by default.)
template <typename Kernel, int avx512_lanes = kAvx512Lanes, int avx2_lanes = kAvx2Lanes,
          int baseline_lanes = kBaselineLanes, typename... Args>
void dispatch(Args... args) {
    switch (isa()) {
        case Isa::avx512: run_avx512<Kernel, avx512_lanes>(args...); return;
        case Isa::avx2: run_avx2<Kernel, avx2_lanes>(args...); return;
        case Isa::baseline: run_baseline<Kernel, baseline_lanes>(args...); return;
    }
}

// The same for a kernel of doubles: run<lanes> with a register's width of them.
template <typename Kernel, typename... Args>
void dispatch_doubles(Args... args) {
    dispatch<Kernel, kAvx512Doubles, kAvx2Doubles, kBaselineDoubles>(args...);
}

// out[i] = f(in[i]) for n doubles, f given as Lane::apply<D, L>(v, result) on each lane of D
// (L: as many int64): a register's width at a time, then one lane at a time by the same code.
template <typename Lane>
struct MapDoubles {
    template <int lanes>
    __attribute__((always_inline)) static void run(const double* in, double* out, int n) {
        int i = 0;
        for (; i + lanes <= n; i += lanes) one<typename Lanes<lanes>::D, typename Lanes<lanes>::L>(in, out, i);
        for (; i < n; ++i) one<Double1, Lanes<1>::L>(in, out, i);
    }
    template <typename D, typename L>
    __attribute__((always_inline)) static void one(const double* in, double* out, int i) {
        D v, result;
        load(v, in + i);
        Lane::template apply<D, L>(v, result);
        store(out + i, result);
    }
};
template <typename Lane>
void map_doubles(const double* in, double* out, int n) {
    dispatch_doubles<MapDoubles<Lane>>(in, out, n);
}

}  // namespace darkroom::simd
