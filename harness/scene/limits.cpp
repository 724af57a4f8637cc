// Bounds and the memory estimate of limits.hpp.
//
// The memory estimate (bytes at the peak of `caustics reference` / `caustics render`), R replicas, T
// worker threads:
//   receiver, per bin:  8 (chart areas) + max(trace, finish, store) + 16 (method map, truth, metrics)
//   camera, per pixel:  29 (G-buffer) + 16 (deposit footprints) + 1 + max(trace, finish, store) + 24
//                       (beauty RGB, method map, metrics)
//     with trace  = 8 R           integer sums, one copy shared by every thread (atomic deposits,
//                                 reference.cpp)
//          finish = 8 R + 2 (8 + 4 R)   sums, and mean, standard error and R replica images (x2 while a
//                                       noise-target round replaces the previous result)
//          store  = 8 R + (8 + 4 R) + 16 R   sums, images, cache payload and file bytes
//   height field, per cell: 300 (grid, triangles, normals, Embree's copy and BVH; measured 269 on the
//                       sine scene at 1024^2 and 2048^2 cells), plus 40 per vertex for the waves
//                       simulation and 24 per volume sample for the noise synthesis
//   mesh: 72 per vertex and 196 per triangle (the scene's and the frame's copies, Embree's copy and BVH,
//                       and the ray tracer's 36 bytes of vertex normals per triangle)
// Not counted: buffers of 1 MiB and more are rounded up to 2 MiB (at most 2 MiB each, small against the
// sizes the limit guards), and up to 256 MiB of freed ones stay mapped for reuse (util/huge_pages.hpp).
// A method's own buffers beyond one map per view are the method's; the measured peak of a reference on a
// 2048^2 receiver with R = 8, T = 2 was 297 B per bin against 256 estimated before the cache encoding
// was reserved exactly (it then grew its strings by doubling).
#include <caustics/scene/limits.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <caustics/util/errors.hpp>

namespace caustics {

std::string format_limit(double x) {
    char text[64];
    std::snprintf(text, sizeof text, "%g", x);
    return text;
}

std::string format_bytes(double bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 6) bytes /= 1024.0, ++u;
    char text[64];
    std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
    return text;
}

double memory_limit_bytes() {
    const char* env = std::getenv(kMemoryLimitVariable);
    if (!env || !*env) return kDefaultMemoryLimitGiB * 1073741824.0;
    char* end = nullptr;
    const double gib = std::strtod(env, &end);
    while (end && (*end == ' ' || *end == '\t')) ++end;
    if (!end || *end != '\0' || !std::isfinite(gib) || !(gib > 0.0) || gib > 1e9)
        throw InputError(kMemoryLimitVariable, "",
                         std::string("got '") + env + "'; valid: a number of GiB (2^30 bytes) in (0, 1e9], e.g. 16");
    return gib * 1073741824.0;
}

int worker_threads() {
    const std::size_t allowed = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    const int arena = tbb::this_task_arena::max_concurrency();
    return std::max(1, std::min(static_cast<int>(std::min<std::size_t>(allowed, 1u << 20)), arena));
}

namespace {

double view_peak(int replicas, int threads) {
    (void)threads;   // the threads deposit atomically into one copy of the sums
    const double r = std::max(1, replicas);
    const double trace = 8.0 * r;
    const double finish = 8.0 * r + 2.0 * (8.0 + 4.0 * r);
    const double store = 8.0 * r + (8.0 + 4.0 * r) + 16.0 * r;
    return std::max({trace, finish, store});
}

std::string object_key(std::size_t k, const char* member) {
    return "objects[" + std::to_string(k) + "]." + member;
}

std::string times(double a, double b) { return format_limit(a) + " x " + format_limit(b); }

std::string integer_text(double x) {
    char text[64];
    std::snprintf(text, sizeof text, "%.0f", x);
    return text;
}

}  // namespace

double reference_bytes_per_bin(int replicas, int threads) { return 8.0 + view_peak(replicas, threads) + 16.0; }

double reference_bytes_per_pixel(int replicas, int threads) {
    return 29.0 + 16.0 + 1.0 + view_peak(replicas, threads) + 24.0;
}

double heightfield_bytes_per_cell() { return 300.0; }

double MemoryEstimate::total() const {
    double sum = 0.0;
    for (const MemoryItem& i : items) sum += i.bytes;
    return sum;
}

const MemoryItem* MemoryEstimate::largest() const {
    const MemoryItem* best = nullptr;
    for (const MemoryItem& i : items)
        if (!best || i.bytes > best->bytes) best = &i;
    return best;
}

MemoryEstimate estimate_scene_memory(const Scene& scene, int replicas, int threads) {
    MemoryEstimate e;
    // A width x height grid of `unit` costing `per` bytes each, set by the scene key `key`.
    auto grid = [&e](const char* key, const char* name, const char* unit, int width, int height, double per) {
        e.items.push_back({key,
                           std::string(name) + " " + times(width, height) + " " + unit + " x " + format_limit(per) + " B",
                           static_cast<double>(width) * height * per, per, unit});
    };
    grid("receiver.resolution", "receiver", "bins", scene.receiver.width, scene.receiver.height,
         reference_bytes_per_bin(replicas, threads));
    grid("camera.width", "camera", "pixels", scene.camera.width, scene.camera.height,
         reference_bytes_per_pixel(replicas, threads));
    for (std::size_t k = 0; k < scene.objects.size(); ++k) {
        const Object& o = scene.objects[k];
        if (o.shape == ShapeType::HeightField) {
            const HeightFieldDesc& d = o.heightfield;
            const double cells = static_cast<double>(d.resolution.x) * d.resolution.y;
            const double vertices = (d.resolution.x + 1.0) * (d.resolution.y + 1.0);
            double per = heightfield_bytes_per_cell();
            std::string what = "height field " + times(d.resolution.x, d.resolution.y) + " cells x " +
                               format_limit(per) + " B";
            double extra = 0.0;
            if (d.generator == HeightGenerator::Waves) {
                extra = 40.0 * vertices;
                what += " + wave simulation " + format_bytes(extra);
            } else if (d.generator == HeightGenerator::Noise) {
                extra = 24.0 * cells * std::max(1, d.time_samples);
                what += " + noise volume " + format_bytes(extra);
            }
            e.items.push_back({object_key(k, "resolution"), what, cells * per + extra, per, "cells"});
        } else if (o.shape == ShapeType::Mesh) {
            const double bytes = 72.0 * o.mesh.positions.size() + 196.0 * o.mesh.triangles.size();
            e.items.push_back({object_key(k, "file"),
                               "mesh of " + format_limit(static_cast<double>(o.mesh.triangles.size())) + " triangles",
                               bytes, 0.0, ""});
        }
    }
    return e;
}

void check_scene_memory(const Scene& scene, int replicas, int threads) {
    const double limit = memory_limit_bytes();
    const MemoryEstimate e = estimate_scene_memory(scene, replicas, threads);
    const double total = e.total();
    if (total <= limit) return;
    const MemoryItem& big = *e.largest();
    std::string others;
    for (const MemoryItem& i : e.items)
        if (&i != &big && i.bytes >= 0.01 * total) others += (others.empty() ? "" : ", ") + i.what + " = " + format_bytes(i.bytes);
    std::string valid;
    const double rest = total - big.bytes;
    if (big.per_unit > 0.0 && limit > rest) {
        const double units = std::floor((limit - rest) / big.per_unit);
        const std::string side = integer_text(std::floor(std::sqrt(units)));
        valid = "at most " + integer_text(units) + " " + big.unit + " here (about " + side + " x " + side + ")";
    } else {
        valid = "a smaller scene";
    }
    throw InputError(scene.path, big.key,
                     big.what + " = " + format_bytes(big.bytes) + (others.empty() ? "" : " (with " + others + ")") +
                         ": about " + format_bytes(total) + " in all with " + std::to_string(replicas) +
                         " reference replicas and " + std::to_string(threads) +
                         " worker threads, above the memory limit of " + format_bytes(limit) + "; valid: " + valid +
                         ", or fewer reference replicas (--replicas), or a higher limit with " +
                         kMemoryLimitVariable + "=<GiB> on a machine that has the memory");
}

void check_allocation(const std::string& file, const std::string& key, double bytes, const std::string& what) {
    const double limit = memory_limit_bytes();
    if (bytes <= limit) return;
    throw InputError(file, key,
                     what + " needs about " + format_bytes(bytes) + ", above the memory limit of " +
                         format_bytes(limit) + "; valid: at most " + format_bytes(limit) + ", or a higher limit with " +
                         kMemoryLimitVariable + "=<GiB> on a machine that has the memory");
}

}  // namespace caustics
