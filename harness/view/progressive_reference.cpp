#include <caustics/view/progressive_reference.hpp>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <filesystem>

#include <tbb/task_arena.h>

namespace caustics::view {
namespace {

bool cacheable(const SceneFrame& sf, const std::string& cache_dir) {
    return !cache_dir.empty() && !sf.scene().source_text.empty();
}

// The total photons that `photons` asks for: a whole number per replica and light (reference.hpp).
std::uint64_t rounded(std::uint64_t photons, const ReferenceSettings& s, std::size_t lights) {
    return photons_per_replica(std::max<std::uint64_t>(photons, 1), s.replicas, lights) * static_cast<std::uint64_t>(s.replicas);
}

}  // namespace

std::uint64_t largest_cached_photons(const SceneFrame& sf, const ReferenceSettings& settings,
                                     const std::string& cache_dir, std::uint64_t photons) {
    if (!cacheable(sf, cache_dir)) return 0;
    ReferenceSettings keyed = settings;
    keyed.camera_view = true;
    const std::string prefix = reference_cache_key(sf.scene(), sf.geometry().frame, keyed) + "-";
    std::uint64_t best = 0;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(cache_dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= prefix.size() + 4 || name.compare(0, prefix.size(), prefix) != 0 ||
            name.compare(name.size() - 4, 4, ".ref") != 0)
            continue;
        const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - 4);
        if (digits.empty() || digits.size() > 19 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
        const std::uint64_t n = std::stoull(digits);
        if (n <= photons) best = std::max(best, n);
    }
    return best;
}

ProgressiveReference::ProgressiveReference(const SceneFrame& sf, ProgressiveSettings settings)
    : sf_(sf), settings_(std::move(settings)) {
    settings_.reference.progress = false;
    settings_.reference.camera_view = true;
    // Rounds are sized here; a noise target ends them early, up to the photon cap.
    noise_target_ = settings_.reference.noise_target;
    settings_.reference.noise_target = 0.0;
    status_.target = rounded(noise_target_ > 0.0 ? settings_.reference.photon_cap : settings_.reference.photons,
                             settings_.reference, sf_.scene().lights.size());
    thread_ = std::thread([this] { run(); });
}

ProgressiveReference::~ProgressiveReference() {
    cancel_ = true;
    if (thread_.joinable()) thread_.join();
}

std::shared_ptr<const ReferenceResult> ProgressiveReference::latest() const {
    std::lock_guard lock(mutex_);
    return latest_;
}

ProgressiveStatus ProgressiveReference::status() const {
    std::lock_guard lock(mutex_);
    return status_;
}

std::vector<std::uint64_t> ProgressiveReference::round_photons() const {
    std::lock_guard lock(mutex_);
    return rounds_;
}

void ProgressiveReference::cancel() { cancel_ = true; }

void ProgressiveReference::wait() {
    if (thread_.joinable()) thread_.join();
}

ReferenceResult ProgressiveReference::trace_round(std::uint64_t photons, const ReferenceResult* previous) {
    ReferenceSettings s = settings_.reference;
    s.photons = photons;
    if (cacheable(sf_, settings_.cache_dir))
        return load_or_compute_reference(sf_.geometry(), sf_.tracer(), sf_.chart(), &sf_.gbuffer(), s, settings_.cache_dir);
    return compute_reference(sf_.tracer(), sf_.chart(), &sf_.gbuffer(), s, previous ? previous->sums.get() : nullptr);
}

void ProgressiveReference::run() {
    if (settings_.low_priority) setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kNice);
    try {
        const ReferenceSettings& s = settings_.reference;
        const std::size_t lights = sf_.scene().lights.size();
        const std::uint64_t target = status_.target;
        std::uint64_t next = settings_.first_round ? settings_.first_round : s.photons / 64;
        next = std::min(target, rounded(std::max<std::uint64_t>(next, ReferenceSettings::kMinPhotons), s, lights));
        bool first = true;
        if (const std::uint64_t cached = largest_cached_photons(sf_, s, settings_.cache_dir, target); cached > next)
            next = cached;
        tbb::task_arena arena(1);
        std::shared_ptr<const ReferenceResult> previous;
        while (!cancel_) {
            auto result = std::make_shared<ReferenceResult>();
            arena.execute([&] { *result = trace_round(next, previous.get()); });
            {
                std::lock_guard lock(mutex_);
                latest_ = result;
                rounds_.push_back(result->photons);
                status_.photons = result->photons;
                status_.rounds = static_cast<int>(rounds_.size());
                if (first) status_.from_cache = result->from_cache;
                if (result->photons_traced > 0 && result->seconds > 0.0)
                    status_.photons_per_second = static_cast<double>(result->photons_traced) / result->seconds;
            }
            first = false;
            previous = result;
            if (result->photons >= target || (noise_target_ > 0.0 && result->noise_nrmse <= noise_target_)) break;
            // Double, but no more than round_seconds at the measured rate (header comment).
            std::uint64_t add = result->photons;
            const double rate = status().photons_per_second;
            if (rate > 0.0) add = std::min<std::uint64_t>(add, static_cast<std::uint64_t>(rate * settings_.round_seconds));
            next = std::min(target, rounded(result->photons + std::max<std::uint64_t>(add, ReferenceSettings::kMinPhotons), s, lights));
        }
    } catch (const std::exception& e) {
        std::lock_guard lock(mutex_);
        status_.error = e.what();
    }
    std::lock_guard lock(mutex_);
    status_.done = true;
}

}  // namespace caustics::view
