#include "lookup_mask.hpp"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace caustics::caustic_mapping {
namespace {

// Bits of n <= 64 texels: flux != 0 or no receiver. NaN flux compares unequal to 0, so it is kept.
std::uint64_t texel_bits(const float* flux, const std::int32_t* id, int n) {
    std::uint64_t b = 0;
    int k = 0;
#if defined(__SSE2__)
    // Four texels a step: the two comparisons' lanes ORed, their sign bits gathered by movemask.
    const __m128 zero = _mm_setzero_ps();
    const __m128i empty = _mm_set1_epi32(-1);
    for (; k + 4 <= n; k += 4) {
        const __m128 f = _mm_cmpneq_ps(_mm_loadu_ps(flux + k), zero);
        const __m128i e = _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(id + k)), empty);
        b |= static_cast<std::uint64_t>(_mm_movemask_ps(_mm_or_ps(f, _mm_castsi128_ps(e)))) << k;
    }
#endif
    for (; k < n; ++k) b |= static_cast<std::uint64_t>((flux[k] != 0.0f) | (id[k] == -1)) << k;
    return b;
}

}  // namespace

void LookupMask::build(const PositionsTexture& receivers, const std::vector<Image>& caustic) {
    const std::size_t faces = receivers.maps.size();
    const int W = faces ? receivers.maps[0].width : 0, H = faces ? receivers.maps[0].height : 0;
    words_ = (W + 63) / 64;
    face_words_ = static_cast<std::size_t>(H) * static_cast<std::size_t>(words_);
    rows_.resize(faces * face_words_);
    bits_.resize(faces * face_words_);
    const std::size_t words = static_cast<std::size_t>(words_);
    const int rows = static_cast<int>(faces) * H;
    // Each row's bits, dilated by one texel along the row (a carry across word boundaries).
    tbb::parallel_for(tbb::blocked_range<int>(0, rows, 32), [&](const tbb::blocked_range<int>& r) {
        std::vector<std::uint64_t> own(words);
        for (int fy = r.begin(); fy != r.end(); ++fy) {
            const std::size_t f = static_cast<std::size_t>(fy / H);
            const int y = fy % H;
            const GBuffer& g = receivers.maps[f];
            const float* flux = caustic[f].pixels.data() + g.index(0, y);
            const std::int32_t* id = g.id.data() + g.index(0, y);
            for (std::size_t w = 0; w < words; ++w) {
                const int x = static_cast<int>(w) * 64;
                own[w] = texel_bits(flux + x, id + x, std::min(64, W - x));
            }
            std::uint64_t* out = rows_.data() + static_cast<std::size_t>(fy) * words;
            for (std::size_t w = 0; w < words; ++w) {
                std::uint64_t d = own[w] | (own[w] << 1) | (own[w] >> 1);
                if (w > 0) d |= own[w - 1] >> 63;
                if (w + 1 < words) d |= own[w + 1] << 63;
                out[w] = d;
            }
        }
    });
    // Across rows, within each face.
    tbb::parallel_for(tbb::blocked_range<int>(0, rows, 64), [&](const tbb::blocked_range<int>& r) {
        for (int fy = r.begin(); fy != r.end(); ++fy) {
            const int y = fy % H;
            const std::uint64_t* mid = rows_.data() + static_cast<std::size_t>(fy) * words;
            const std::uint64_t* up = y > 0 ? mid - words : mid;
            const std::uint64_t* down = y + 1 < H ? mid + words : mid;
            std::uint64_t* out = bits_.data() + static_cast<std::size_t>(fy) * words;
            for (std::size_t w = 0; w < words; ++w) out[w] = up[w] | mid[w] | down[w];
        }
    });
}

bool LookupMask::any(const std::uint64_t* face, int words, int x0, int y0, int x1, int y1) {
    const int w0 = x0 >> 6, w1 = x1 >> 6;
    const std::uint64_t first = ~std::uint64_t{0} << (x0 & 63), last = ~std::uint64_t{0} >> (63 - (x1 & 63));
    for (int y = y0; y <= y1; ++y) {
        const std::uint64_t* row = face + static_cast<std::size_t>(y) * static_cast<std::size_t>(words);
        if (w0 == w1) {
            if (row[w0] & first & last) return true;
            continue;
        }
        if ((row[w0] & first) || (row[w1] & last)) return true;
        for (int w = w0 + 1; w < w1; ++w)
            if (row[w]) return true;
    }
    return false;
}

}  // namespace caustics::caustic_mapping
