#pragma once
// cos and sin of many angles at once, for loops that need both for every element (a point light's
// emission azimuths, harness/reference/photon_source.cpp).
#include <cstddef>

namespace caustics {

// cos_out[k] = cos(angle[k]) and sin_out[k] = sin(angle[k]) for k < n; the arrays may not overlap.
//
// Built with GCC on x86-64 Linux with glibc's libmvec, on a CPU with AVX2 and FMA: four angles per call
// of libmvec's AVX2 kernels (the x86-64 vector function ABI's _ZGVdN4v_cos and _ZGVdN4v_sin), at most
// 4 ulp from the exact values (glibc manual, "Known Maximum Errors in Math Functions"; 3 ulp from libm
// measured, tests/test_vector_sincos.cpp). They took about 1.3 ns per angle on an AMD EPYC where libm's
// scalar sincos took 10 to 16 ns. Each value depends only on its own angle (a last group of fewer than
// four is padded), so its bits do not depend on n or on the angle's place in the array, and they are
// the same on every CPU with AVX2 and FMA: libmvec picks these kernels by the same test (unless
// GLIBC_TUNABLES hides AVX2 or FMA from it). Elsewhere libm's std::cos and std::sin, one angle at a time.
void vector_sincos(const double* angle, std::size_t n, double* cos_out, double* sin_out);

// Whether vector_sincos runs libmvec's kernels in this build on this CPU (the reference's recorded bits
// depend on it, tests/test_reference_bits.cpp).
bool vector_sincos_uses_libmvec();

}  // namespace caustics
