#include <caustics/util/vector_sincos.hpp>

#include <cmath>

#if defined(CAUSTICS_HAVE_LIBMVEC)
#include <immintrin.h>
#endif

namespace caustics {
namespace {

void scalar_sincos(const double* angle, std::size_t n, double* cos_out, double* sin_out) {
    for (std::size_t k = 0; k < n; ++k) {
        cos_out[k] = std::cos(angle[k]);
        sin_out[k] = std::sin(angle[k]);
    }
}

}  // namespace

#if defined(CAUSTICS_HAVE_LIBMVEC)

// libmvec's 4-lane double kernels for AVX2 (glibc >= 2.22; libmvec picks its AVX2-and-FMA version or
// an SSE fallback once, at load time).
extern "C" __m256d _ZGVdN4v_cos(__m256d);
extern "C" __m256d _ZGVdN4v_sin(__m256d);

namespace {

__attribute__((target("avx2"))) void libmvec_sincos(const double* angle, std::size_t n, double* cos_out,
                                                     double* sin_out) {
    std::size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        const __m256d a = _mm256_loadu_pd(angle + k);
        _mm256_storeu_pd(cos_out + k, _ZGVdN4v_cos(a));
        _mm256_storeu_pd(sin_out + k, _ZGVdN4v_sin(a));
    }
    if (k == n) return;
    alignas(32) double a[4] = {0.0, 0.0, 0.0, 0.0}, c[4], s[4];
    for (std::size_t j = k; j < n; ++j) a[j - k] = angle[j];
    const __m256d v = _mm256_load_pd(a);
    _mm256_store_pd(c, _ZGVdN4v_cos(v));
    _mm256_store_pd(s, _ZGVdN4v_sin(v));
    for (std::size_t j = k; j < n; ++j) {
        cos_out[j] = c[j - k];
        sin_out[j] = s[j - k];
    }
}

// The test libmvec applies before it runs its AVX2 kernels (otherwise it runs an SSE version, whose
// last bits differ).
bool cpu_has_avx2_fma() {
    static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return yes;
}

}  // namespace

bool vector_sincos_uses_libmvec() { return cpu_has_avx2_fma(); }

void vector_sincos(const double* angle, std::size_t n, double* cos_out, double* sin_out) {
    if (cpu_has_avx2_fma())
        libmvec_sincos(angle, n, cos_out, sin_out);
    else
        scalar_sincos(angle, n, cos_out, sin_out);
}

#else

bool vector_sincos_uses_libmvec() { return false; }

void vector_sincos(const double* angle, std::size_t n, double* cos_out, double* sin_out) {
    scalar_sincos(angle, n, cos_out, sin_out);
}

#endif

}  // namespace caustics
