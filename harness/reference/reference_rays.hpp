#pragma once
// The rays the reference casts, recorded for throughput measurements (bench/bench_reference.cpp):
// replaying them through bare rtcIntersect1 / rtcOccluded1 gives the cost of the ray queries alone,
// so the photon bookkeeping's share of compute_reference can be measured in the same process.
#include <cstdint>
#include <vector>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/reference.hpp>

namespace caustics {

struct RecordedRay {
    float origin[3];
    float dir[3];
    float tnear;
    float tfar;
    bool shadow;   // a visibility ray (rtcOccluded1) rather than a closest-hit query
    std::uint8_t segment;   // the ray's place in its photon's sequence of queries (0: the emitted ray),
                            // capped at 255: replays group a batch's rays by it (coherent streams)
};

// Traces photons [0, settings.photons) exactly as compute_reference does (same random numbers, same
// paths; single thread) and returns every ray in the order cast, photon after photon.
std::vector<RecordedRay> record_reference_rays(const RayTracer& tracer, const ReceiverChart& chart,
                                               const CameraGBuffer* camera, const ReferenceSettings& settings);

}  // namespace caustics
