#include "core/simd.h"

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <initializer_list>

namespace darkroom::simd {

namespace {

Isa detect_widest() {
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl"))
        return Isa::avx512;
    if (__builtin_cpu_supports("avx2")) return Isa::avx2;
    return Isa::baseline;
}

Isa narrower(Isa a, Isa b) { return int(a) < int(b) ? a : b; }

Isa from_environment() {
    const Isa widest = widest_isa();
    const char* name = std::getenv("DARKROOM_ISA");
    if (!name) return widest;
    for (Isa candidate : {Isa::baseline, Isa::avx2, Isa::avx512})
        if (std::strcmp(name, isa_name(candidate)) == 0) return narrower(candidate, widest);
    return widest;
}

std::atomic<Isa>& chosen() {
    static std::atomic<Isa> isa{from_environment()};
    return isa;
}

}  // namespace

const char* isa_name(Isa isa) {
    switch (isa) {
        case Isa::avx512: return "avx512";
        case Isa::avx2: return "avx2";
        case Isa::baseline: break;
    }
    return "baseline";
}

Isa widest_isa() {
    static const Isa widest = detect_widest();
    return widest;
}

Isa isa() { return chosen().load(std::memory_order_relaxed); }

Isa set_isa(Isa isa) {
    const Isa used = narrower(isa, widest_isa());
    chosen().store(used, std::memory_order_relaxed);
    return used;
}

}  // namespace darkroom::simd
