#include "splats.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace caustics::caustic_mapping {

void build_splats(const std::vector<FaceSplat>& landing, int grid, FootprintMode mode, float radius,
                  std::vector<std::vector<Splat>>& per_face) {
    for (auto& v : per_face) v.clear();
    const int g = grid;
    // The landing point of texel (x, y) when it lands on `face`, else null.
    auto at = [&](int x, int y, int face) -> const Splat* {
        if (x < 0 || y < 0 || x >= g || y >= g) return nullptr;
        const FaceSplat& o = landing[static_cast<std::size_t>(y) * g + x];
        return o.splat.value > 0.0f && o.face == face ? &o.splat : nullptr;
    };
    // Landing-point spacing along the grid's (dx, dy): central difference, one-sided at an edge of the
    // lit region; false when neither neighbour lands on the same face.
    auto spacing = [&](int x, int y, int face, const Splat& c, int dx, int dy, float& len) {
        const Splat* p = at(x + dx, y + dy, face);
        const Splat* m = at(x - dx, y - dy, face);
        glm::vec2 d;
        if (p && m) d = 0.5f * (p->pixel - m->pixel);
        else if (p) d = p->pixel - c.pixel;
        else if (m) d = c.pixel - m->pixel;
        else return false;
        len = glm::length(d);
        return true;
    };
    for (int y = 0; y < g; ++y)
        for (int x = 0; x < g; ++x) {
            const FaceSplat& fs = landing[static_cast<std::size_t>(y) * g + x];
            if (!(fs.splat.value > 0.0f)) continue;
            Splat sp = fs.splat;
            sp.radius = radius;
            if (mode == FootprintMode::Adaptive) {
                float sx = 0.0f, sy = 0.0f;
                spacing(x, y, fs.face, sp, 1, 0, sx);
                spacing(x, y, fs.face, sp, 0, 1, sy);
                sp.radius = std::clamp(kAdaptiveScale * std::max(sx, sy), radius, kMaxAdaptiveRadius);
            }
            per_face[static_cast<std::size_t>(fs.face)].push_back(sp);
        }
}

}  // namespace caustics::caustic_mapping
