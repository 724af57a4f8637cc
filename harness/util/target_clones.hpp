#pragma once
// CAUSTICS_AVX2_CLONES: a function compiled twice, for AVX2 and for the baseline x86-64, the version
// picked once at load time by the CPU (GCC's function multiversioning on x86-64 Linux); elsewhere one
// version. For loops that vectorise well only with AVX2 (wide blends, strided stores, float <-> double
// conversions). The avx2 target has no FMA, so no multiply and add are fused in either version: an
// element-wise loop gives the same values on every machine.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define CAUSTICS_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CAUSTICS_AVX2_CLONES
#endif

namespace caustics {

// Whether this CPU runs AVX2 code: the test before a function written with AVX2 intrinsics (under
// __attribute__((target("avx2")))) is called. False off x86-64.
inline bool cpu_has_avx2() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    static const bool yes = __builtin_cpu_supports("avx2");
    return yes;
#else
    return false;
#endif
}

}  // namespace caustics
