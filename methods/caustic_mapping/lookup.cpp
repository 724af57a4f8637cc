#include "lookup.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics::caustic_mapping {

PreparedLookup prepare_lookup(const PositionsTexture& receivers, const glm::dvec3& p, const glm::dvec3& n,
                              double depth_bias) {
    PreparedLookup l;
    Texel t;
    if (!receivers.locate(p, t)) return l;
    const std::size_t f = static_cast<std::size_t>(t.face);
    const LightProjection& view = receivers.faces[f];
    const GBuffer& g = receivers.maps[f];
    const int W = g.width, H = g.height;
    const int ix = std::clamp(static_cast<int>(t.px), 0, W - 1), iy = std::clamp(static_cast<int>(t.py), 0, H - 1);
    l.face = static_cast<std::uint32_t>(f);
    l.texel = static_cast<std::uint32_t>(g.index(ix, iy));
    // Bilinear between texel centres, clamped at the borders (x0 <= W - 2: the map is at least 2 wide).
    const double fx = std::clamp(t.px - 0.5, 0.0, W - 1.0), fy = std::clamp(t.py - 0.5, 0.0, H - 1.0);
    const int x0 = std::min(static_cast<int>(fx), W - 2), y0 = std::min(static_cast<int>(fy), H - 2);
    l.corner = static_cast<std::uint32_t>(g.index(x0, y0));
    l.ax = static_cast<float>(fx - x0);
    l.ay = static_cast<float>(fy - y0);
    // Shadow-map depth test with a slope-scaled bias of about two texels.
    const glm::dvec3 to = view.type == ProjectionType::Perspective ? glm::normalize(p - view.eye) : view.forward;
    const double c = std::max(std::abs(glm::dot(n, to)), 0.05);
    const double texel = std::sqrt(view.texel_area()) * (view.type == ProjectionType::Perspective ? t.depth : 1.0);
    const double bias = depth_bias * 2.0 * texel * (1.0 + std::sqrt(1.0 - c * c) / c);
    l.depth = static_cast<float>(t.depth - bias);
    l.inv_area = static_cast<float>(1.0 / view.surface_texel_area(p, n));
    return l;
}

int auto_bin_samples(const PositionsTexture& receivers, const ReceiverChart& chart) {
    double ratio = 1.0;
    const int W = chart.width(), H = chart.height();
    for (auto [s, t] : {std::pair{0.5, 0.5}, {0.02, 0.02}, {0.98, 0.02}, {0.02, 0.98}, {0.98, 0.98}}) {
        const glm::dvec3 p = chart.point(s, t);
        Texel where;
        if (!receivers.locate(p, where)) continue;
        const double texel = receivers.faces[static_cast<std::size_t>(where.face)].surface_texel_area(p, chart.normal(s, t));
        const int i = std::clamp(static_cast<int>(s * W), 0, W - 1), j = std::clamp(static_cast<int>(t * H), 0, H - 1);
        ratio = std::max(ratio, std::sqrt(chart.bin_area(i, j) / texel));
    }
    return std::clamp(static_cast<int>(std::ceil(ratio - 1e-6)), 1, 16);
}

void prepare_receiver_lookups(LookupSet& set, const PositionsTexture& receivers,
                              const ReceiverChart& chart, int n, double depth_bias) {
    const int W = chart.width(), H = chart.height();
    const std::size_t per_bin = static_cast<std::size_t>(n) * n;
    set.lookups.resize(static_cast<std::size_t>(W) * H * per_bin);
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < W; ++x) {
                PreparedLookup* bin = &set.lookups[(static_cast<std::size_t>(y) * W + x) * per_bin];
                for (int b = 0; b < n; ++b)
                    for (int a = 0; a < n; ++a) {
                        const double s = (x + (a + 0.5) / n) / W, t = (y + (b + 0.5) / n) / H;
                        bin[b * n + a] = prepare_lookup(receivers, chart.point(s, t), chart.normal(s, t), depth_bias);
                    }
            }
    });
}

void prepare_camera_lookups(LookupSet& set, const PositionsTexture& receivers,
                            const CameraGBuffer& gb, double depth_bias) {
    set.lookups.assign(static_cast<std::size_t>(gb.width) * gb.height, PreparedLookup{});
    tbb::parallel_for(tbb::blocked_range<int>(0, gb.height, 4), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < gb.width; ++x) {
                const std::size_t i = gb.index(x, y);
                if (gb.covered[i])
                    set.lookups[i] = prepare_lookup(receivers, glm::dvec3(gb.position[i]), glm::dvec3(gb.normal[i]), depth_bias);
            }
    });
}

}  // namespace caustics::caustic_mapping
