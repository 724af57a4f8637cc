// The reference's sums stay the same bits across speed work on the light tracer (issue 18): cache
// entries of the same kReferenceVersion stay valid only if the same seed and settings still give the
// same integer sums and the same flux ledger. The hashes below were computed with the tracer as it was
// before that work (commit e5aa3c1); a change of the transport or the estimators that changes them on
// purpose must bump kReferenceVersion (reference_cache.cpp) and update them here.
#include <cmath>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include <caustics/frame/camera.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/reference/reference_rays.hpp>
#include <caustics/util/hash.hpp>
#include "reference_support.hpp"

using namespace caustics;
using namespace caustics::test_support;

namespace {

// Every integer sum and every ledger double, bit for bit.
std::string hash_sums(const ReferenceSums& s) {
    Hash128 h;
    h.u64(s.per_replica);
    h.u64(s.replicas);
    h.u64(s.lights);
    h.bytes(s.bin_sums.data(), s.bin_sums.size() * sizeof(std::int64_t));
    h.bytes(s.pixel_sums.data(), s.pixel_sums.size() * sizeof(std::int64_t));
    h.bytes(s.volume_sums.data(), s.volume_sums.size() * sizeof(std::int64_t));
    const FluxLedger& l = s.ledger_units;
    for (double v : {l.emitted, l.deposited_receiver, l.deposited_other, l.direct, l.escaped, l.absorbed,
                     l.scattered, l.truncated})
        h.f64(v);
    return h.hex();
}

std::string reference_hash(const std::string& scene_file, bool camera_view, SamplerKind sampler,
                           std::uint64_t photons) {
    const TracedScene ts(load_scene(scene_path(scene_file)));
    const CameraGBuffer gbuffer = build_camera_gbuffer(*ts.tracer, ts.scene.camera);
    ReferenceSettings settings;
    settings.photons = photons;
    settings.sampler = sampler;
    settings.camera_view = camera_view;
    settings.progress = false;
    const ReferenceResult r = compute_reference(*ts.tracer, *ts.chart, camera_view ? &gbuffer : nullptr, settings);
    return hash_sums(*r.sums);
}

}  // namespace

// Two batches per replica on pool (131072 photons per replica) so that batch boundaries are covered.
TEST(ReferenceBits, PoolSameSumsAsBefore) {
    EXPECT_EQ(reference_hash("pool.json", false, SamplerKind::Sobol, 8 * 70000), "91285762766b48253c143d2482928885");
    EXPECT_EQ(reference_hash("pool.json", true, SamplerKind::Sobol, 8 * 70000), "45c02240dac474e7e300c1b1a10a6318");
    EXPECT_EQ(reference_hash("pool.json", true, SamplerKind::Independent, 8 * 20000), "b8e70ce179eea9e9ef2fe0edc5e7a9fc");
}

TEST(ReferenceBits, SphereAndBunnySameSumsAsBefore) {
    EXPECT_EQ(reference_hash("sphere.json", true, SamplerKind::Sobol, 8 * 20000), "3eb0e399996ea930ccc0d487ed9daa1c");
    EXPECT_EQ(reference_hash("bunny.json", true, SamplerKind::Sobol, 8 * 20000), "95628c61e39f96c916acf890c5f6806f");
}

TEST(ReferenceBits, SphereFogSameSumsAsBefore) {
    EXPECT_EQ(reference_hash("sphere_fog.json", true, SamplerKind::Sobol, 8 * 20000), "857ce368eaccf699a24f909ad6899537");
    EXPECT_EQ(reference_hash("sphere_fog.json", true, SamplerKind::Independent, 8 * 20000), "0430ecd24ae7a9a90e59adc19b08684c");
}

namespace {

bool same_bits(const Hit& a, const Hit& b) {
    auto bits = [](const glm::dvec3& v, const glm::dvec3& w) { return std::memcmp(&v, &w, sizeof v) == 0; };
    return a.valid == b.valid && a.object == b.object && std::memcmp(&a.t, &b.t, sizeof a.t) == 0 &&
           bits(a.position, b.position) && bits(a.geometric_normal, b.geometric_normal) &&
           bits(a.shading_normal, b.shading_normal);
}

// The reference's own rays (closest-hit and visibility) on a scene, through the single-ray and the
// packet forms of the tracer: the same hits, bit for bit.
void expect_batches_match_single_rays(const std::string& scene_file) {
    const TracedScene ts(load_scene(scene_path(scene_file)));
    const CameraGBuffer gbuffer = build_camera_gbuffer(*ts.tracer, ts.scene.camera);
    ReferenceSettings settings;
    settings.photons = 8 * 4000;
    settings.progress = false;
    const std::vector<RecordedRay> rays = record_reference_rays(*ts.tracer, *ts.chart, &gbuffer, settings);
    std::vector<RayQuery> hit_queries, shadow_queries;
    for (const RecordedRay& r : rays) {
        RayQuery q;
        q.origin = {r.origin[0], r.origin[1], r.origin[2]};
        q.dir = {r.dir[0], r.dir[1], r.dir[2]};
        q.tmin = r.tnear;
        q.tmax = std::isinf(r.tfar) ? 1e30 : r.tfar;
        (r.shadow ? shadow_queries : hit_queries).push_back(q);
    }
    // Empty segments (tmax <= tmin) are part of the contract too.
    shadow_queries.push_back({{0.0, 0.0, 0.5}, {0.0, 0.0, -1.0}, 0.3, 0.2});
    ASSERT_GT(hit_queries.size(), 10000u) << scene_file;
    std::vector<Hit> hits(hit_queries.size());
    ts.tracer->intersect(hit_queries.data(), hit_queries.size(), hits.data());
    std::size_t valid = 0, mismatches = 0;
    for (std::size_t k = 0; k < hit_queries.size(); ++k) {
        const RayQuery& q = hit_queries[k];
        const Hit single = ts.tracer->intersect(q.origin, q.dir, q.tmin, q.tmax);
        valid += single.valid ? 1 : 0;
        mismatches += same_bits(single, hits[k]) ? 0 : 1;
    }
    EXPECT_EQ(mismatches, 0u) << scene_file << ": " << hit_queries.size() << " closest-hit queries";
    EXPECT_GT(valid, hit_queries.size() / 4) << scene_file;
    std::vector<std::uint8_t> occluded(shadow_queries.size());
    ts.tracer->occluded(shadow_queries.data(), shadow_queries.size(), occluded.data());
    std::size_t occluded_count = 0;
    mismatches = 0;
    for (std::size_t k = 0; k < shadow_queries.size(); ++k) {
        const RayQuery& q = shadow_queries[k];
        const bool single = ts.tracer->occluded(q.origin, q.dir, q.tmin, q.tmax);
        occluded_count += single ? 1 : 0;
        mismatches += single == (occluded[k] != 0) ? 0 : 1;
    }
    EXPECT_EQ(mismatches, 0u) << scene_file << ": " << shadow_queries.size() << " visibility queries";
    EXPECT_EQ(occluded.back(), 0u);
}

}  // namespace

TEST(RayTracerBatches, SameHitsAsSingleRays) {
    for (const char* scene : {"pool.json", "sphere.json", "bunny.json", "sphere_fog.json"})
        expect_batches_match_single_rays(scene);
}
