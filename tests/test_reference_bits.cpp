// The reference's sums stay the same bits across speed work on the light tracer (issue 18): cache
// entries of the same kReferenceVersion stay valid only if the same seed and settings still give the
// same integer sums and the same flux ledger. The hashes below were computed with the tracer as it was
// before that work (commit e5aa3c1, its test at 24ebad5); a change of the transport or the estimators
// that changes them on purpose must bump kReferenceVersion (reference_cache.cpp) and update them here.
// Version 5 (a point light's azimuth cos and sin from libmvec, util/vector_sincos.hpp) moved the
// directions' last bits; of these sums only sphere_fog's Sobol' ones under the AVX-512 kernels changed
// (both recorded: a build without libmvec keeps the old ones; every other hash, also under the AVX2
// kernels, stayed the same).
//
// Embree picks its traversal kernels by the CPU's instruction set at run time, and its AVX-512 and AVX2
// kernels round some hits' last bits differently, so the sums' bits depend on the CPU: the hashes are
// recorded for both (the AVX2 ones by 24ebad5's test on an AVX2 machine, equal to those of the current
// tracer there). On a CPU with neither the sums are not pinned (the test says so and skips). Embree
// limited to its AVX2 kernels on a CPU with AVX-512 (CAUSTICS_EMBREE_CONFIG=isa=avx2) does not give the AVX2
// machine's bits on every such CPU: on a Xeon with AVX-512 IFMA and VBMI (Embree 3.13.5: "Unknown CPU") 24
// of the 26 hash checks differed from both recorded sets, while the native AVX-512 ones matched. So the AVX2
// hashes are checked on AVX2 machines only; ctest's Avx2Kernels.* copies (tests/CMakeLists.txt) keep the
// RayTracerBatches cases, which compare batches with single rays and hold under any kernels.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/frame/camera.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/reference/photon_source.hpp>
#include <caustics/reference/reference_rays.hpp>
#include <caustics/util/hash.hpp>
#include <caustics/util/vector_sincos.hpp>
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
                           std::uint64_t photons, std::optional<QueryMode> mode) {
    const TracedScene ts(load_scene(scene_path(scene_file)));
    const CameraGBuffer gbuffer = build_camera_gbuffer(*ts.tracer, ts.scene.camera);
    ReferenceSettings settings;
    settings.photons = photons;
    settings.sampler = sampler;
    settings.camera_view = camera_view;
    settings.progress = false;
    settings.query_mode = mode;
    const ReferenceResult r = compute_reference(*ts.tracer, *ts.chart, camera_view ? &gbuffer : nullptr, settings);
    return hash_sums(*r.sums);
}

// The instruction set of Embree's kernels on this CPU (Embree 3.13's AVX512SKX needs AVX-512 F, CD, DQ,
// BW and VL), or AVX2 where the device configuration limits Embree to it.
enum class EmbreeIsa { Avx512, Avx2, Other };

// Whether CAUSTICS_EMBREE_CONFIG (Embree's comma-separated device configuration) sets isa or max_isa to
// avx2; any other isa setting leaves the CPU's own kernels expected.
bool config_limits_to_avx2() {
    const char* config = std::getenv("CAUSTICS_EMBREE_CONFIG");
    if (!config) return false;
    std::string c(config);
    c.erase(std::remove(c.begin(), c.end(), ' '), c.end());
    for (std::size_t begin = 0; begin <= c.size();) {
        const std::size_t end = std::min(c.find(',', begin), c.size());
        const std::string token = c.substr(begin, end - begin);
        if (token == "isa=avx2" || token == "max_isa=avx2") return true;
        begin = end + 1;
    }
    return false;
}

bool cpu_has_avx512() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
           __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
#else
    return false;
#endif
}

EmbreeIsa embree_isa() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (cpu_has_avx512()) return config_limits_to_avx2() ? EmbreeIsa::Avx2 : EmbreeIsa::Avx512;
    if (__builtin_cpu_supports("avx2")) return EmbreeIsa::Avx2;
#endif
    return EmbreeIsa::Other;
}

// The hash recorded for this CPU's kernels, or "" where none is.
std::string recorded(const char* avx512, const char* avx2) {
    switch (embree_isa()) {
        case EmbreeIsa::Avx512: return avx512;
        case EmbreeIsa::Avx2: return avx2;
        default: return "";
    }
}

// The recorded hash, with the query mode chosen by timing (the default) and with each mode pinned: the
// modes must not change the sums.
void expect_hash(const std::string& scene_file, bool camera_view, SamplerKind sampler, std::uint64_t photons,
                 const std::string& expected) {
    EXPECT_EQ(reference_hash(scene_file, camera_view, sampler, photons, std::nullopt), expected) << scene_file;
    for (QueryMode mode : {QueryMode::Single, QueryMode::Packet8, QueryMode::Packet16})
        EXPECT_EQ(reference_hash(scene_file, camera_view, sampler, photons, mode), expected)
            << scene_file << ", query mode " << static_cast<int>(mode);
}

// Skips where no hashes are recorded, and the Avx2Kernels.* copies (tests/CMakeLists.txt) on a CPU
// whose own kernels are the AVX2 ones: ReferenceBits.* checks those already.
#define SKIP_WITHOUT_RECORDED_HASHES()                                                                      \
    if (embree_isa() == EmbreeIsa::Other)                                                                  \
        GTEST_SKIP() << "no hashes recorded for Embree's kernels on a CPU without AVX2 (the sums' last bits " \
                        "depend on them)";                                                                  \
    if (config_limits_to_avx2() && !cpu_has_avx512())                                                      \
    GTEST_SKIP() << "Embree's AVX2 kernels are this CPU's own: ReferenceBits.* checks their hashes"

}  // namespace

// Two batches per replica on pool (131072 photons per replica) so that batch boundaries are covered.
TEST(ReferenceBits, PoolSameSumsAsBefore) {
    SKIP_WITHOUT_RECORDED_HASHES();
    expect_hash("pool.json", false, SamplerKind::Sobol, 8 * 70000,
                recorded("91285762766b48253c143d2482928885", "e900921fc1ad49803195e1a812badca9"));
    expect_hash("pool.json", true, SamplerKind::Sobol, 8 * 70000,
                recorded("45c02240dac474e7e300c1b1a10a6318", "e02e05c3a51f0e485ba380df997bc394"));
    expect_hash("pool.json", true, SamplerKind::Independent, 8 * 20000,
                recorded("b8e70ce179eea9e9ef2fe0edc5e7a9fc", "39acc94b36857c5ffe9cf72f214a3556"));
}

TEST(ReferenceBits, SphereAndBunnySameSumsAsBefore) {
    SKIP_WITHOUT_RECORDED_HASHES();
    expect_hash("sphere.json", true, SamplerKind::Sobol, 8 * 20000,
                recorded("3eb0e399996ea930ccc0d487ed9daa1c", "f456ab83f874151a9bd49d0b8f7de845"));
    expect_hash("bunny.json", true, SamplerKind::Sobol, 8 * 20000,
                recorded("95628c61e39f96c916acf890c5f6806f", "4f30839efd7bce9b34cd9bc2a4a1be94"));
}

TEST(ReferenceBits, SphereFogSameSumsAsBefore) {
    SKIP_WITHOUT_RECORDED_HASHES();
    expect_hash("sphere_fog.json", true, SamplerKind::Sobol, 8 * 20000,
                // Under the AVX-512 kernels these sums depend on the azimuths' sincos (libmvec's or libm's,
                // util/vector_sincos.hpp: a GCC build on a CPU with AVX2 and FMA runs libmvec's).
                recorded(vector_sincos_uses_libmvec() ? "89d1d9a9f5ec97402d67eb9e64f6ed1e"
                                                      : "857ce368eaccf699a24f909ad6899537",
                         "476dd92c5df9f30c2b13140d3a987312"));
    expect_hash("sphere_fog.json", true, SamplerKind::Independent, 8 * 20000,
                recorded("0430ecd24ae7a9a90e59adc19b08684c", "d7048ef6a53b674bdaf54542b80e5588"));
}

namespace {

bool same_bits(const Hit& a, const Hit& b) {
    auto bits = [](const glm::dvec3& v, const glm::dvec3& w) { return std::memcmp(&v, &w, sizeof v) == 0; };
    return a.valid == b.valid && a.object == b.object && std::memcmp(&a.t, &b.t, sizeof a.t) == 0 &&
           bits(a.position, b.position) && bits(a.geometric_normal, b.geometric_normal) &&
           bits(a.shading_normal, b.shading_normal);
}

// The reference's own rays (closest-hit and visibility) on a scene, through the single-ray form of the
// tracer and its batched form in every QueryMode: the same hits, bit for bit. (In QueryMode::Single the
// batch runs the single-ray queries themselves; the packet modes are the ones this can catch.)
void expect_batches_match_single_rays(const std::string& scene_file,
                                      std::initializer_list<QueryMode> modes = {QueryMode::Single, QueryMode::Packet8,
                                                                                QueryMode::Packet16}) {
    SCOPED_TRACE(scene_file);
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
    ASSERT_GT(hit_queries.size(), 10000u);
    ASSERT_GT(shadow_queries.size(), 1000u);
    std::vector<Hit> single_hits(hit_queries.size());
    std::size_t valid = 0;
    for (std::size_t k = 0; k < hit_queries.size(); ++k) {
        const RayQuery& q = hit_queries[k];
        single_hits[k] = ts.tracer->intersect(q.origin, q.dir, q.tmin, q.tmax);
        valid += single_hits[k].valid ? 1 : 0;
    }
    EXPECT_GT(valid, hit_queries.size() / 4);
    // Visibility queries with a known answer too (some scenes' camera deposits are never blocked): along
    // closest-hit rays, up to twice the hit's distance (blocked) and up to half of it (free).
    for (std::size_t k = 0, added = 0; k < hit_queries.size() && added < 200; ++k) {
        if (!single_hits[k].valid) continue;
        const RayQuery& q = hit_queries[k];
        const double t = single_hits[k].t;
        shadow_queries.push_back({q.origin, q.dir, q.tmin, 2.0 * t});
        shadow_queries.push_back({q.origin, q.dir, q.tmin, 0.5 * t});
        added += 2;
    }
    std::vector<std::uint8_t> single_occluded(shadow_queries.size());
    std::size_t occluded_count = 0;
    for (std::size_t k = 0; k < shadow_queries.size(); ++k) {
        const RayQuery& q = shadow_queries[k];
        single_occluded[k] = ts.tracer->occluded(q.origin, q.dir, q.tmin, q.tmax) ? 1 : 0;
        occluded_count += single_occluded[k];
    }
    // Empty segments (tmax <= tmin) are part of the contract too.
    shadow_queries.push_back({{0.0, 0.0, 0.5}, {0.0, 0.0, -1.0}, 0.3, 0.2});
    single_occluded.push_back(ts.tracer->occluded(shadow_queries.back().origin, shadow_queries.back().dir, 0.3, 0.2) ? 1 : 0);
    // Both answers occur, so that a batch answering all one way fails.
    EXPECT_GT(occluded_count, 0u);
    EXPECT_LT(occluded_count, shadow_queries.size() - 1);
    for (QueryMode mode : modes) {
        SCOPED_TRACE("query mode " + std::to_string(static_cast<int>(mode)));
        std::vector<Hit> hits(hit_queries.size());
        ts.tracer->intersect(hit_queries.data(), hit_queries.size(), hits.data(), mode);
        std::size_t mismatches = 0;
        for (std::size_t k = 0; k < hit_queries.size(); ++k) mismatches += same_bits(single_hits[k], hits[k]) ? 0 : 1;
        EXPECT_EQ(mismatches, 0u) << hit_queries.size() << " closest-hit queries";
        std::vector<std::uint8_t> occluded(shadow_queries.size(), 2);
        ts.tracer->occluded(shadow_queries.data(), shadow_queries.size(), occluded.data(), mode);
        EXPECT_EQ(occluded, single_occluded) << shadow_queries.size() << " visibility queries";
        EXPECT_EQ(occluded.back(), 0u);
    }
}

}  // namespace

TEST(RayTracerBatches, SameHitsAsSingleRays) {
    for (const char* scene : {"pool.json", "sphere.json", "bunny.json", "sphere_fog.json"})
        expect_batches_match_single_rays(scene);
}

// Batches complete a group's sphere hits and height-field normals together, grouped by object. On `sand`
// two height fields (one periodic, completed point by point) and a sphere share the groups. Single-ray
// queries only: there Embree's 8- and 16-ray packets answer 1 of its 63,978 closest-hit queries with the
// other triangle of a cell (a vertical ray on a cell's diagonal: the same distance, another geometric
// normal), a difference of Embree's kernels, not of the completion. That normal decided nothing on the
// ray's path: sand's reference sums were the same bits in all three modes (32,000 and 200,000 photons,
// checked once, not kept as a test since no hash is recorded for sand).
TEST(RayTracerBatches, MixedGroupsSameHitsAsSingleRays) {
    expect_batches_match_single_rays("sand.json", {QueryMode::Single});
}

// A ray Embree would abort on is refused in every mode, wherever it sits in a batch (here: in the second
// 8-ray packet of a group).
TEST(RayTracerBatches, RefuseInvalidRaysInEveryMode) {
    const TracedScene ts(load_scene(scene_path("sphere.json")));
    std::vector<RayQuery> queries(12, RayQuery{{0.0, 0.0, 3.0}, {0.0, 0.0, -1.0}, 1e-6, 1e30});
    queries[10].dir = {std::nan(""), 0.0, -1.0};
    std::vector<Hit> hits(queries.size());
    std::vector<std::uint8_t> occluded(queries.size());
    for (QueryMode mode : {QueryMode::Single, QueryMode::Packet8, QueryMode::Packet16}) {
        SCOPED_TRACE("query mode " + std::to_string(static_cast<int>(mode)));
        EXPECT_THROW(ts.tracer->intersect(queries.data(), queries.size(), hits.data(), mode), std::runtime_error);
        EXPECT_THROW(ts.tracer->occluded(queries.data(), queries.size(), occluded.data(), mode), std::runtime_error);
    }
}

namespace {

std::uint32_t naive_reverse(std::uint32_t x) {
    std::uint32_t r = 0;
    for (int b = 0; b < 32; ++b) r |= ((x >> b) & 1u) << (31 - b);
    return r;
}

// The sampler's definition (photon_sampler.hpp), written out the slow way: a shuffled index per pair,
// the pair's Sobol' point, each dimension Owen-scrambled with its own seed.
double sobol_by_definition(std::uint64_t seed, std::uint32_t replica, std::uint32_t index, int dim) {
    const std::uint64_t replica_seed = mix64(seed * 0x9E3779B97F4A7C15ull + replica + 1);
    const std::uint64_t pair_seed = mix64(replica_seed + static_cast<std::uint64_t>(dim >> 1) * 0xA24BAED4963EE407ull);
    const std::uint32_t shuffled = owen_scramble(index, static_cast<std::uint32_t>(pair_seed));
    const std::uint32_t raw = (dim & 1) ? sobol_dim1(shuffled) : naive_reverse(shuffled);
    const std::uint32_t scrambled = owen_scramble(raw, static_cast<std::uint32_t>(pair_seed >> 32) ^ (dim & 1 ? 0x68bc21ebu : 0u));
    return (static_cast<double>(scrambled) + 0.5) * 0x1.0p-32;
}

}  // namespace

// The table-driven sampler gives the values of its definition, bit for bit, in every quasi-random
// dimension, alone (get) and in pairs (get2).
TEST(PhotonSamplerBits, SameValuesAsTheDefinition) {
    std::size_t mismatches = 0;
    for (std::uint32_t replica = 0; replica < 3; ++replica)
        for (std::uint32_t index = 0; index < 4000; index = index * 3 + 1 + (index >> 4)) {
            const PhotonSampler s(SamplerKind::Sobol, 7, replica, index);
            for (int dim = 0; dim < kQuasiDimensions; ++dim) {
                const double expected = sobol_by_definition(7, replica, index, dim);
                mismatches += s.get(dim) == expected ? 0 : 1;
                double a, b;
                s.get2(dim, a, b);
                mismatches += a == expected ? 0 : 1;
                mismatches += b == (dim + 1 < kQuasiDimensions ? sobol_by_definition(7, replica, index, dim + 1) : s.get(dim + 1)) ? 0 : 1;
            }
        }
    EXPECT_EQ(mismatches, 0u);
    // sobol_dim1 is the Sobol' generator of x + 1: digit k of the index adds direction number v_k.
    EXPECT_EQ(sobol_dim1(1), 0x80000000u);
    EXPECT_EQ(sobol_dim1(2), 0xC0000000u);
    EXPECT_EQ(sobol_dim1(3), 0x40000000u);
}

// A batch's emission samples in one call (the loop that vectorises) are emission() of each index, bit
// for bit: for both samplers, at odd offsets and lengths, up to the last index of the quasi-random pair
// (2^32 - 1), and across 2^32 (where emissions() computes one index at a time).
TEST(PhotonSamplerBits, BatchedEmissionsEqualOneAtATime) {
    std::size_t compared = 0, mismatches = 0;
    for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent})
        for (std::uint32_t replica = 0; replica < 2; ++replica) {
            const SamplerSeeds seeds = PhotonSampler::seeds(kind, 11, replica);
            for (std::uint64_t first : {0ull, 3ull, 65536ull, 0x100000000ull - 45ull, 0xFFFFFFFFull - 20ull})
                for (std::size_t n : {std::size_t{1}, std::size_t{7}, std::size_t{45}}) {
                    std::vector<double> out(2 * n);
                    PhotonSampler::emissions(seeds, first, n, out.data());
                    for (std::size_t k = 0; k < n; ++k) {
                        double u1, u2;
                        PhotonSampler::emission(seeds, first + k, u1, u2);
                        mismatches += (out[2 * k] == u1 && out[2 * k + 1] == u2) ? 0 : 1;
                        ++compared;
                    }
                }
        }
    EXPECT_EQ(compared, 2u * 2u * 5u * (1u + 7u + 45u));
    EXPECT_EQ(mismatches, 0u);
}

// A batch's photon order is a stable sort of its offsets by (light, Z-order cell of the emission
// values), the cell's Morton key with the first value's bits in the even places: checked against
// std::stable_sort for full and partial batches, one and three lights, and a first index that is not a
// multiple of the light count; 65,536 photons and fewer take the 32-bit keys, more the 64-bit ones.
TEST(PhotonBatchOrder, StableSortByLightAndCell) {
    auto cell = [](const glm::dvec2& u) {
        const auto x = static_cast<std::uint32_t>(u.x * 256.0), y = static_cast<std::uint32_t>(u.y * 256.0);
        std::uint32_t key = 0;
        for (int b = 0; b < 8; ++b) key |= ((x >> b) & 1u) << (2 * b) | ((y >> b) & 1u) << (2 * b + 1);
        return key;
    };
    std::uint64_t state = 12345;
    auto uniform = [&] {   // duplicates of cells are frequent at these sizes: stability matters
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1.0p-53;
    };
    std::size_t checked = 0;
    for (std::uint64_t lights : {1ull, 3ull})
        for (std::size_t n : {std::size_t{1000}, std::size_t{65536}, std::size_t{65537}}) {
            const std::uint64_t first = 65536 * 5 + 1;
            std::vector<glm::dvec2> values(n);
            for (glm::dvec2& u : values) u = {uniform(), uniform()};
            std::vector<std::uint32_t> order, expected(n);
            SortScratch scratch;
            photon_batch_order(lights, first, values, order, scratch);
            for (std::size_t i = 0; i < n; ++i) expected[i] = static_cast<std::uint32_t>(i);
            std::stable_sort(expected.begin(), expected.end(), [&](std::uint32_t a, std::uint32_t b) {
                const std::uint64_t la = (first + a) % lights, lb = (first + b) % lights;
                return la != lb ? la < lb : cell(values[a]) < cell(values[b]);
            });
            EXPECT_EQ(order, expected) << lights << " lights, " << n << " photons";
            ++checked;
        }
    EXPECT_EQ(checked, 6u);
}

// The same stable sort for the reference's own batches of scrambled Sobol' emission values: a full and
// a partial batch from an aligned start (one photon per cell at most: sorted by one scatter), an
// unaligned batch (cells shared: the radix sort), each for one and three lights, over two replicas.
TEST(PhotonBatchOrder, SobolBatchesAsTheReferenceMakesThem) {
    std::size_t checked = 0;
    for (std::uint32_t replica : {0u, 5u})
        for (std::uint64_t lights : {1ull, 3ull})
            for (auto [first, n] : {std::pair<std::uint64_t, std::size_t>{65536 * 3, 65536}, {65536 * 3 + 7, 65536},
                                    {65536 * 2, 40000}}) {
                const SamplerSeeds seeds = PhotonSampler::seeds(SamplerKind::Sobol, 1, replica);
                std::vector<glm::dvec2> values(n);
                PhotonSampler::emissions(seeds, first, n, reinterpret_cast<double*>(values.data()));
                std::vector<std::uint32_t> order, expected(n);
                SortScratch scratch;
                photon_batch_order(lights, first, values, order, scratch);
                auto key = [&](std::uint32_t k) {
                    const auto x = static_cast<std::uint32_t>(values[k].x * 256.0);
                    const auto y = static_cast<std::uint32_t>(values[k].y * 256.0);
                    std::uint32_t m = 0;
                    for (int b = 0; b < 8; ++b) m |= ((x >> b) & 1u) << (2 * b) | ((y >> b) & 1u) << (2 * b + 1);
                    return std::pair<std::uint64_t, std::uint32_t>((first + k) % lights, m);
                };
                for (std::size_t i = 0; i < n; ++i) expected[i] = static_cast<std::uint32_t>(i);
                std::stable_sort(expected.begin(), expected.end(),
                                 [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
                EXPECT_EQ(order, expected) << "replica " << replica << ", " << lights << " lights, first " << first;
                ++checked;
            }
    EXPECT_EQ(checked, 12u);
}

// A wave's emissions in one call (Emitter::sample_many: the libm calls in one loop, the arithmetic in
// another that vectorises) are the one-photon formula's bits, written out here with glm as the emitter
// had it: over chunk boundaries (64) and partial chunks, for a cone and a full sphere around an oblique
// axis. Every direction is a unit vector inside the cone, and a directional light's photons start on
// its rectangle along its direction.
TEST(EmitterBits, BatchedEmissionsEqualTheOnePhotonFormula) {
    std::uint64_t state = 99;
    auto uniform = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1.0p-53;
    };
    std::size_t checked = 0, mismatches = 0, outside = 0;
    for (double cos_max : {0.3, -1.0}) {
        Emitter e;
        e.type = LightType::Point;
        e.position = {0.5, -2.0, 3.0};
        e.direction = glm::normalize(glm::dvec3(0.3, 0.4, -0.8));
        orthonormal_basis(e.direction, e.axis_a, e.axis_b);
        e.cos_max = cos_max;
        for (std::size_t n : {std::size_t{1}, std::size_t{64}, std::size_t{150}}) {
            std::vector<glm::dvec2> u(n);
            for (glm::dvec2& v : u) v = {uniform(), uniform()};
            u[0] = {0.0, 0.0};   // the cone's axis
            if (n > 1) u[1] = {1.0, 0.999};   // its rim
            std::vector<glm::dvec3> origins(n), dirs(n);
            e.sample_many(u.data(), n, origins.data(), dirs.data());
            for (std::size_t k = 0; k < n; ++k) {
                const double cos_t = 1.0 - u[k].x * (1.0 - cos_max);
                const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
                const double phi = 2.0 * std::numbers::pi * u[k].y;
                double cos_phi, sin_phi;   // one angle alone (tests/test_vector_sincos.cpp checks its values)
                vector_sincos(&phi, 1, &cos_phi, &sin_phi);
                const glm::dvec3 expected =
                    glm::normalize(cos_t * e.direction + sin_t * (cos_phi * e.axis_a + sin_phi * e.axis_b));
                mismatches += (dirs[k] == expected && origins[k] == e.position) ? 0 : 1;
                outside += std::abs(glm::length(dirs[k]) - 1.0) < 1e-15 && glm::dot(dirs[k], e.direction) >= cos_max - 1e-12 ? 0 : 1;
                ++checked;
            }
        }
    }
    Emitter d;
    d.type = LightType::Directional;
    d.direction = glm::normalize(glm::dvec3(-0.2, 0.1, -1.0));
    orthonormal_basis(d.direction, d.axis_a, d.axis_b);
    d.corner = {-1.0, -1.0, 4.0};
    d.extent_a = 2.0, d.extent_b = 3.0;
    std::vector<glm::dvec2> u(70);
    for (glm::dvec2& v : u) v = {uniform(), uniform()};
    std::vector<glm::dvec3> origins(u.size()), dirs(u.size());
    d.sample_many(u.data(), u.size(), origins.data(), dirs.data());
    for (std::size_t k = 0; k < u.size(); ++k) {
        const glm::dvec3 offset = origins[k] - d.corner;
        mismatches += dirs[k] == d.direction ? 0 : 1;
        outside += std::abs(glm::dot(offset, d.direction)) < 1e-12 && glm::dot(offset, d.axis_a) >= -1e-12 &&
                           glm::dot(offset, d.axis_a) <= 2.0 + 1e-12 && glm::dot(offset, d.axis_b) >= -1e-12 &&
                           glm::dot(offset, d.axis_b) <= 3.0 + 1e-12
                       ? 0
                       : 1;
        ++checked;
    }
    EXPECT_EQ(checked, 2u * (1u + 64u + 150u) + 70u);
    EXPECT_EQ(mismatches, 0u);
    EXPECT_EQ(outside, 0u);
}
