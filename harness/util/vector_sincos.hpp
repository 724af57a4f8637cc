#pragma once
// cos and sin of many angles at once, for loops that need both for every element (a point light's
// emission azimuths, harness/reference/photon_source.cpp).
#include <cstddef>

namespace caustics {

// cos_out[k] = cos(angle[k]) and sin_out[k] = sin(angle[k]) for k < n; the arrays may not overlap.
//
// On x86-64 Linux with glibc's libmvec and a CPU with AVX2, four angles per call of libmvec's AVX2
// kernels (the x86-64 vector function ABI's _ZGVdN4v_cos and _ZGVdN4v_sin): at most 4 ulp from the
// exact values (glibc manual, "Known Maximum Errors in Math Functions"), against about 15 ns per angle
// for libm's scalar sincos. Each value depends only on its own angle (a last group of fewer than four
// is padded), so its bits do not depend on n or on the angle's place in the array; on CPUs with AVX2
// and FMA (the kernels libmvec then runs) they are the same on every machine. Elsewhere libm's
// std::cos and std::sin, one angle at a time.
void vector_sincos(const double* angle, std::size_t n, double* cos_out, double* sin_out);

// Whether vector_sincos runs libmvec's kernels on this CPU (for tests and the build's description).
bool vector_sincos_uses_libmvec();

}  // namespace caustics
