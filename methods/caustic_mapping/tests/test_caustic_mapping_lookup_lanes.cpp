// caustic_mapping: the lookups' front half in lanes (lookup_lanes.hpp) against the scalar operations it
// stands for, bit for bit: glm::dot of p - eye with the view's axes, then 1 / depth and the texel
// coordinates. Row lengths 1 to 17 and 1027 (the vector loops' remainders), orthographic and perspective
// views, points behind the eye, at its depth (a division by 0), huge and NaN.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "../lookup_lanes.hpp"

using namespace caustics;
using namespace caustics::caustic_mapping;

namespace {

bool same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0; }

// The scalar definition (lookup.cpp's to_view and project).
struct Expected {
    glm::dvec3 v;
    double inv_depth, px, py;
};

Expected scalar(const ViewProjection& view, bool perspective, const glm::dvec3& v) {
    Expected e{v, 1.0, 0.0, 0.0};
    double x = v.x, y = v.y;
    if (perspective) {
        e.inv_depth = 1.0 / v.z;
        x *= e.inv_depth;
        y *= e.inv_depth;
    }
    e.px = (x - view.x0) * view.sx, e.py = (view.y1 - y) * view.sy;
    return e;
}

Expected scalar_world(const ViewProjection& view, bool perspective, const glm::vec3& p) {
    const glm::dvec3 d = glm::dvec3(p) - view.eye;
    return scalar(view, perspective, {glm::dot(d, view.right), glm::dot(d, view.up), glm::dot(d, view.forward)});
}

void expect_lane(const RowLanes& r, std::size_t i, const Expected& e, const char* what) {
    EXPECT_TRUE(same(r.vx[i], e.v.x) && same(r.vy[i], e.v.y) && same(r.vz[i], e.v.z)) << what << " point " << i;
    EXPECT_TRUE(same(r.inv_depth[i], e.inv_depth)) << what << " point " << i;
    EXPECT_TRUE(same(r.px[i], e.px) && same(r.py[i], e.py)) << what << " point " << i;
}

ViewProjection tilted_view() {
    ViewProjection v;
    v.eye = {0.6, -0.4, 3.0};
    v.forward = glm::normalize(glm::dvec3(-0.2, 0.13, -1.0));
    v.right = glm::normalize(glm::cross(v.forward, glm::dvec3(0, 0, 1) + glm::dvec3(0.01, 0.0, 0.0)));
    v.up = glm::cross(v.right, v.forward);
    v.x0 = -0.731, v.y1 = 0.6173, v.sx = 541.37, v.sy = 529.91;
    return v;
}

// World points around the view: most in front, some behind the eye, one at the eye's depth, huge, NaN.
std::vector<glm::vec3> points(const ViewProjection& view, int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-3.0f, 3.0f);
    std::vector<glm::vec3> p(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        glm::vec3& q = p[static_cast<std::size_t>(i)];
        q = {u(rng), u(rng), u(rng)};
        switch (i % 13) {
            case 5: q = glm::vec3(view.eye + 0.5 * view.right); break;   // depth 0
            case 7: q.x = 1e30f; break;
            case 11: q.y = std::numeric_limits<float>::quiet_NaN(); break;
            default: break;
        }
    }
    return p;
}

TEST(LookupLanes, RowsEqualTheScalarProjection) {
    std::mt19937 rng(3);
    const ViewProjection view = tilted_view();
    std::vector<int> lengths;
    for (int n = 1; n <= 17; ++n) lengths.push_back(n);
    lengths.push_back(1027);
    for (bool perspective : {false, true})
        for (int n : lengths) {
            const std::vector<glm::vec3> p = points(view, n, rng);
            RowLanes r;
            r.resize(static_cast<std::size_t>(n));
            project_row(view, perspective, p.data(), n, r);
            for (int i = 0; i < n; ++i)
                expect_lane(r, static_cast<std::size_t>(i), scalar_world(view, perspective, p[static_cast<std::size_t>(i)]),
                            perspective ? "perspective row" : "orthographic row");
        }
}

TEST(LookupLanes, BinRowsEqualTheScalarProjection) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    const ViewProjection view = tilted_view();
    for (bool perspective : {false, true})
        for (int n = 1; n <= 17; ++n)
            for (int k = 0; k < 20; ++k) {
                const glm::dvec3 left(u(rng), u(rng), k == 3 ? 0.0 : u(rng) + 2.0), step(u(rng) * 0.01, u(rng) * 0.01, k == 4 ? -1.0 : u(rng) * 0.01);
                RowLanes r;
                r.resize(static_cast<std::size_t>(n));
                project_samples(view, perspective, left, step, n, r);
                for (int a = 0; a < n; ++a)
                    expect_lane(r, static_cast<std::size_t>(a), scalar(view, perspective, left + (a + 0.5) * step),
                                perspective ? "perspective bin row" : "orthographic bin row");
            }
}

}  // namespace
