// The reference light tracer (DESIGN.md section 5). See reference.hpp for the contract.
//
// Determinism: photon k draws its random numbers only from a counter-based generator keyed by
// (seed, k, dimension); deposits are summed as 64-bit fixed-point integers (associative), photons are
// traced in a fixed order within each fixed batch (batch_order), and the flux ledger is summed per fixed
// chunk of that order, then over chunks and batches in order. The result is
// therefore bit-identical for any thread count and scheduling.
//
// Noise: photon k contributes X_k = N w_k / A to the bin it lands in (0 elsewhere); E = mean(X_k) and
// se^2 = (sum X_k^2 / N - E^2) / (N - 1). One photon deposits at most once (it stops at the first
// diffuse surface, and Fresnel splitting is done by Russian roulette), so per-bin sums of w and w^2
// are exactly the needed moments.
//
// Bump kReferenceVersion (reference_cache.cpp) whenever the transport or the estimators change.
#include "reference.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "hash.hpp"
#include "photon_source.hpp"
#include "progress.hpp"
#include "ray_offset.hpp"
#include "ray_tracer.hpp"
#include "reference_rays.hpp"

namespace caustics {
namespace {

constexpr std::uint64_t kBatchSize = 65536;
// Photons of one batch traced as one task (and summed into one partial ledger), in the batch's order.
constexpr std::size_t kChunkSize = 2048;
// One photon's normalised weight (<= 1) becomes an integer of at most 2^30: 1e9 photons in one bin
// stay below 2^60, and each contribution keeps ~2^-30 relative precision.
constexpr double kFixedScale = 1073741824.0;  // 2^30

// Unpolarised Fresnel reflectance of a dielectric interface.
double fresnel_reflectance(double cos_i, double cos_t, double n_i, double n_t) {
    const double rs = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t);
    const double rp = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Ray logs: NoRayLog compiles away; RayRecorder keeps every query for bench/ replays.
struct NoRayLog {
    void ray(const glm::dvec3&, const glm::dvec3&, double, double, bool) {}
};

struct RayRecorder {
    double offset = 0.0;   // the tracer's own minimum tnear
    std::vector<RecordedRay> rays;
    void ray(const glm::dvec3& o, const glm::dvec3& d, double tmin, double tmax, bool shadow) {
        RecordedRay r;
        for (int i = 0; i < 3; ++i) r.origin[i] = static_cast<float>(o[i]), r.dir[i] = static_cast<float>(d[i]);
        r.tnear = static_cast<float>(std::max(tmin, offset));
        r.tfar = tmax >= 3e38 ? std::numeric_limits<float>::infinity() : static_cast<float>(tmax);
        r.shadow = shadow;
        rays.push_back(r);
    }
};

// Per bin / pixel: {sum of q, sum of q^2 / 2^30}, interleaved so that one deposit touches one cache line.
using FixedPair = std::array<std::int64_t, 2>;

struct Accumulators {
    std::vector<FixedPair> bins;     // receiver
    std::vector<FixedPair> pixels;   // camera
};

// What a camera deposit needs of one pixel, packed so that it costs one cache miss: the pixel's
// G-buffer footprint factor (d_c^2 / cos_c) and the primary-hit object (-1 where not covered).
struct PixelInfo {
    double scale = 0.0;
    int object = -1;
};

// Everything one photon needs, shared read-only by all threads.
struct Transport {
    const RayTracer* tracer = nullptr;
    const FrameGeometry* frame = nullptr;
    const ReceiverChart* chart = nullptr;
    const CameraGBuffer* gbuffer = nullptr;
    const CameraModel* camera = nullptr;
    std::vector<double> pixel_scale;   // camera: d_c^2 / cos_c of each pixel's G-buffer point
    std::vector<PixelInfo> pixel_info; // camera: pixel_scale and G-buffer object, packed
    std::vector<Emitter> emitters;
    std::vector<std::uint64_t> photons_of_light;
    double weight_ref = 1.0;           // largest flux per photon: normalises fixed-point weights
    double outside_ior = 1.0;
    int receiver_object = -1;
    int max_depth = 8;
    bool fresnel = false;
    std::uint64_t seed = 1;

    void batch_order(std::uint64_t first, std::uint64_t last, std::vector<std::uint32_t>& order,
                     std::vector<std::uint32_t>& scratch) const {
        photon_batch_order(seed, emitters.size(), first, last, order, scratch);
    }
    template <class Log>
    void trace(std::uint64_t k, FluxLedger& ledger, Accumulators& acc, Log& log) const;
    // The pixel a deposit at p would land in, or -1 (outside the image or behind the camera).
    std::ptrdiff_t camera_pixel(const glm::dvec3& p) const;
    template <class Log>
    void deposit_camera(const Hit& hit, std::size_t index, const glm::dvec3& dir_in, double w, Accumulators& acc,
                        Log& log) const;
};

void add_ledger(FluxLedger& sum, const FluxLedger& l) {
    sum.emitted += l.emitted;
    sum.deposited_receiver += l.deposited_receiver;
    sum.deposited_other += l.deposited_other;
    sum.direct += l.direct;
    sum.escaped += l.escaped;
    sum.absorbed += l.absorbed;
    sum.truncated += l.truncated;
}

void add_fixed(FixedPair& acc, double x) {
    // x >= 0: adding 1/2 and truncating rounds to nearest, without a libm call.
    acc[0] += static_cast<std::int64_t>(x * kFixedScale + 0.5);
    acc[1] += static_cast<std::int64_t>(x * x * kFixedScale + 0.5);
}

template <class Log>
void Transport::trace(std::uint64_t k, FluxLedger& ledger, Accumulators& acc, Log& log) const {
    PhotonRandom rng(seed, k);
    const std::size_t light = emitters.size() == 1 ? 0 : static_cast<std::size_t>(k % emitters.size());
    const Emitter& emitter = emitters[light];
    glm::dvec3 origin, dir;
    const double u1 = rng.next(), u2 = rng.next();
    emitter.sample(u1, u2, origin, dir);
    const double u_dispersion = rng.next();
    double w = emitter.flux_per_photon;
    ledger.emitted += w;

    const auto& objects = frame->scene->objects;
    int depth = 0;       // specular events so far
    int inside = -1;     // dielectric object the photon travels in (-1: outside medium)
    for (;;) {
        log.ray(origin, dir, 1e-6, 1e30, false);
        const Hit hit = tracer->intersect(origin, dir);
        if (!hit.valid) {
            ledger.escaped += w;
            return;
        }
        if (inside >= 0) {   // Beer-Lambert over the segment just travelled inside a dielectric
            const double ka = objects[static_cast<std::size_t>(inside)].material.absorption;
            if (ka > 0.0) {
                const double kept = w * std::exp(-ka * hit.t);
                ledger.absorbed += w - kept;
                w = kept;
            }
        }
        const Material& material = objects[static_cast<std::size_t>(hit.object)].material;
        if (material.type == MaterialType::Diffuse) {
            if (depth == 0) {
                ledger.direct += w;
                return;
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
                ledger.deposited_receiver += w;
                const int bin = chart->bin_of(hit.position);
                if (bin >= 0) add_fixed(acc.bins[static_cast<std::size_t>(bin)], w / weight_ref);
            } else {
                ledger.deposited_other += w;
            }
            if (pixel >= 0) deposit_camera(hit, static_cast<std::size_t>(pixel), dir, w, acc, log);
            return;
        }
        if (depth >= max_depth) {
            ledger.truncated += w;
            return;
        }
        ++depth;

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
            dir = glm::normalize(reflected);
            origin = hit.position;
            continue;   // the medium does not change at a mirror
        }
        const double ior = material.ior + material.dispersion * u_dispersion;
        const double n_i = from_outside ? outside_ior : ior;
        const double n_t = from_outside ? ior : outside_ior;
        const double eta = n_i / n_t;
        const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        bool reflect = sin2_t >= 1.0;   // total internal reflection
        double cos_t = 0.0;
        if (!reflect) {
            cos_t = std::sqrt(1.0 - sin2_t);
            // Fresnel by Russian roulette: unbiased and flux conserving, one path per photon.
            if (fresnel) reflect = rng.next() < fresnel_reflectance(cos_i, cos_t, n_i, n_t);
        }
        dir = reflect ? reflected : eta * dir + (eta * cos_i - cos_t) * n;
        dir = glm::normalize(dir);
        origin = hit.position;
        // Inside or outside is decided by where the new direction actually points.
        inside = glm::dot(dir, hit.geometric_normal) < 0.0 ? hit.object : -1;
    }
}

std::ptrdiff_t Transport::camera_pixel(const glm::dvec3& p) const {
    double px, py;
    if (!camera->project(p, px, py)) return -1;
    if (!(px >= 0.0 && py >= 0.0 && px < gbuffer->width && py < gbuffer->height)) return -1;
    const int ix = static_cast<int>(px), iy = static_cast<int>(py);
    return static_cast<std::ptrdiff_t>(gbuffer->index(ix, iy));
}

template <class Log>
void Transport::deposit_camera(const Hit& hit, std::size_t index, const glm::dvec3& dir_in, double w,
                               Accumulators& acc, Log& log) const {
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
    log.ray(hit.position, to_camera, 0.0, dist * (1.0 - 1e-6), true);
    if (tracer->occluded(hit.position, to_camera, 0.0, dist * (1.0 - 1e-6))) return;
    // E_pixel += w / A_pix with A_pix = omega d^2 / cos; stored relative to the pixel's own G-buffer
    // footprint so the fixed-point value stays near w / weight_ref.
    const double x = (w / weight_ref) * pixel.scale * cos_c / (dist * dist);
    add_fixed(acc.pixels[index], x);
}

double nrmse_of(const Image& e, const Image& se, const std::vector<std::uint8_t>* mask) {
    double sum_e = 0.0, sum_var = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < e.pixels.size(); ++i) {
        if (mask && !(*mask)[i]) continue;
        sum_e += e.pixels[i];
        sum_var += static_cast<double>(se.pixels[i]) * se.pixels[i];
        ++n;
    }
    if (n == 0 || !(sum_e > 0.0)) return 0.0;
    return std::sqrt(sum_var / n) / (sum_e / n);
}

// Everything compute_reference needs before tracing; `camera` null for no camera view.
Transport make_transport(const RayTracer& tracer, const ReceiverChart& chart, const CameraGBuffer* camera,
                         const ReferenceSettings& settings, std::unique_ptr<CameraModel>& camera_model) {
    const FrameGeometry& frame = tracer.frame();
    const Scene& scene = *frame.scene;
    const std::uint64_t photons = settings.photons;
    const bool camera_view = camera != nullptr;
    Transport transport;
    transport.tracer = &tracer;
    transport.frame = &frame;
    transport.chart = &chart;
    transport.receiver_object = scene.receiver.object_index;
    transport.max_depth = scene.max_specular_depth;
    transport.fresnel = scene.fresnel;
    transport.seed = settings.seed;
    transport.outside_ior = scene.medium.present ? scene.medium.ior : 1.0;
    const std::size_t lights = scene.lights.size();
    transport.weight_ref = 0.0;
    for (std::size_t l = 0; l < lights; ++l) {
        Emitter e = make_emitter(scene.lights[l], frame);
        // Photon k belongs to light k mod L.
        const std::uint64_t count = photons / lights + (l < photons % lights ? 1 : 0);
        e.flux_per_photon = count > 0 ? e.power / static_cast<double>(count) : 0.0;
        transport.weight_ref = std::max(transport.weight_ref, e.flux_per_photon);
        transport.emitters.push_back(e);
        transport.photons_of_light.push_back(count);
    }
    if (!(transport.weight_ref > 0.0)) transport.weight_ref = 1.0;

    if (camera_view) {
        camera_model = std::make_unique<CameraModel>(scene.camera);
        if (camera_model->width != camera->width || camera_model->height != camera->height)
            throw std::runtime_error("reference: camera G-buffer size differs from the scene camera");
        transport.camera = camera_model.get();
        transport.gbuffer = camera;
        transport.pixel_scale.assign(camera->covered.size(), 0.0);
        for (std::size_t i = 0; i < camera->covered.size(); ++i) {
            if (!camera->covered[i]) continue;
            const glm::dvec3 to_cam = camera_model->position - glm::dvec3(camera->position[i]);
            const double d2 = glm::dot(to_cam, to_cam);
            const double cos_c = d2 > 0.0 ? glm::dot(glm::dvec3(camera->normal[i]), to_cam) / std::sqrt(d2) : 1.0;
            transport.pixel_scale[i] = std::max(d2, 1e-12) / std::clamp(cos_c, 0.05, 1.0);
        }
        transport.pixel_info.resize(camera->covered.size());
        for (std::size_t i = 0; i < camera->covered.size(); ++i) {
            if (!camera->covered[i] || camera->object[i] < 0) continue;
            transport.pixel_info[i] = {transport.pixel_scale[i], camera->object[i]};
        }
    }

    return transport;
}

}  // namespace

ReferenceResult compute_reference(const RayTracer& tracer, const ReceiverChart& chart,
                                  const CameraGBuffer* camera, const ReferenceSettings& settings) {
    const auto start = std::chrono::steady_clock::now();
    const FrameGeometry& frame = tracer.frame();
    const Scene& scene = *frame.scene;
    if (scene.lights.empty()) throw std::runtime_error("reference: the scene has no light");
    if (settings.photons == 0) throw std::runtime_error("reference: photons must be > 0");
    const bool camera_view = camera != nullptr && settings.camera_view;
    const std::uint64_t photons = settings.photons;

    std::unique_ptr<CameraModel> camera_model;
    const Transport transport = make_transport(tracer, chart, camera_view ? camera : nullptr, settings, camera_model);

    const std::size_t bins = static_cast<std::size_t>(chart.width()) * chart.height();
    const std::size_t pixels = camera_view ? camera->covered.size() : 0;
    tbb::enumerable_thread_specific<Accumulators> accumulators([&] {
        Accumulators a;
        a.bins.assign(bins, FixedPair{0, 0});
        a.pixels.assign(pixels, FixedPair{0, 0});
        return a;
    });
    const std::uint64_t batches = (photons + kBatchSize - 1) / kBatchSize;
    std::vector<FluxLedger> batch_ledgers(batches);
    ProgressBar progress("reference " + scene.name, photons, settings.progress);

    // Each batch is ordered once (batch_order) and then traced in fixed chunks of that order, in parallel
    // (fine-grained enough to balance two threads on a shared machine); chunk ledgers are summed in chunk
    // order, so the ledger does not depend on scheduling either.
    auto run_batches = [&] {
        tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, batches, 1), [&](const tbb::blocked_range<std::uint64_t>& range) {
            for (std::uint64_t b = range.begin(); b < range.end(); ++b) {
                const std::uint64_t first = b * kBatchSize;
                const std::uint64_t last = std::min(photons, first + kBatchSize);
                // Per batch, not per thread: a thread waiting on the chunks below may start another batch.
                std::vector<std::uint32_t> order, scratch;
                transport.batch_order(first, last, order, scratch);
                const std::size_t chunks = (order.size() + kChunkSize - 1) / kChunkSize;
                std::vector<FluxLedger> chunk_ledgers(chunks);
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& cr) {
                    Accumulators& acc = accumulators.local();
                    NoRayLog log;
                    for (std::size_t c = cr.begin(); c < cr.end(); ++c) {
                        FluxLedger ledger;
                        const std::size_t end = std::min(order.size(), (c + 1) * kChunkSize);
                        for (std::size_t j = c * kChunkSize; j < end; ++j) transport.trace(first + order[j], ledger, acc, log);
                        chunk_ledgers[c] = ledger;
                    }
                });
                FluxLedger ledger;
                for (const FluxLedger& l : chunk_ledgers) add_ledger(ledger, l);
                batch_ledgers[b] = ledger;
                progress.advance(last - first);
            }
        });
    };
    if (settings.threads > 0) {
        tbb::task_arena arena(settings.threads);
        arena.execute(run_batches);
    } else {
        run_batches();
    }
    progress.finish();

    ReferenceResult result;
    for (const FluxLedger& l : batch_ledgers) add_ledger(result.ledger, l);

    // Integer sums are exact, so combining the threads' accumulators in any order gives the same bits.
    std::vector<std::int64_t> bin_sum(bins, 0), bin_sq(bins, 0), pix_sum(pixels, 0), pix_sq(pixels, 0);
    for (const Accumulators& a : accumulators) {
        for (std::size_t i = 0; i < bins; ++i) bin_sum[i] += a.bins[i][0], bin_sq[i] += a.bins[i][1];
        for (std::size_t i = 0; i < pixels; ++i) pix_sum[i] += a.pixels[i][0], pix_sq[i] += a.pixels[i][1];
    }

    const double n = static_cast<double>(photons);
    const double wr = transport.weight_ref;
    // E = (sum w) / A; se^2 = (N sum w^2 / A^2 - E^2) / (N - 1).
    auto estimate = [&](std::int64_t sum, std::int64_t sq, double area, float& e_out, float& se_out) {
        const double e = static_cast<double>(sum) / kFixedScale * wr / area;
        const double m2 = n * (static_cast<double>(sq) / kFixedScale) * wr * wr / (area * area);
        const double var = photons > 1 ? std::max(0.0, (m2 - e * e) / (n - 1.0)) : 0.0;
        e_out = static_cast<float>(e);
        se_out = static_cast<float>(std::sqrt(var));
    };
    result.receiver = Image(chart.width(), chart.height(), 1);
    result.receiver_stderr = Image(chart.width(), chart.height(), 1);
    for (int j = 0; j < chart.height(); ++j)
        for (int i = 0; i < chart.width(); ++i) {
            const std::size_t b = static_cast<std::size_t>(j) * chart.width() + i;
            const double area = chart.bin_area(i, j);
            if (area > 0.0) estimate(bin_sum[b], bin_sq[b], area, result.receiver.pixels[b], result.receiver_stderr.pixels[b]);
        }
    result.noise_nrmse = nrmse_of(result.receiver, result.receiver_stderr, nullptr);

    if (camera_view) {
        result.camera = Image(camera->width, camera->height, 1);
        result.camera_stderr = Image(camera->width, camera->height, 1);
        result.camera_covered = camera->covered;
        for (int y = 0; y < camera->height; ++y)
            for (int x = 0; x < camera->width; ++x) {
                const std::size_t i = camera->index(x, y);
                if (!camera->covered[i]) continue;
                // E_pix = sum w / A_dep = (wr / A_c) sum x with A_c = omega * pixel_scale.
                const double area = camera_model->pixel_solid_angle(x, y) * transport.pixel_scale[i];
                estimate(pix_sum[i], pix_sq[i], area, result.camera.pixels[i], result.camera_stderr.pixels[i]);
            }
        result.noise_nrmse_camera = nrmse_of(result.camera, result.camera_stderr, &result.camera_covered);
    }

    result.photons = photons;
    result.seed = settings.seed;
    ReferenceSettings keyed = settings;
    keyed.camera_view = camera_view;
    result.cache_key = reference_cache_key(scene, frame.frame, keyed);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace caustics

namespace caustics {

std::vector<RecordedRay> record_reference_rays(const RayTracer& tracer, const ReceiverChart& chart,
                                               const CameraGBuffer* camera, const ReferenceSettings& settings) {
    const bool camera_view = camera != nullptr && settings.camera_view;
    std::unique_ptr<CameraModel> camera_model;
    const Transport transport = make_transport(tracer, chart, camera_view ? camera : nullptr, settings, camera_model);
    Accumulators acc;
    acc.bins.assign(static_cast<std::size_t>(chart.width()) * chart.height(), FixedPair{0, 0});
    if (camera_view) acc.pixels.assign(camera->covered.size(), FixedPair{0, 0});
    RayRecorder recorder;
    recorder.offset = scene_ray_offset(tracer.frame());
    FluxLedger ledger;
    // The same batches and the same order within each batch as compute_reference.
    std::vector<std::uint32_t> order, scratch;
    for (std::uint64_t first = 0; first < settings.photons; first += kBatchSize) {
        const std::uint64_t last = std::min(settings.photons, first + kBatchSize);
        transport.batch_order(first, last, order, scratch);
        for (const std::uint32_t i : order) transport.trace(first + i, ledger, acc, recorder);
    }
    return std::move(recorder.rays);
}

}  // namespace caustics
