#include "splats.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace caustics::caustic_mapping {

namespace {

// The landing point of texel (x, y) when it lands on `face`, else null.
const Splat* landed(const std::vector<FaceSplat>& landing, int g, int x, int y, int face) {
    if (x < 0 || y < 0 || x >= g || y >= g) return nullptr;
    const FaceSplat& o = landing[static_cast<std::size_t>(y) * g + x];
    return o.splat.value > 0.0f && o.face == face ? &o.splat : nullptr;
}

// Landing-point spacing along the grid offset (dx, dy): the length of lattice_step.
bool spacing(const std::vector<FaceSplat>& landing, int g, int x, int y, int dx, int dy, float& len) {
    glm::vec2 d;
    if (!lattice_step(landing, g, x, y, dx, dy, d)) return false;
    len = glm::length(d);
    return true;
}

}  // namespace

bool lattice_step(const std::vector<FaceSplat>& landing, int grid, int x, int y, int dx, int dy, glm::vec2& step) {
    const FaceSplat& c = landing[static_cast<std::size_t>(y) * grid + x];
    const Splat* p = landed(landing, grid, x + dx, y + dy, c.face);
    const Splat* m = landed(landing, grid, x - dx, y - dy, c.face);
    if (p && m) step = 0.5f * (p->pixel - m->pixel);
    else if (p) step = p->pixel - c.splat.pixel;
    else if (m) step = c.splat.pixel - m->pixel;
    else return false;
    return true;
}

bool adaptive_radius(const std::vector<FaceSplat>& landing, int grid, int x, int y, float min_radius, float& radius) {
    const int g = grid;
    const FaceSplat& fs = landing[static_cast<std::size_t>(y) * g + x];
    const int face = fs.face;
    const Splat& c = fs.splat;
    // The larger spacing of the lattice around texel (x, y) from whatever neighbours land.
    auto larger_spacing = [&](float& s) {
        float sx = 0.0f, sy = 0.0f;
        const bool hx = spacing(landing, g, x, y, 1, 0, sx), hy = spacing(landing, g, x, y, 0, 1, sy);
        s = std::max(sx, sy);
        if (hx && hy) return true;
        // An axis without neighbours (the object's silhouette in the grid, or next to rays lost to TIR or
        // a null value): the diagonals J (1, 1) and J (1, -1) bound the larger column of J from above
        // (parallelogram law: |J(1,1)|^2 + |J(1,-1)|^2 = 2 (|J(1,0)|^2 + |J(0,1)|^2)), so the splat
        // errs on the wide side instead of collapsing to the minimum where grazing rays spread the most.
        float d = 0.0f;
        bool found = hx || hy;
        if (spacing(landing, g, x, y, 1, 1, d)) s = std::max(s, d), found = true;
        if (spacing(landing, g, x, y, 1, -1, d)) s = std::max(s, d), found = true;
        if (found) return true;
        // No neighbour at all: the mean spacing to the landing points on the nearest ring of texels
        // (Chebyshev distance k) that has any, the largest over that ring.
        for (int k = 2; k <= kNeighbourSearch; ++k) {
            for (int j = -k; j <= k; ++j)
                for (int i = -k; i <= k; ++i) {
                    if (std::max(std::abs(i), std::abs(j)) != k) continue;
                    const Splat* n = landed(landing, g, x + i, y + j, face);
                    if (!n) continue;
                    s = std::max(s, glm::length(n->pixel - c.pixel) / std::sqrt(static_cast<float>(i * i + j * j)));
                    found = true;
                }
            if (found) return true;
        }
        return false;
    };
    float s = 0.0f;
    const bool found = larger_spacing(s);
    radius = std::clamp(kAdaptiveScale * s, min_radius, kMaxAdaptiveRadius);
    return found;
}

int build_splats(const std::vector<FaceSplat>& landing, int grid, FootprintMode mode, float radius,
                 std::vector<std::vector<Splat>>& per_face) {
    for (auto& v : per_face) v.clear();
    const int g = grid;
    int isolated = 0;
    for (int y = 0; y < g; ++y)
        for (int x = 0; x < g; ++x) {
            const FaceSplat& fs = landing[static_cast<std::size_t>(y) * g + x];
            if (!(fs.splat.value > 0.0f)) continue;
            Splat sp = fs.splat;
            sp.radius = radius;
            if (mode == FootprintMode::Adaptive && !adaptive_radius(landing, g, x, y, radius, sp.radius))
                ++isolated;   // kept at the minimum footprint
            per_face[static_cast<std::size_t>(fs.face)].push_back(sp);
        }
    return isolated;
}

}  // namespace caustics::caustic_mapping
