// The on-disk reference cache (DESIGN.md section 5).
//
// Key: a 128-bit hash of everything the reference depends on (scene bytes, every asset's bytes, frame,
// photons, seed, camera view, receiver and camera sizes, kReferenceVersion).
// File cache_dir/<key>.ref:
//   magic "CAUSREF\n" | u32 file format | u32 kReferenceVersion | key (u64 length + bytes)
//   | u64 payload size | payload | u64 checksum64(payload)
// Anything that does not match exactly (truncation, flipped bits, another version, another key) makes
// the entry stale: it is recomputed and rewritten (temporary name, then rename), never used.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "hash.hpp"
#include "reference.hpp"

namespace caustics {
namespace {

// Bump whenever reference.cpp changes what it computes (transport, estimators, sampling).
constexpr std::uint32_t kReferenceVersion = 2;
constexpr std::uint32_t kFileFormat = 1;
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
        std::memcpy(dst, p_, n);
        p_ += n;
    }
    std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }

private:
    const char* p_;
    const char* end_;
};

std::string serialize_payload(const ReferenceResult& r) {
    Writer w;
    w.image(r.receiver);
    w.image(r.receiver_stderr);
    w.image(r.camera);
    w.image(r.camera_stderr);
    w.u64(r.camera_covered.size());
    w.raw(r.camera_covered.data(), r.camera_covered.size());
    w.f64(r.noise_nrmse);
    w.f64(r.noise_nrmse_camera);
    const FluxLedger& l = r.ledger;
    for (double v : {l.emitted, l.deposited_receiver, l.deposited_other, l.direct, l.escaped, l.absorbed, l.truncated})
        w.f64(v);
    w.u64(r.photons);
    w.u64(r.seed);
    w.f64(r.seconds);   // how long the computation took when it was made (informational)
    return std::move(w.out);
}

ReferenceResult parse_payload(Reader& in) {
    ReferenceResult r;
    r.receiver = in.image();
    r.receiver_stderr = in.image();
    r.camera = in.image();
    r.camera_stderr = in.image();
    const std::uint64_t covered = in.u64();
    if (covered > in.remaining()) throw Corrupt{};
    r.camera_covered.resize(covered);
    in.raw(r.camera_covered.data(), covered);
    r.noise_nrmse = in.f64();
    r.noise_nrmse_camera = in.f64();
    FluxLedger& l = r.ledger;
    for (double* v : {&l.emitted, &l.deposited_receiver, &l.deposited_other, &l.direct, &l.escaped, &l.absorbed,
                      &l.truncated})
        *v = in.f64();
    r.photons = in.u64();
    r.seed = in.u64();
    in.f64();   // original compute time
    if (in.remaining() != 0) throw Corrupt{};
    return r;
}

std::string encode_file(const ReferenceResult& r, const std::string& key) {
    const std::string payload = serialize_payload(r);
    Writer w;
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
bool decode_file(const std::string& bytes, const std::string& key, ReferenceResult& out) {
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

}  // namespace

std::string reference_cache_key(const Scene& scene, int frame, const ReferenceSettings& settings) {
    Hash128 h;
    h.text("caustics-reference");
    h.u64(kReferenceVersion);
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
    h.u64(static_cast<std::uint64_t>(frame));
    h.u64(settings.photons);
    h.u64(settings.seed);
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

ReferenceResult load_or_compute_reference(const FrameGeometry& frame, const RayTracer& tracer,
                                          const ReceiverChart& chart, const CameraGBuffer* camera,
                                          const ReferenceSettings& settings, const std::string& cache_dir) {
    namespace fs = std::filesystem;
    // The key hashes the scene file's bytes; a scene built in code has none, so two different ones
    // would share a key. Those are computed every time and never cached.
    if (frame.scene->source_text.empty()) return compute_reference(tracer, chart, camera, settings);
    ReferenceSettings keyed = settings;
    keyed.camera_view = settings.camera_view && camera != nullptr;
    const std::string key = reference_cache_key(*frame.scene, frame.frame, keyed);
    const fs::path path = fs::path(cache_dir) / (key + ".ref");

    std::string bytes;
    if (read_file_bytes(path.string(), bytes)) {
        ReferenceResult cached;
        if (decode_file(bytes, key, cached)) {
            // The receiver and camera sizes are part of the key; a mismatch here means a damaged entry.
            const bool sizes_ok = cached.receiver.width == chart.width() && cached.receiver.height == chart.height() &&
                                  (!keyed.camera_view ||
                                   (cached.camera.width == camera->width && cached.camera.height == camera->height));
            if (sizes_ok) {
                cached.cache_key = key;
                cached.from_cache = true;
                cached.seconds = 0.0;
                return cached;
            }
        }
        std::fprintf(stderr, "reference: cache entry %s is damaged or stale; recomputing\n", path.string().c_str());
    }

    ReferenceResult result = compute_reference(tracer, chart, camera, keyed);
    result.cache_key = key;
    result.from_cache = false;

    // Store atomically. A cache that cannot be written costs time later, not correctness now.
    std::error_code ec;
    fs::create_directories(cache_dir, ec);
    const fs::path tmp = fs::path(cache_dir) / (key + ".ref.tmp." + std::to_string(::getpid()));
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        const std::string encoded = encode_file(result, key);
        out.write(encoded.data(), static_cast<std::streamsize>(encoded.size()));
        out.close();
        if (!out) {
            std::fprintf(stderr, "reference: warning: cannot write cache file %s\n", tmp.string().c_str());
            fs::remove(tmp, ec);
            return result;
        }
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        std::fprintf(stderr, "reference: warning: cannot store cache file %s: %s\n", path.string().c_str(),
                     ec.message().c_str());
        fs::remove(tmp, ec);
    }
    return result;
}

}  // namespace caustics
