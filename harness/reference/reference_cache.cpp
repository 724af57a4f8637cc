// The on-disk reference cache (docs/design.md section 5).
//
// Key: a 128-bit hash of everything the reference depends on (scene bytes, every asset's bytes, frame,
// photons, seed, camera view, receiver and camera sizes, kReferenceVersion).
// The payload: the integer sums of every view (receiver, camera, camera_volume) and the flux ledger,
// scattered share included. File cache_dir/<key>.ref:
//   magic "CAUSREF\n" | u32 file format | u32 kReferenceVersion | key (u64 length + bytes)
//   | u64 payload size | payload | u64 checksum64(payload)
// Anything that does not match exactly (truncation, flipped bits, another version, another key) makes
// the entry stale: it is recomputed and rewritten (temporary name, then rename), never used.
// An empty reference (no flux emitted, or nothing in any receiver bin) is never stored, and one found
// in the cache (written before such references became errors) is stale: compute_reference refuses it.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <memory>
#include <vector>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include <caustics/util/hash.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/reference/reference.hpp>

namespace caustics {
namespace {

// Bump whenever reference.cpp changes what it computes (transport, estimators, sampling).
// 3: replicas, quasi-Monte Carlo sampler, sums stored; 4: media (extinction, the scattered ledger, camera_volume);
// 5: a point light's azimuth cos and sin from libmvec's kernels (last bits of the directions)
constexpr std::uint32_t kReferenceVersion = 5;
constexpr std::uint32_t kFileFormat = 2;
constexpr char kMagic[8] = {'C', 'A', 'U', 'S', 'R', 'E', 'F', '\n'};

class Writer {
public:
    void u32(std::uint32_t v) { raw(&v, sizeof v); }
    void u64(std::uint64_t v) { raw(&v, sizeof v); }
    void f64(double v) { raw(&v, sizeof v); }
    void text(const std::string& s) {
        u64(s.size());
        raw(s.data(), s.size());
    }
    void image(const Image& im) {
        u32(static_cast<std::uint32_t>(im.width));
        u32(static_cast<std::uint32_t>(im.height));
        u32(static_cast<std::uint32_t>(im.channels));
        u64(im.pixels.size());
        raw(im.pixels.data(), im.pixels.size() * sizeof(float));
    }
    void raw(const void* p, std::size_t n) { out.append(static_cast<const char*>(p), n); }
    std::string out;
};

struct Corrupt {};   // thrown by Reader on any inconsistency

class Reader {
public:
    Reader(const char* p, std::size_t n) : p_(p), end_(p + n) {}
    std::uint32_t u32() { std::uint32_t v; raw(&v, sizeof v); return v; }
    std::uint64_t u64() { std::uint64_t v; raw(&v, sizeof v); return v; }
    double f64() { double v; raw(&v, sizeof v); return v; }
    std::string text() {
        const std::uint64_t n = u64();
        if (n > remaining()) throw Corrupt{};
        std::string s(p_, n);
        p_ += n;
        return s;
    }
    Image image() {
        Image im;
        im.width = static_cast<int>(u32());
        im.height = static_cast<int>(u32());
        im.channels = static_cast<int>(u32());
        const std::uint64_t n = u64();
        if (n != static_cast<std::uint64_t>(im.width) * im.height * im.channels) throw Corrupt{};
        if (n * sizeof(float) > remaining()) throw Corrupt{};
        im.pixels.resize(n);
        raw(im.pixels.data(), n * sizeof(float));
        return im;
    }
    void raw(void* dst, std::size_t n) {
        if (n > remaining()) throw Corrupt{};
        if (n == 0) return;   // dst may be null for an empty vector
        std::memcpy(dst, p_, n);
        p_ += n;
    }
    std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }

private:
    const char* p_;
    const char* end_;
};

// The payload is the integer sums (the images are rebuilt from them with the scene at load time) and
// the facts that are not in them.
std::string serialize_payload(const ReferenceResult& r) {
    const ReferenceSums& sums = *r.sums;
    Writer w;
    // Sized exactly: growing by doubling held up to three times the sums at once.
    w.out.reserve(72 + (sums.bin_sums.size() + sums.pixel_sums.size() + sums.volume_sums.size()) * sizeof(std::int64_t) +
                  11 * sizeof(double));
    w.u64(sums.per_replica);
    w.u32(sums.replicas);
    w.u32(sums.lights);
    w.u64(sums.bins);
    w.u64(sums.pixels);
    w.u64(sums.volume_pixels);
    w.raw(sums.bin_sums.data(), sums.bin_sums.size() * sizeof(std::int64_t));
    w.raw(sums.pixel_sums.data(), sums.pixel_sums.size() * sizeof(std::int64_t));
    w.raw(sums.volume_sums.data(), sums.volume_sums.size() * sizeof(std::int64_t));
    const FluxLedger& l = sums.ledger_units;
    for (double v : {l.emitted, l.deposited_receiver, l.deposited_other, l.direct, l.escaped, l.absorbed, l.scattered,
                     l.truncated})
        w.f64(v);
    w.f64(r.noise_nrmse);
    w.u64(r.seed);
    w.f64(r.seconds);   // how long the computation took when it was made (informational)
    return std::move(w.out);
}

struct CachedEntry {
    std::shared_ptr<ReferenceSums> sums;
    double noise_nrmse = 0.0;
    std::uint64_t seed = 0;
};

CachedEntry parse_payload(Reader& in) {
    CachedEntry e;
    e.sums = std::make_shared<ReferenceSums>();
    ReferenceSums& s = *e.sums;
    s.per_replica = in.u64();
    s.replicas = in.u32();
    s.lights = in.u32();
    s.bins = in.u64();
    s.pixels = in.u64();
    s.volume_pixels = in.u64();
    // Sizes are checked against what is left before anything is allocated. The volume view is the
    // camera's pixels or nothing.
    if (s.replicas == 0 || s.per_replica == 0 || s.bins > in.remaining() || s.pixels > in.remaining() ||
        (s.volume_pixels != 0 && s.volume_pixels != s.pixels))
        throw Corrupt{};
    const std::uint64_t words = (static_cast<std::uint64_t>(s.bins) + s.pixels + s.volume_pixels) * s.replicas;
    if (words > in.remaining() / sizeof(std::int64_t)) throw Corrupt{};
    s.bin_sums.resize(s.bins * s.replicas);
    s.pixel_sums.resize(s.pixels * s.replicas);
    s.volume_sums.resize(s.volume_pixels * s.replicas);
    in.raw(s.bin_sums.data(), s.bin_sums.size() * sizeof(std::int64_t));
    in.raw(s.pixel_sums.data(), s.pixel_sums.size() * sizeof(std::int64_t));
    in.raw(s.volume_sums.data(), s.volume_sums.size() * sizeof(std::int64_t));
    FluxLedger& l = s.ledger_units;
    for (double* v : {&l.emitted, &l.deposited_receiver, &l.deposited_other, &l.direct, &l.escaped, &l.absorbed,
                      &l.scattered, &l.truncated})
        *v = in.f64();
    e.noise_nrmse = in.f64();
    e.seed = in.u64();
    in.f64();   // original compute time
    if (in.remaining() != 0) throw Corrupt{};
    return e;
}

std::string encode_file(const ReferenceResult& r, const std::string& key) {
    const std::string payload = serialize_payload(r);
    Writer w;
    w.out.reserve(sizeof kMagic + 32 + key.size() + payload.size());
    w.raw(kMagic, sizeof kMagic);
    w.u32(kFileFormat);
    w.u32(kReferenceVersion);
    w.text(key);
    w.u64(payload.size());
    w.raw(payload.data(), payload.size());
    w.u64(checksum64(payload.data(), payload.size()));
    return std::move(w.out);
}

// Parses a cache file; false (never a throw) when it is unusable for `key`.
bool decode_file(const std::string& bytes, const std::string& key, CachedEntry& out) {
    try {
        Reader in(bytes.data(), bytes.size());
        char magic[sizeof kMagic];
        in.raw(magic, sizeof magic);
        if (std::memcmp(magic, kMagic, sizeof kMagic) != 0) return false;
        if (in.u32() != kFileFormat) return false;
        if (in.u32() != kReferenceVersion) return false;
        if (in.text() != key) return false;
        const std::uint64_t size = in.u64();
        if (size + sizeof(std::uint64_t) != in.remaining()) return false;
        const std::size_t offset = bytes.size() - in.remaining();
        const std::uint64_t stored = [&] {
            std::uint64_t v;
            std::memcpy(&v, bytes.data() + offset + size, sizeof v);
            return v;
        }();
        if (checksum64(bytes.data() + offset, size) != stored) return false;
        Reader payload(bytes.data() + offset, size);
        out = parse_payload(payload);
        return true;
    } catch (const Corrupt&) {
        return false;
    }
}

// Whether the sums measured anything: flux emitted and some receiver bin non-zero (reference.cpp).
bool measured_something(const ReferenceSums& sums) {
    if (!(sums.ledger_units.emitted > 0.0)) return false;
    for (const std::int64_t v : sums.bin_sums)
        if (v != 0) return true;
    return false;
}

}  // namespace

void hash_scene_contents(Hash128& h, const Scene& scene) {
    h.text(scene.source_text);
    h.u64(scene.assets.size());
    for (const std::string& asset : scene.assets) {
        std::string bytes;
        if (read_file_bytes(asset, bytes)) {
            h.u64(1);
            h.text(bytes);
        } else {
            h.u64(0);   // unreadable now: key on the name so a later readable file changes the key
            h.text(asset);
        }
    }
}

std::string reference_cache_key(const Scene& scene, int frame, const ReferenceSettings& settings) {
    Hash128 h;
    h.text("caustics-reference");
    h.u64(kReferenceVersion);
    hash_scene_contents(h, scene);
    h.u64(static_cast<std::uint64_t>(frame));
    h.u64(settings.seed);
    h.text(sampler_name(settings.sampler));
    h.u64(static_cast<std::uint64_t>(settings.replicas));
    h.u64(settings.camera_view ? 1 : 0);
    h.u64(static_cast<std::uint64_t>(scene.receiver.width));
    h.u64(static_cast<std::uint64_t>(scene.receiver.height));
    h.u64(static_cast<std::uint64_t>(scene.camera.width));
    h.u64(static_cast<std::uint64_t>(scene.camera.height));
    return h.hex();
}

std::string default_cache_dir() {
    const char* env = std::getenv("CAUSTICS_CACHE_DIR");
    return env && *env ? std::string(env) : std::string("results/cache");
}

namespace {

namespace fs = std::filesystem;

// Entries of one key: cache_dir/<key>-<photons>.ref.
struct EntryFile {
    fs::path path;
    std::uint64_t photons = 0;
};

std::vector<EntryFile> entries_of(const std::string& cache_dir, const std::string& key) {
    std::vector<EntryFile> out;
    std::error_code ec;
    const std::string prefix = key + "-";
    for (fs::directory_iterator it(cache_dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= prefix.size() + 4 || name.compare(0, prefix.size(), prefix) != 0 ||
            name.compare(name.size() - 4, 4, ".ref") != 0)
            continue;
        const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - 4);
        if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 19) continue;
        out.push_back({it->path(), std::stoull(digits)});
    }
    std::sort(out.begin(), out.end(), [](const EntryFile& a, const EntryFile& b) { return a.photons < b.photons; });
    return out;
}

// Reads an entry; null (and a message) when it is damaged, stale or made for other sizes.
std::shared_ptr<const ReferenceSums> read_entry(const EntryFile& file, const std::string& key, std::size_t bins,
                                                std::size_t pixels, std::size_t volume_pixels,
                                                const ReferenceSettings& settings, std::size_t lights, double& noise) {
    std::string bytes;
    CachedEntry entry;
    if (read_file_bytes(file.path.string(), bytes) && decode_file(bytes, key, entry) && entry.sums->bins == bins &&
        entry.sums->pixels == pixels && entry.sums->volume_pixels == volume_pixels &&
        entry.sums->replicas == static_cast<std::uint32_t>(settings.replicas) &&
        entry.sums->lights == lights && entry.sums->per_replica * entry.sums->replicas == file.photons &&
        measured_something(*entry.sums)) {
        noise = entry.noise_nrmse;
        return entry.sums;
    }
    std::fprintf(stderr, "reference: cache entry %s is damaged or stale; recomputing\n", file.path.string().c_str());
    std::error_code ec;
    fs::remove(file.path, ec);
    return nullptr;
}

void store_entry(const ReferenceResult& result, const std::string& key, const std::string& cache_dir) {
    // compute_reference refuses an empty reference; this keeps one out of the cache whatever its caller.
    if (!result.sums || !measured_something(*result.sums)) return;
    // Store atomically. A cache that cannot be written costs time later, not correctness now.
    std::error_code ec;
    fs::create_directories(cache_dir, ec);
    const fs::path path = fs::path(cache_dir) / (key + "-" + std::to_string(result.photons) + ".ref");
    const fs::path tmp = fs::path(path.string() + temporary_suffix());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        const std::string encoded = encode_file(result, key);
        out.write(encoded.data(), static_cast<std::streamsize>(encoded.size()));
        out.close();
        if (!out) {
            std::fprintf(stderr, "reference: warning: cannot write cache file %s\n", tmp.string().c_str());
            fs::remove(tmp, ec);
            return;
        }
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        std::fprintf(stderr, "reference: warning: cannot store cache file %s: %s\n", path.string().c_str(),
                     ec.message().c_str());
        fs::remove(tmp, ec);
    }
}

}  // namespace

ReferenceResult load_or_compute_reference(const FrameGeometry& frame, const RayTracer& tracer,
                                          const ReceiverChart& chart, const CameraGBuffer* camera,
                                          const ReferenceSettings& settings, const std::string& cache_dir) {
    // The key hashes the scene file's bytes; a scene built in code has none, so two different ones
    // would share a key. Those are computed every time and never cached.
    if (frame.scene->source_text.empty()) return compute_reference(tracer, chart, camera, settings);
    ReferenceSettings keyed = settings;
    keyed.camera_view = settings.camera_view && camera != nullptr;
    const std::string key = reference_cache_key(*frame.scene, frame.frame, keyed);
    const std::size_t lights = frame.scene->lights.size();
    const std::size_t bins = static_cast<std::size_t>(chart.width()) * chart.height();
    const std::size_t pixels = keyed.camera_view ? camera->covered.size() : 0;
    const std::size_t volume_pixels = scene_scatters(*frame.scene) ? pixels : 0;   // camera_volume (reference.cpp)
    const std::uint64_t wanted = photons_per_replica(settings.photons, settings.replicas, lights) *
                                 static_cast<std::uint64_t>(std::max(1, settings.replicas));
    const bool target = settings.noise_target > 0.0;

    // Serve an entry that answers the request; else extend the largest smaller one.
    std::shared_ptr<const ReferenceSums> start;
    for (const EntryFile& file : entries_of(cache_dir, key)) {
        if (!target && file.photons > wanted) break;
        double noise = 0.0;
        std::shared_ptr<const ReferenceSums> sums = read_entry(file, key, bins, pixels, volume_pixels, keyed, lights, noise);
        if (!sums) continue;
        const bool answers = target ? (noise <= settings.noise_target || file.photons >= settings.photon_cap)
                                    : file.photons == wanted;
        if (answers) {
            ReferenceResult cached = reference_from_sums(tracer, chart, camera, keyed, sums);
            cached.from_cache = true;
            cached.seconds = 0.0;
            return cached;
        }
        start = std::move(sums);
    }

    ReferenceSettings run = keyed;
    if (target && start) run.photons = std::max(run.photons, start->per_replica * start->replicas);
    ReferenceResult result = compute_reference(tracer, chart, camera, run, start.get());
    result.from_cache = false;
    store_entry(result, key, cache_dir);
    if (start) {   // the extended entry holds every photon of the smaller one: it is no longer needed
        std::error_code ec;
        fs::remove(fs::path(cache_dir) / (key + "-" + std::to_string(start->per_replica * start->replicas) + ".ref"), ec);
    }
    return result;
}

}  // namespace caustics
