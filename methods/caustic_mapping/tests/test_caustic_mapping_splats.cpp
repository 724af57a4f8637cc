// caustic_mapping: the adaptive splat footprint (methods/caustic_mapping/splats.hpp). The landing points
// of a regular grid through an affine landing map J form a lattice whose spacings along the grid's axes
// are |J (1, 0)| and |J (0, 1)|, so every footprint has a closed form, including those of texels whose
// grid neighbours did not land (the object's silhouette, rays lost to TIR or a null value).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "../elliptic_splats.hpp"
#include "../splats.hpp"
#include <caustics/frame/frame.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/api/registry.hpp>

using namespace caustics;
using namespace caustics::caustic_mapping;

namespace {

constexpr int kGrid = 16;
// The landing map: anisotropic and sheared, spacings |J(1,0)| = 5, |J(0,1)| = sqrt(8) (columns of J).
const glm::vec2 kJx(3.0f, 4.0f), kJy(2.0f, -2.0f);

std::vector<FaceSplat> lattice() {
    std::vector<FaceSplat> landing(static_cast<std::size_t>(kGrid) * kGrid);
    for (int y = 0; y < kGrid; ++y)
        for (int x = 0; x < kGrid; ++x)
            landing[static_cast<std::size_t>(y) * kGrid + x] =
                {0, {glm::vec2(100.0f) + static_cast<float>(x) * kJx + static_cast<float>(y) * kJy, 1.0f}};
    return landing;
}

void drop(std::vector<FaceSplat>& landing, int x, int y) { landing[static_cast<std::size_t>(y) * kGrid + x].splat.value = 0.0f; }

// The footprint of the splat that texel (x, y) produced (splats come in row-major order of the texels).
float radius_of(const std::vector<FaceSplat>& landing, const std::vector<Splat>& splats, int x, int y) {
    std::size_t k = 0;
    for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) {
            if (!(landing[static_cast<std::size_t>(j) * kGrid + i].splat.value > 0.0f)) continue;
            if (i == x && j == y) return splats[k].radius;
            ++k;
        }
    ADD_FAILURE() << "texel " << x << "," << y << " has no splat";
    return 0.0f;
}

float larger_spacing() { return std::max(glm::length(kJx), glm::length(kJy)); }

}  // namespace

TEST(CausticMappingSplats, AdaptiveRadiusFollowsTheLatticeSpacing) {
    const std::vector<FaceSplat> landing = lattice();
    std::vector<std::vector<Splat>> per_face(1);
    EXPECT_EQ(build_splats(landing, kGrid, FootprintMode::Adaptive, 1.0f, per_face), 0);
    ASSERT_EQ(per_face[0].size(), static_cast<std::size_t>(kGrid * kGrid));
    for (const Splat& s : per_face[0]) EXPECT_FLOAT_EQ(s.radius, kAdaptiveScale * larger_spacing());
}

TEST(CausticMappingSplats, MissingAxisNeighboursUseTheDiagonals) {
    // Texel (8, 8) keeps only its diagonal neighbours (a silhouette texel in a staircase). The larger
    // diagonal spacing max |J(1,+-1)| lies in [max(|Jx|, |Jy|), |Jx| + |Jy|]: never the 1-texel minimum.
    std::vector<FaceSplat> landing = lattice();
    for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) drop(landing, 8 + dx, 8 + dy);
    std::vector<std::vector<Splat>> per_face(1);
    EXPECT_EQ(build_splats(landing, kGrid, FootprintMode::Adaptive, 1.0f, per_face), 0);
    const float expected = kAdaptiveScale * std::max(glm::length(kJx + kJy), glm::length(kJx - kJy));
    const float r = radius_of(landing, per_face[0], 8, 8);
    EXPECT_FLOAT_EQ(r, expected);
    EXPECT_GE(r, kAdaptiveScale * larger_spacing());
    EXPECT_LE(r, kAdaptiveScale * (glm::length(kJx) + glm::length(kJy)));
}

TEST(CausticMappingSplats, IsolatedTexelUsesTheNearestLandedRing) {
    // Only texels (2, 2) and (5, 2) land (3 grid texels apart along x): each one's footprint is the
    // spacing that the pair implies, |J (3, 0)| / 3 = |Jx|; its flux is kept.
    std::vector<FaceSplat> landing = lattice();
    for (int y = 0; y < kGrid; ++y)
        for (int x = 0; x < kGrid; ++x)
            if (!(y == 2 && (x == 2 || x == 5))) drop(landing, x, y);
    std::vector<std::vector<Splat>> per_face(1);
    EXPECT_EQ(build_splats(landing, kGrid, FootprintMode::Adaptive, 1.0f, per_face), 0);
    ASSERT_EQ(per_face[0].size(), 2u);
    for (const Splat& s : per_face[0]) {
        EXPECT_NEAR(s.radius, kAdaptiveScale * glm::length(kJx), 1e-4f);
        EXPECT_EQ(s.value, 1.0f);
    }
}

TEST(CausticMappingSplats, LoneTexelKeepsItsFluxAndIsCounted) {
    // Two texels farther apart than the search window, and a third between them that lands on another
    // face (not a neighbour of theirs): no spacing to go by. All keep their flux at the minimum footprint
    // and are counted.
    std::vector<FaceSplat> landing = lattice();
    for (int y = 0; y < kGrid; ++y)
        for (int x = 0; x < kGrid; ++x)
            if (!(y == 1 && (x == 1 || x == 2 + kNeighbourSearch))) drop(landing, x, y);
    landing[1 * kGrid + 2] = {1, {glm::vec2(50.0f), 1.0f}};   // lands on another cube face
    std::vector<std::vector<Splat>> per_face(2);
    EXPECT_EQ(build_splats(landing, kGrid, FootprintMode::Adaptive, 1.5f, per_face), 3);
    ASSERT_EQ(per_face[0].size(), 2u);
    ASSERT_EQ(per_face[1].size(), 1u);
    for (const auto& face : per_face)
        for (const Splat& s : face) {
            EXPECT_FLOAT_EQ(s.radius, 1.5f);
            EXPECT_EQ(s.value, 1.0f);
        }
}

TEST(CausticMappingSplats, FixedModeIgnoresNeighbours) {
    // splat=gaussian / point (the paper's fixed footprint) are untouched by the adaptive rules.
    std::vector<FaceSplat> landing = lattice();
    for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) drop(landing, 8 + dx, 8 + dy);
    std::vector<std::vector<Splat>> per_face(1);
    EXPECT_EQ(build_splats(landing, kGrid, FootprintMode::Fixed, 2.5f, per_face), 0);
    for (const Splat& s : per_face[0]) EXPECT_FLOAT_EQ(s.radius, 2.5f);
}

TEST(CausticMappingSplats, SphereSilhouetteSplatsHaveNeighbours) {
    // sphere.json at the defaults: the grid texels on the sphere's silhouette whose neighbours' rays are
    // lost (exit estimate at the back face's rim) used to fall back to the 1-texel minimum and put their
    // grazing rays' flux into isolated bright dots on the floor. Every splat must now find a spacing.
    Scene scene = load_scene("scenes/sphere.json");
    const MethodInfo& m = require_method("caustic_mapping");
    std::unique_ptr<Method> method = m.create(ParamSet::resolve(m.name, m.params, {}));
    FrameGeometry frame = build_frame_geometry(scene, 0);
    ReceiverChart chart(frame, 64, 64);
    method->prepare(scene);
    method->update(frame);
    RenderRequest request;
    request.receiver = &chart;
    const CausticOutput out = method->render(frame, request);
    EXPECT_GT(out.health.get("splats"), 0);
    EXPECT_EQ(out.health.get("isolated_splats"), 0);
}

// draw_elliptic against a direct double-precision evaluation of its definition: each texel whose centre
// lies inside the 3.5-sigma ellipse gets value exp(-q) / sum of exp(-q) over those texels, q = d^T
// Sigma^-1 d / 2. Narrow (the normalising sum over texels), wide (the closed-form normalisation), clipped,
// and long and sheared at 45 degrees (the largest footprint the clamp allows, 18.3 by 0.6 texels: its
// expanded quadratic form has terms of 1e3 that cancel), narrow with rows longer than one chunk of the
// normalising pass, narrow at the image's last texel (its rows' chunks reach past the image's end), and
// wide and clipped by the image's right and bottom edges (its last chunks too). The weights are computed in single precision
// as a t^2 + c0 with both terms in [0, 6.1] (the cut-off q) and |t| within the chord: a few roundings of
// 6e-8 relative each bound the error of q by about 3e-6, and the exponential's polynomial adds 1.2e-7;
// a texel's value is a weight over a sum of such weights, so its relative error is below 8e-6, the
// tolerance (plus the closed form's 1e-4 where it normalises).
TEST(CausticMappingSplats, EllipticWeightsMatchTheirDefinition) {
    const int W = 160, H = 150;
    const std::vector<EllipticSplat> cases = {
        {{20.3f, 17.8f}, 2.0f, {0.3f, 0.1f, 0.8f}},           // narrow: normalised over the texels
        {{31.6f, 24.2f}, 1.5f, {9.0f, 4.0f, 6.0f}},           // wide, sheared: closed-form normalisation
        {{2.4f, 145.1f}, 3.0f, {16.0f, -3.0f, 4.0f}},         // clipped by the image's corner
        {{80.3f, 74.6f}, 1.0f, {167.3f, 166.9f, 167.3f}},     // long and thin at 45 degrees
        {{139.7f, 60.2f}, 2.5f, {30.0f, 0.4f, 0.3f}},         // narrow, rows of up to 38 texels (several chunks)
        {{157.5f, 146.5f}, 1.0f, {0.3f, 0.1f, 0.8f}},         // narrow, wholly inside, at the last row's end
        {{157.0f, 146.0f}, 2.0f, {16.0f, 2.0f, 9.0f}},        // wide, clipped by the right and bottom edges
    };
    for (const EllipticSplat& s : cases) {
        Image img(W, H);
        const SplatStats st = draw_elliptic({s}, img);
        const double a = s.cov.x, b = s.cov.y, d = s.cov.z, det = a * d - b * b;
        const double ixx = d / det, ixy = -b / det, iyy = a / det;
        const double cut = 0.5 * kEllipticCutoff * kEllipticCutoff;
        auto q_at = [&](int i, int j) {
            const double dx = i + 0.5 - s.pixel.x, dy = j + 0.5 - s.pixel.y;
            return 0.5 * (ixx * dx * dx + 2.0 * ixy * dx * dy + iyy * dy * dy);
        };
        double sum = 0.0, in = 0.0;
        for (int j = -100; j < 300; ++j)
            for (int i = -100; i < 300; ++i)
                if (q_at(i, j) <= cut) {
                    sum += std::exp(-q_at(i, j));
                    if (i >= 0 && j >= 0 && i < W && j < H) in += std::exp(-q_at(i, j));
                }
        // Both eigenvalues >= 1 and the support inside the image: the closed-form normalisation.
        const double minor = 0.5 * (a + d) - std::sqrt(0.25 * (a - d) * (a - d) + b * b);
        const bool wide = minor >= 1.0 && in == sum;
        // The closed form stands for the sum to within 1e-4 (elliptic_splats.cpp): the wide case's
        // texels are compared after dividing out the normalisation.
        const double norm_tol = (wide ? 1e-4 : 0.0) + 8e-6;
        double drawn = 0.0;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const double want = q_at(i, j) <= cut ? s.value * std::exp(-q_at(i, j)) / sum : 0.0;
                const double got = img.at(i, j);
                drawn += got;
                if (want == 0.0) {
                    // A centre within rounding of the ellipse may fall on either side: its weight is exp(-6.1).
                    if (got != 0.0) {
                        EXPECT_NEAR(q_at(i, j), cut, 1e-5) << i << "," << j;
                    }
                    continue;
                }
                EXPECT_NEAR(got / want, 1.0, norm_tol) << "texel " << i << "," << j;
            }
        EXPECT_NEAR(drawn, s.value * in / sum, s.value * norm_tol);
        EXPECT_EQ(st.splatted, 1);
        EXPECT_NEAR(st.value_inside, s.value * in / sum, s.value * norm_tol);
    }
}

namespace {

// count random splats over a W x H image and 10 texels around it: narrow, wide, clipped and off-image.
std::vector<EllipticSplat> random_splats(int count, int W, int H, std::uint32_t state) {
    std::vector<EllipticSplat> splats;
    auto uniform = [&] {
        state = state * 1664525u + 1013904223u;
        return static_cast<float>(state >> 8) / 16777216.0f;
    };
    for (int k = 0; k < count; ++k) {
        const float major = 0.05f + 6.0f * uniform(), minor = 0.05f + (k % 3 == 0 ? 2.0f : 0.6f) * uniform();
        const float angle = 3.14159f * uniform(), c = std::cos(angle), s = std::sin(angle);
        const glm::vec3 cov(major * c * c + minor * s * s, (major - minor) * c * s, major * s * s + minor * c * c);
        splats.push_back({{-10.0f + (W + 20.0f) * uniform(), -10.0f + (H + 20.0f) * uniform()}, 0.5f + uniform(), cov});
    }
    return splats;
}

}  // namespace

// Many splats in one call (more than one group of kept weights, several bands, narrow ones whose
// weights are kept and reused, wide, clipped and off-image ones recomputed) give exactly the image of
// drawing them one at a time in the same order: every texel receives the same values in the same order.
TEST(CausticMappingSplats, EllipticBatchEqualsOneAtATime) {
    const int W = 200, H = 120;
    const std::vector<EllipticSplat> splats = random_splats(700, W, H, 12345u);
    Image batch(W, H), single(W, H);
    const SplatStats st = draw_elliptic(splats, batch);
    for (const EllipticSplat& s : splats) draw_elliptic({s}, single);
    EXPECT_GT(st.splatted, 600);
    EXPECT_GT(st.value_outside, 0.0);   // some footprints are clipped by the image's edges
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) ASSERT_EQ(batch.at(i, j), single.at(i, j)) << i << "," << j;
}

// A splatter keeps its buffers between draws: draws of different sizes in sequence (larger, then smaller
// with splats that are not drawn, then an image of another size) give exactly the images of fresh draws.
TEST(CausticMappingSplats, EllipticSplatterReusedEqualsFresh) {
    std::vector<EllipticSplat> with_invalid = random_splats(150, 90, 70, 777u);
    with_invalid[3].pixel.x = std::numeric_limits<float>::quiet_NaN();   // not finite: not drawn
    with_invalid[40].cov = glm::vec3(1.0f, 2.0f, 1.0f);                   // not positive definite
    const struct {
        std::vector<EllipticSplat> splats;
        int W, H;
    } draws[] = {{random_splats(900, 200, 120, 99u), 200, 120}, {with_invalid, 90, 70}, {random_splats(600, 300, 40, 5u), 300, 40}};
    EllipticSplatter reused;
    for (const auto& d : draws) {
        Image a(d.W, d.H), b(d.W, d.H);
        const SplatStats sa = reused.draw(d.splats, a), sb = draw_elliptic(d.splats, b);
        EXPECT_EQ(sa.splatted, sb.splatted);
        EXPECT_EQ(sa.outside, sb.outside);
        EXPECT_EQ(sa.nonfinite, sb.nonfinite);
        EXPECT_EQ(sa.value_inside, sb.value_inside);
        EXPECT_EQ(sa.value_outside, sb.value_outside);
        EXPECT_GT(sa.splatted, 100);
        for (int j = 0; j < d.H; ++j)
            for (int i = 0; i < d.W; ++i) ASSERT_EQ(a.at(i, j), b.at(i, j)) << i << "," << j;
    }
}

// build_elliptic_splats against its rule, texel by texel, on a 64 x 64 lattice over two faces with
// holes and lone texels (its rows are built in parallel into slots counted beforehand): each face's
// splats in row-major order of its landed texels, with their landing point and flux; covariance
// s^2 J J^T + sigma0^2 I from central (or one-sided) differences where both axes have a landed
// neighbour on the same face, else isotropic from build_splats' adaptive footprint; the isolated count
// equal to build_splats'. The lattice's spacings (5 and 2.8 texels) keep every covariance inside the
// clamp's range, so the rule's values are compared exactly.
TEST(CausticMappingSplats, EllipticSplatsFollowTheirRule) {
    const int g = 64;
    std::vector<FaceSplat> landing(static_cast<std::size_t>(g) * g);
    for (int y = 0; y < g; ++y)
        for (int x = 0; x < g; ++x) {
            const int face = (x / 20 + y / 24) % 2;   // patches of two faces
            const bool hole = (x * 7 + y * 13) % 11 == 0 || (x > 40 && x < 44);
            const bool lone = (x == 50 && y == 10) || (x == 2 && y == 60);
            const bool ring = std::abs(x - 50) <= 3 && std::abs(y - 10) <= 3 && !(x == 50 && y == 10);
            const float value = hole || ring ? 0.0f : 1.0f + 0.01f * static_cast<float>(x + y);
            landing[static_cast<std::size_t>(y) * g + x] = {
                lone ? 1 : face, {glm::vec2(10.0f) + static_cast<float>(x) * kJx + static_cast<float>(y) * kJy, lone ? 2.0f : value}};
        }
    const float min_radius = 1.0f, sigma0 = min_radius / kEllipticCutoff;
    std::vector<std::vector<EllipticSplat>> got(2);
    std::vector<std::vector<Splat>> iso(2);
    const int isolated = build_elliptic_splats(landing, g, kEllipticSigma, min_radius, got);
    EXPECT_EQ(isolated, build_splats(landing, g, FootprintMode::Adaptive, min_radius, iso));
    EXPECT_GE(isolated, 1);   // the lone texels
    auto at = [&](int x, int y, int face) -> const FaceSplat* {
        if (x < 0 || y < 0 || x >= g || y >= g) return nullptr;
        const FaceSplat& o = landing[static_cast<std::size_t>(y) * g + x];
        return o.splat.value > 0.0f && o.face == face ? &o : nullptr;
    };
    auto column = [&](int x, int y, int face, int dx, int dy, glm::vec2& j) {
        const FaceSplat* p = at(x + dx, y + dy, face);
        const FaceSplat* m = at(x - dx, y - dy, face);
        const glm::vec2 c = landing[static_cast<std::size_t>(y) * g + x].splat.pixel;
        if (p && m) j = 0.5f * (p->splat.pixel - m->splat.pixel);
        else if (p) j = p->splat.pixel - c;
        else if (m) j = c - m->splat.pixel;
        else return false;
        return true;
    };
    std::size_t next[2] = {0, 0};
    int anisotropic = 0, fallback = 0;
    for (int y = 0; y < g; ++y)
        for (int x = 0; x < g; ++x) {
            const FaceSplat& fs = landing[static_cast<std::size_t>(y) * g + x];
            if (!(fs.splat.value > 0.0f)) continue;
            const std::size_t f = static_cast<std::size_t>(fs.face);
            ASSERT_LT(next[f], got[f].size());
            const EllipticSplat& s = got[f][next[f]];
            const Splat& is = iso[f][next[f]++];
            EXPECT_EQ(s.pixel, fs.splat.pixel) << x << "," << y;
            EXPECT_EQ(s.value, fs.splat.value) << x << "," << y;
            glm::vec2 jx, jy;
            glm::vec3 want;
            if (column(x, y, fs.face, 1, 0, jx) && column(x, y, fs.face, 0, 1, jy)) {
                const float s2 = kEllipticSigma * kEllipticSigma, o2 = sigma0 * sigma0;
                want = {s2 * (jx.x * jx.x + jy.x * jy.x) + o2, s2 * (jx.x * jx.y + jy.x * jy.y), s2 * (jx.y * jx.y + jy.y * jy.y) + o2};
                ++anisotropic;
            } else {
                const float r = is.radius / kEllipticCutoff;
                want = {r * r, 0.0f, r * r};
                ++fallback;
            }
            EXPECT_EQ(s.cov, want) << x << "," << y;
        }
    EXPECT_EQ(next[0], got[0].size());
    EXPECT_EQ(next[1], got[1].size());
    EXPECT_GT(anisotropic, 1000);
    EXPECT_GT(fallback, 50);
}

// The drawing passes write whole chunks of 8 texels; the lanes past a row's end must leave their texels'
// bits alone (not add 0, which would turn -0 into +0). On an image filled with -0, every texel whose
// centre lies clearly outside the footprint's cut-off ellipse still holds -0 after the draw: rows ending
// inside the image, at its right edge and at its last texel, narrow (kept weights) and wide (recomputed).
TEST(CausticMappingSplats, EllipticTexelsOutsideTheFootprintKeepTheirBits) {
    const int W = 64, H = 48;
    const std::vector<EllipticSplat> cases = {
        {{20.3f, 17.8f}, 2.0f, {0.3f, 0.1f, 0.8f}},      // narrow, rows of 1-3 texels
        {{45.2f, 20.1f}, 1.0f, {30.0f, 0.4f, 0.3f}},     // narrow, rows up to 38 texels
        {{61.5f, 46.5f}, 1.0f, {0.3f, 0.1f, 0.8f}},      // narrow, at the last texel
        {{30.4f, 24.7f}, 1.5f, {9.0f, 4.0f, 6.0f}},      // wide, rows ending inside
        {{61.0f, 44.0f}, 2.0f, {16.0f, 2.0f, 9.0f}},     // wide, clipped by the right and bottom edges
    };
    for (const EllipticSplat& s : cases) {
        Image img(W, H);
        std::fill(img.pixels.begin(), img.pixels.end(), -0.0f);
        draw_elliptic({s}, img);
        const double a = s.cov.x, b = s.cov.y, d = s.cov.z, det = a * d - b * b;
        const double cut = 0.5 * kEllipticCutoff * kEllipticCutoff;
        int outside = 0, drawn = 0;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const double dx = i + 0.5 - s.pixel.x, dy = j + 0.5 - s.pixel.y;
                const double q = 0.5 * (d * dx * dx - 2.0 * b * dx * dy + a * dy * dy) / det;
                if (q <= cut + 1e-5) {
                    drawn += img.at(i, j) > 0.0f;
                    continue;
                }
                ++outside;
                ASSERT_TRUE(img.at(i, j) == 0.0f && std::signbit(img.at(i, j))) << "texel " << i << "," << j;
            }
        EXPECT_GT(outside, 0);
        EXPECT_GT(drawn, 0);
    }
}

// Splats that cannot be drawn are refused and counted, and leave the image alone: a covariance with a
// positive determinant that is not positive definite, a support reaching past 4096 texels (which would
// take seconds to normalise), and a flux whose normalised value overflows float (a footprint whose one
// texel centre has weight e^-4).
TEST(CausticMappingSplats, EllipticRefusesWhatItCannotDraw) {
    const std::vector<EllipticSplat> refused = {
        {{10.0f, 10.0f}, 1.0f, {-1.0f, 0.0f, -2.0f}},
        {{10.0f, 10.0f}, 1.0f, {1e9f, 0.0f, 1e9f}},
        {{10.3f, 10.3f}, 3.0e38f, {0.01f, 0.0f, 0.01f}},
    };
    Image img(32, 32);
    const SplatStats st = draw_elliptic(refused, img);
    EXPECT_EQ(st.nonfinite, 3);
    EXPECT_EQ(st.splatted, 0);
    for (float v : img.pixels) ASSERT_EQ(v, 0.0f);
    // The same flux on a footprint whose weights sum to more than 1 is drawn.
    const SplatStats ok = draw_elliptic({{{10.5f, 10.5f}, 3.0e38f, {0.3f, 0.0f, 0.3f}}}, img);
    EXPECT_EQ(ok.splatted, 1);
    EXPECT_EQ(ok.nonfinite, 0);
}
