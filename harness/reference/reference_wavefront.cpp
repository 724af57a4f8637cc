// Wavefront tracing of the reference's photons (issue 18): a chunk's photons advance together, one
// segment per wave. Each wave sends the live photons' next rays to Embree as one batch (RayTracer's
// batched intersect), steps every photon on its hit (reference_transport.cpp), then resolves the wave's
// visibility queries (camera deposits, camera_volume points) as another batch. Photons of a batch are
// ordered along a Z-order curve of their emission samples (photon_source.hpp), so the rays of one
// packet start close together and stay coherent over the first bounces, where packets traverse the BVH
// often faster than single rays; after refractions through a large mesh single rays can be faster
// (bench/bench_reference.cpp). Each batch goes to Embree in the mode this thread has timed fastest for
// its kind (query_mode_chooser.hpp), or in ReferenceSettings::query_mode where that is set; the modes
// gave the same hits on every ray of pool, sphere, bunny and sphere_fog checked
// (tests/test_reference_bits.cpp). A ray exactly on the edge shared by two triangles may get either in
// Embree's packets and single rays: on sand, 1 of 63,978 queries did, with the same distance and
// position, and the sums stayed the same bits since that triangle's normal decided nothing there.
//
// Same bits as tracing one photon after another: every photon reads the same sample values and takes
// the same path (the batched queries return exactly the single-ray hits, tests/test_reference_bits.cpp);
// deposits are integer sums, whose order does not matter; and each field of the flux ledger, a
// floating-point sum, receives its additions in photon order, each photon's in the order it made them
// (LedgerEvent, detail/transport.hpp).
#include "detail/transport.hpp"

#include <algorithm>

namespace caustics::detail {
namespace {

// Photons per wave: enough for full packets over several bounces, few enough that the wave's states,
// queries and hits stay in the core's L2 cache.
constexpr std::size_t kWave = 512;

// At least n elements, never fewer: a buffer that shrank with a wave's live photons and grew back
// with the next wave rebuilt every element it regained (a Hit's 88 bytes of default values, each
// overwritten by the query before it is read).
template <class T>
void grow(std::vector<T>& v, std::size_t n) {
    if (v.size() < n) v.resize(n);
}

}  // namespace

void Transport::trace_wave(std::uint32_t replica, std::uint64_t first, const std::uint32_t* order,
                           const glm::dvec2* emission, std::size_t n, FluxLedger& ledger, Accumulators& acc,
                           WaveScratch& s) const {
    seeds_of(replica, s.seeds);
    for (std::size_t w0 = 0; w0 < n; w0 += kWave) {
        const std::size_t count = std::min(kWave, n - w0);
        s.events.clear();
        s.photons.resize(count);
        s.active.resize(count);
        s.origins.resize(count);
        s.dirs.resize(count);
        // The wave's emissions in one call where all its photons share a light (their libm calls and
        // their arithmetic in loops of their own, Emitter::sample_many).
        if (emitters.size() == 1) {
            emitters[0].sample_many(emission + w0, count, s.origins.data(), s.dirs.data());
        } else {
            for (std::size_t k = 0; k < count; ++k)
                emitters[light_of(first + order[w0 + k])].sample_many(emission + w0 + k, 1, &s.origins[k], &s.dirs[k]);
        }
        // The emitted weights summed in a register (the same additions in the same order): through the
        // ledger's memory each addition waited for the one before it.
        double emitted = ledger.emitted;
        for (std::size_t k = 0; k < count; ++k) {
            const std::uint32_t offset = order[w0 + k];
            start(s.seeds.data(), first + offset, s.origins[k], s.dirs[k], static_cast<std::uint32_t>(k), s.photons[k]);
            emitted += s.photons[k].w;
            s.active[k] = static_cast<std::uint32_t>(k);
        }
        ledger.emitted = emitted;
        for (int segment = 0; !s.active.empty(); ++segment) {
            const std::size_t live = s.active.size();
            grow(s.queries, live);
            grow(s.hits, live);
            for (std::size_t j = 0; j < live; ++j) {
                const PhotonState& p = s.photons[s.active[j]];
                s.queries[j] = {p.origin, p.dir, 1e-6, 1e30};
            }
            s.modes.run(QueryModeChooser::hit_kind(segment), live, query_mode,
                        [&](QueryMode mode) { tracer->intersect(s.queries.data(), live, s.hits.data(), mode); });
            s.shadows.clear();
            s.next.clear();
            for (std::size_t j = 0; j < live; ++j)
                if (step(s.photons[s.active[j]], s.hits[j], s.events, acc, s.shadows)) s.next.push_back(s.active[j]);
            if (!s.shadows.empty()) {
                grow(s.shadow_rays, s.shadows.size());
                grow(s.occluded, s.shadows.size());
                for (std::size_t j = 0; j < s.shadows.size(); ++j) s.shadow_rays[j] = s.shadows[j].ray;
                s.modes.run(QueryModeChooser::kVisibility, s.shadows.size(), query_mode, [&](QueryMode mode) {
                    tracer->occluded(s.shadow_rays.data(), s.shadows.size(), s.occluded.data(), mode);
                });
                for (std::size_t j = 0; j < s.shadows.size(); ++j)
                    if (!s.occluded[j]) apply_shadow(s.shadows[j]);
            }
            s.active.swap(s.next);
        }
        // The ledger in photon order (LedgerEvent): the media's events by a stable counting sort by
        // photon, then each photon's end.
        if (!s.events.empty()) {
            s.event_start.assign(count + 1, 0u);
            for (const LedgerEvent& e : s.events) ++s.event_start[e.slot + 1];
            for (std::size_t k = 1; k <= count; ++k) s.event_start[k] += s.event_start[k - 1];
            s.sorted.resize(s.events.size());
            for (const LedgerEvent& e : s.events) s.sorted[s.event_start[e.slot]++] = e;
            for (const LedgerEvent& e : s.sorted) ledger.*e.field += e.value;
        }
        for (std::size_t k = 0; k < count; ++k) ledger.*s.photons[k].end += s.photons[k].w;
    }
}

}  // namespace caustics::detail
