// One photon's path through the scene (docs/design.md section 5): emission, specular refraction and
// reflection (Fresnel by Russian roulette where the scene asks), extinction in media, the camera_volume
// scattering points (reference_volume.cpp) and the deposit on the first diffuse object after at least
// one specular event. See reference.cpp for the determinism and noise contract.
//
// Media: on every segment, the medium is medium_at(scene, inside) (inside: the dielectric the photon is
// in, -1 outside it). The photon keeps exp(-sigma_t l) of its weight over a segment of length l; what
// it loses is booked as absorbed (share sigma_a / sigma_t) and scattered (sigma_s / sigma_t). A photon
// that leaves the scene (no hit) travels an infinite segment: in a medium with sigma_t > 0 all of it is
// extinct (nothing escapes through an infinite absorbing or scattering medium, and the camera_volume
// view integrates such segments to infinity too). A directional light's photons start on its emission
// rectangle just outside the scene's bounds (photon_source.cpp): in a scene-wide medium its irradiance
// E0 is the one that enters the scene's bounds.
#include "detail/transport.hpp"

#include <cmath>

namespace caustics::detail {
namespace {

// Unpolarised Fresnel reflectance of a dielectric interface.
double fresnel_reflectance(double cos_i, double cos_t, double n_i, double n_t) {
    const double rs = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t);
    const double rp = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// A photon's path ends: the ledger books its weight under `field`.
bool end(PhotonState& p, double FluxLedger::*field) {
    p.end = field;
    return false;
}

}  // namespace

void Transport::batch_order(std::uint32_t replica, std::uint64_t first, std::uint64_t last, BatchOrder& batch) const {
    const std::size_t n = static_cast<std::size_t>(last - first);
    std::vector<SamplerSeeds> seeds;
    seeds_of(replica, seeds);
    const std::size_t lights = emitters.size();
    batch.by_index.resize(n);
    static_assert(sizeof(glm::dvec2) == 2 * sizeof(double), "by_index is written as pairs of doubles");
    if (lights == 1) {
        if (n > 0) PhotonSampler::emissions(seeds[0], first, n, reinterpret_cast<double*>(batch.by_index.data()));
    } else {
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint64_t i = first + k;
            glm::dvec2& u = batch.by_index[k];
            PhotonSampler::emission(seeds[i % lights], i / lights, u.x, u.y);
        }
    }
    photon_batch_order(lights, first, batch.by_index, batch.order, batch.scratch);
    // One gather of independent loads here, in place of a dependent miss in every photon's start.
    batch.emission.resize(n);
    for (std::size_t j = 0; j < n; ++j) batch.emission[j] = batch.by_index[batch.order[j]];
}

void Transport::seeds_of(std::uint32_t replica, std::vector<SamplerSeeds>& seeds) const {
    seeds.resize(emitters.size());
    for (std::size_t l = 0; l < emitters.size(); ++l)
        seeds[l] = PhotonSampler::seeds(sampler, seed + 0x51ED270B27D5A3C1ull * l, replica);
}

void Transport::start(const SamplerSeeds* seeds, std::uint64_t i, const glm::dvec3& origin, const glm::dvec3& dir,
                      std::uint32_t slot, PhotonState& p) const {
    const std::size_t light = light_of(i);
    p.rng = PhotonSampler(seeds[light], emitters.size() == 1 ? i : i / emitters.size());
    p.origin = origin;
    p.dir = dir;
    p.w = start_weight[light];
    // Dimension 2 is the dispersion sample, read where a dispersive material is hit (step).
    // Dimensions 3, 4, ... in the order of use: each Fresnel choice, and each segment after a specular
    // event in a scattering medium (its camera_volume scattering point, drawn whether or not the view
    // is measured so that the other views do not depend on it). Scenes without scattering read exactly
    // the dimensions they read before media existed.
    p.next_dim = 3;
    p.depth = 0;
    p.inside = -1;
    p.slot = slot;
    p.end = nullptr;
}

bool Transport::step(PhotonState& p, const Hit& hit, std::vector<LedgerEvent>& ledger, Accumulators& acc,
                     std::vector<ShadowQuery>& shadows) const {
    const MediumCoefficients& medium = media[static_cast<std::size_t>(p.inside + 1)];
    const double sigma_t = medium.extinction();
    if (sigma_t > 0.0) {
        const double length = hit.valid ? hit.t : std::numeric_limits<double>::infinity();
        if (p.depth > 0 && medium.scatters()) {
            const double u = p.rng.get(p.next_dim++);
            if (volume && p.inside == camera_medium) scatter_to_camera(p.origin, p.dir, length, p.w, u, medium, acc, shadows);
        }
        // Beer-Lambert with extinction; an absorbing-only medium books exactly what it did before.
        const double kept = hit.valid ? p.w * std::exp(-sigma_t * length) : 0.0;
        const double lost = p.w - kept;
        const double absorbed = medium.scattering > 0.0 ? lost * (medium.absorption / sigma_t) : lost;
        ledger.push_back({p.slot, &FluxLedger::absorbed, absorbed});
        ledger.push_back({p.slot, &FluxLedger::scattered, lost - absorbed});
        p.w = kept;
    }
    if (!hit.valid) {
        return end(p, &FluxLedger::escaped);
    }
    const Material& material = frame->scene->objects[static_cast<std::size_t>(hit.object)].material;
    if (material.type == MaterialType::Diffuse) {
        if (p.depth == 0) {
            return end(p, &FluxLedger::direct);
        }
        // The camera pixel's data is fetched first (prefetch) so that its cache misses overlap the
        // receiver deposit's.
        std::ptrdiff_t pixel = -1;
        if (camera) {
            pixel = camera_pixel(hit.position);
            if (pixel >= 0) {
                __builtin_prefetch(&pixel_info[static_cast<std::size_t>(pixel)]);
                __builtin_prefetch(&acc.pixels[static_cast<std::size_t>(pixel)], 1);
            }
        }
        if (hit.object == receiver_object) {
            p.end = &FluxLedger::deposited_receiver;
            const int bin = chart->bin_of(hit.position);
            if (bin >= 0) add_sum(acc.bins[static_cast<std::size_t>(bin)], to_fixed(p.w));
        } else {
            p.end = &FluxLedger::deposited_other;
        }
        if (pixel >= 0) deposit_camera(hit, static_cast<std::size_t>(pixel), p.dir, p.w, acc, shadows);
        return false;   // its weight p.w is what the ledger books under p.end
    }
    if (p.depth >= max_depth) {
        return end(p, &FluxLedger::truncated);
    }
    ++p.depth;

    const glm::dvec3 dir = p.dir;
    const bool from_outside = glm::dot(dir, hit.geometric_normal) < 0.0;
    // Normal on the side the photon arrives from; fall back to the geometric one where the
    // interpolated normal disagrees with the side (grazing hits on coarse meshes).
    glm::dvec3 n = from_outside ? hit.shading_normal : -hit.shading_normal;
    double cos_i = -glm::dot(dir, n);
    if (cos_i <= 0.0) {
        n = from_outside ? hit.geometric_normal : -hit.geometric_normal;
        cos_i = -glm::dot(dir, n);
    }
    const glm::dvec3 reflected = dir + 2.0 * cos_i * n;
    if (material.type == MaterialType::Mirror) {
        p.dir = glm::normalize(reflected);
        p.origin = hit.position;
        return true;   // the medium does not change at a mirror
    }
    // Without dispersion ior + 0 * u is ior: the sample is read only where it matters.
    const double ior = material.dispersion != 0.0 ? material.ior + material.dispersion * p.rng.get(2) : material.ior;
    const double n_i = from_outside ? outside_ior : ior;
    const double n_t = from_outside ? ior : outside_ior;
    const double eta = n_i / n_t;
    const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    bool reflect = sin2_t >= 1.0;   // total internal reflection
    double cos_t = 0.0;
    if (!reflect) {
        cos_t = std::sqrt(1.0 - sin2_t);
        // Fresnel by Russian roulette: unbiased and flux conserving, one path per photon.
        if (fresnel) reflect = p.rng.get(p.next_dim++) < fresnel_reflectance(cos_i, cos_t, n_i, n_t);
    }
    p.dir = glm::normalize(reflect ? reflected : eta * dir + (eta * cos_i - cos_t) * n);
    p.origin = hit.position;
    // Inside or outside is decided by where the new direction actually points.
    p.inside = glm::dot(p.dir, hit.geometric_normal) < 0.0 ? hit.object : -1;
    return true;
}

void Transport::trace(const SamplerSeeds* seeds, std::uint64_t i, const glm::dvec2& emission, FluxLedger& ledger,
                      Accumulators& acc, RayRecorder& log) const {
    std::vector<LedgerEvent> events;
    std::vector<ShadowQuery> shadows;
    glm::dvec3 origin, dir;
    emitters[light_of(i)].sample(emission.x, emission.y, origin, dir);
    PhotonState p;
    start(seeds, i, origin, dir, 0, p);
    events.push_back({0, &FluxLedger::emitted, p.w});
    for (bool alive = true; alive;) {
        log.ray(p.origin, p.dir, 1e-6, 1e30, false);
        alive = step(p, tracer->intersect(p.origin, p.dir), events, acc, shadows);
        for (const ShadowQuery& q : shadows) {
            log.ray(q.ray.origin, q.ray.dir, q.ray.tmin, q.ray.tmax, true);
            if (!tracer->occluded(q.ray.origin, q.ray.dir, q.ray.tmin, q.ray.tmax)) apply_shadow(q);
        }
        shadows.clear();
    }
    events.push_back({0, p.end, p.w});
    for (const LedgerEvent& e : events) ledger.*e.field += e.value;
}

std::ptrdiff_t Transport::camera_pixel(const glm::dvec3& p) const {
    double px, py;
    if (!camera->project(p, px, py)) return -1;
    if (!(px >= 0.0 && py >= 0.0 && px < gbuffer->width && py < gbuffer->height)) return -1;
    const int ix = static_cast<int>(px), iy = static_cast<int>(py);
    return static_cast<std::ptrdiff_t>(gbuffer->index(ix, iy));
}

void Transport::deposit_camera(const Hit& hit, std::size_t index, const glm::dvec3& dir_in, double w,
                               Accumulators& acc, std::vector<ShadowQuery>& shadows) const {
    const PixelInfo& pixel = pixel_info[index];
    if (pixel.object != hit.object) return;   // also rejects pixels the G-buffer does not cover
    glm::dvec3 to_camera = camera->position - hit.position;
    const double dist = glm::length(to_camera);
    if (!(dist > 0.0)) return;
    to_camera /= dist;
    // The camera must see the side the photon landed on.
    const double side = glm::dot(dir_in, hit.geometric_normal) < 0.0 ? 1.0 : -1.0;
    if (side * glm::dot(hit.geometric_normal, to_camera) <= 0.0) return;
    const double cos_c = side * glm::dot(hit.shading_normal, to_camera);
    if (cos_c <= 0.0) return;
    // E_pixel += w / A_pix with A_pix = omega d^2 / cos; stored relative to the pixel's own G-buffer
    // footprint so the fixed-point value stays near q. Added if the pinhole sees the point.
    const double x = w * pixel.scale * cos_c / (dist * dist);
    shadows.push_back({{hit.position, to_camera, 0.0, dist * (1.0 - 1e-6)}, &acc.pixels[index],
                       to_fixed(x), false});
}

}  // namespace caustics::detail
