// Vector types for the hot loops (GCC and clang vector extensions) and their unaligned
// loads and stores.
//
// The loops that use them are cloned for AVX2 and the baseline (target_clones), never with
// FMA, so every machine computes the same values. A vector never passes through a call by
// value (its ABI differs with and without AVX): helpers take references and are inlined,
// and the cloned loops are free functions (clang 14 does not clone member functions).
#pragma once

#include <cstdint>

namespace darkroom::simd {

using Float8 = float __attribute__((vector_size(32)));
using Int8 = int32_t __attribute__((vector_size(32)));
using Uint8 = uint32_t __attribute__((vector_size(32)));
using Float4 = float __attribute__((vector_size(16)));
using Double4 = double __attribute__((vector_size(32)));
// One lane: the scalar tails run the same lane-generic code as the vector blocks.
using Float1 = float __attribute__((vector_size(4)));
using Int1 = int32_t __attribute__((vector_size(4)));
using Uint1 = uint32_t __attribute__((vector_size(4)));
using Double1 = double __attribute__((vector_size(8)));

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

}  // namespace darkroom::simd
