// HeightField::sample_normals: sample_normal for a batch of points. The reference's tracer completes a
// group's height-field hits together (harness/frame/ray_tracer.cpp): one point at a time, each waited on
// its chain of two divisions, a square root and a third division (docs/reference_throughput.md).
//
// The AVX2 version does the operations of sample_normal (heightfield.cpp: grid_coord, the bilinear
// gradient, glm::normalize) in the same order, each correctly rounded by IEEE 754, four points per
// vector. It uses no FMA, and the scalar code contracts none (x86-64's baseline has no FMA, and
// harness/CMakeLists.txt builds both files with -ffp-contract=off should a build enable it), so each
// lane's bits equal sample_normal's (tests/test_heightfield_normals.cpp). Fields that wrap (fmod), have an
// exact gradient (a std::function), a single vertex along an axis, or more vertices than 32-bit gather
// indices reach, and CPUs without AVX2, take sample_normal point by point.
#include <caustics/scene/heightfield/heightfield.hpp>

#include <caustics/util/target_clones.hpp>

#include <cstdint>
#include <limits>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CAUSTICS_HEIGHTFIELD_AVX2 1
#include <immintrin.h>
#endif

namespace caustics {
namespace {

void scalar_normals(const HeightField& hf, const double* x, const double* y, std::size_t n, double* nx, double* ny,
                    double* nz) {
    for (std::size_t k = 0; k < n; ++k) {
        const glm::dvec3 v = hf.sample_normal(x[k], y[k]);
        nx[k] = v.x, ny[k] = v.y, nz[k] = v.z;
    }
}

#if defined(CAUSTICS_HEIGHTFIELD_AVX2)

// One axis of grid_coord for four points (the non-periodic branch): the cell index and the position in it.
struct AxisCells {
    __m128i i0;
    __m256d f;
};

__attribute__((target("avx2"))) inline AxisCells axis_cells(__m256d x, double origin, double spacing, int cells) {
    const __m256d zero = _mm256_setzero_pd(), top = _mm256_set1_pd(static_cast<double>(cells));
    __m256d g = _mm256_div_pd(_mm256_sub_pd(x, _mm256_set1_pd(origin)), _mm256_set1_pd(spacing));
    // std::clamp(g, 0, cells) (g < 0 gives 0, cells < g gives cells, anything else g, -0 included), then
    // NaN to 0.
    g = _mm256_blendv_pd(g, zero, _mm256_cmp_pd(g, zero, _CMP_LT_OQ));
    g = _mm256_blendv_pd(g, top, _mm256_cmp_pd(top, g, _CMP_LT_OQ));
    g = _mm256_blendv_pd(g, zero, _mm256_cmp_pd(g, g, _CMP_UNORD_Q));
    const __m128i i0 = _mm_min_epi32(_mm256_cvttpd_epi32(g), _mm_set1_epi32(cells - 1));
    return {i0, _mm256_sub_pd(g, _mm256_cvtepi32_pd(i0))};
}

// The gradients of four vertices (glm::vec2, 8 bytes each) as doubles: x components and y components.
__attribute__((target("avx2"))) inline void gather_gradients(const glm::vec2* gradient, __m128i index, __m256d& gx,
                                                             __m256d& gy) {
    static_assert(sizeof(glm::vec2) == 8, "one 64-bit gather element per vertex");
    const __m256i pairs = _mm256_i32gather_epi64(reinterpret_cast<const long long*>(gradient), index, 8);
    // (gx0 gy0 gx1 gy1 gx2 gy2 gx3 gy3) to (gx0 gx1 gx2 gx3 | gy0 gy1 gy2 gy3).
    const __m256 split = _mm256_permutevar8x32_ps(_mm256_castsi256_ps(pairs), _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7));
    gx = _mm256_cvtps_pd(_mm256_castps256_ps128(split));
    gy = _mm256_cvtps_pd(_mm256_extractf128_ps(split, 1));
}

// (1 - fy) ((1 - fx) a + fx b) + fy ((1 - fx) d + fx e), as bilinear() in heightfield.cpp.
__attribute__((target("avx2"))) inline __m256d bilinear4(__m256d fx, __m256d fy, __m256d a, __m256d b, __m256d d,
                                                         __m256d e) {
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d gx = _mm256_sub_pd(one, fx), gy = _mm256_sub_pd(one, fy);
    const __m256d low = _mm256_add_pd(_mm256_mul_pd(gx, a), _mm256_mul_pd(fx, b));
    const __m256d high = _mm256_add_pd(_mm256_mul_pd(gx, d), _mm256_mul_pd(fx, e));
    return _mm256_add_pd(_mm256_mul_pd(gy, low), _mm256_mul_pd(fy, high));
}

__attribute__((target("avx2"))) void avx2_normals(const HeightField& hf, const double* x, const double* y,
                                                  std::size_t n, double* nx, double* ny, double* nz) {
    const int cells_x = hf.nx - 1, cells_y = hf.ny - 1;
    const __m128i row = _mm_set1_epi32(hf.nx), one_i = _mm_set1_epi32(1);
    const __m256d one = _mm256_set1_pd(1.0), sign = _mm256_set1_pd(-0.0);
    const glm::vec2* gradient = hf.gradient.data();
    std::size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        const AxisCells cx = axis_cells(_mm256_loadu_pd(x + k), hf.origin.x, hf.spacing.x, cells_x);
        const AxisCells cy = axis_cells(_mm256_loadu_pd(y + k), hf.origin.y, hf.spacing.y, cells_y);
        const __m128i v00 = _mm_add_epi32(_mm_mullo_epi32(cy.i0, row), cx.i0);
        const __m128i v10 = _mm_add_epi32(v00, one_i), v01 = _mm_add_epi32(v00, row), v11 = _mm_add_epi32(v01, one_i);
        __m256d ax, ay, bx, by, dx, dy, ex, ey;
        gather_gradients(gradient, v00, ax, ay);
        gather_gradients(gradient, v10, bx, by);
        gather_gradients(gradient, v01, dx, dy);
        gather_gradients(gradient, v11, ex, ey);
        // normalize(-gx, -gy, 1) = v * (1 / sqrt((vx vx + vy vy) + 1 * 1)), as glm computes it.
        // Negation flips the sign bit (0 - g would turn -0 into +0).
        const __m256d vx = _mm256_xor_pd(bilinear4(cx.f, cy.f, ax, bx, dx, ex), sign);
        const __m256d vy = _mm256_xor_pd(bilinear4(cx.f, cy.f, ay, by, dy, ey), sign);
        const __m256d length2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(vx, vx), _mm256_mul_pd(vy, vy)), one);
        const __m256d inverse = _mm256_div_pd(one, _mm256_sqrt_pd(length2));
        _mm256_storeu_pd(nx + k, _mm256_mul_pd(vx, inverse));
        _mm256_storeu_pd(ny + k, _mm256_mul_pd(vy, inverse));
        _mm256_storeu_pd(nz + k, inverse);
    }
    scalar_normals(hf, x + k, y + k, n - k, nx + k, ny + k, nz + k);
}

#endif

}  // namespace

void HeightField::sample_normals(const double* x, const double* y, std::size_t n, double* out_x, double* out_y,
                                 double* out_z) const {
#if defined(CAUSTICS_HEIGHTFIELD_AVX2)
    // The grid's vertex indices as 32-bit integers, every cell with four distinct corners.
    const std::int64_t vertices = static_cast<std::int64_t>(nx) * ny;
    const bool gridded = !periodic && !exact_gradient && nx >= 2 && ny >= 2 &&
                         vertices <= std::numeric_limits<std::int32_t>::max() &&
                         gradient.size() == static_cast<std::size_t>(vertices);
    if (gridded && cpu_has_avx2()) return avx2_normals(*this, x, y, n, out_x, out_y, out_z);
#endif
    scalar_normals(*this, x, y, n, out_x, out_y, out_z);
}

}  // namespace caustics
