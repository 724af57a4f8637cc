// The reference's estimates from its integer sums (docs/design.md section 5; the noise model is in
// reference.cpp's file comment): per view, the mean over the replicas, its standard error and each
// replica's own image, and the flux ledger in watts.
#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "detail/transport.hpp"

namespace caustics::detail {
namespace {

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

// Mean, standard error and per-replica images of one view from its replica sums; `area(k)` is the
// measure that turns a sum into irradiance (0: not measured).
template <class Area>
void estimate_view(const SumVector& sums, std::size_t count, std::uint32_t replicas, double unit,
                   int width, int height, Area area, Image& mean, Image& stderr_image, std::vector<Image>& per_replica) {
    // The 2 + R images: zeroed memory (util/image.hpp), written below only where a replica deposited.
    // Allocated in parallel: heap memory (below 1 MiB) and reused blocks are cleared when allocated.
    per_replica.assign(replicas, Image());
    tbb::parallel_for(std::uint32_t{0}, replicas + 2, [&](std::uint32_t i) {
        (i == replicas ? mean : i == replicas + 1 ? stderr_image : per_replica[i]) = Image(width, height);
    });
    const double r = replicas;
    // Pixels in parallel (each is its own computation: the same bits for any thread count). A pixel no
    // replica deposited in keeps its zeros without its measure being computed (four atan per camera
    // pixel: most of a 1024 x 768 view is dark).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
            bool any = false;
            for (std::uint32_t rep = 0; rep < replicas && !any; ++rep) any = sums[rep * count + k] != 0;
            if (!any) continue;
            const double a = area(k);
            if (!(a > 0.0)) continue;
            double sum = 0.0, sq = 0.0;
            for (std::uint32_t rep = 0; rep < replicas; ++rep) {
                const double e = static_cast<double>(sums[rep * count + k]) / kFixedScale * unit / a;
                per_replica[rep].pixels[k] = static_cast<float>(e);
                sum += e;
                sq += e * e;
            }
            const double m = sum / r;
            const double var = replicas > 1 ? std::max(0.0, (sq - r * m * m) / (r - 1.0)) / r : 0.0;
            mean.pixels[k] = static_cast<float>(m);
            stderr_image.pixels[k] = static_cast<float>(std::sqrt(var));
        }
    });
}

}  // namespace

ReferenceResult finish_reference(const Transport& transport, const ReceiverChart& chart, const CameraGBuffer* camera,
                                 const CameraModel* camera_model, std::shared_ptr<const ReferenceSums> sums) {
    ReferenceResult result;
    // One replica's photon of light l carries q0 = P_l / scale at n / L photons per light: E = q sum *
    // scale * L / (n * A).
    const double unit = transport.scale * static_cast<double>(sums->lights) / static_cast<double>(sums->per_replica);
    estimate_view(sums->bin_sums, sums->bins, sums->replicas, unit, chart.width(), chart.height(),
                  [&](std::size_t k) { return chart.bin_area(static_cast<int>(k % chart.width()), static_cast<int>(k / chart.width())); },
                  result.receiver, result.receiver_stderr, result.receiver_replicas);
    result.noise_nrmse = nrmse_of(result.receiver, result.receiver_stderr, nullptr);
    if (camera && sums->pixels > 0) {
        result.camera_covered.reserve(camera->covered.size());
        prepare_fresh_memory(result.camera_covered.data(), camera->covered.size());
        result.camera_covered.assign(camera->covered.begin(), camera->covered.end());
        // E_pix = sum w / A_dep = (unit / A_c) sum x with A_c = omega * pixel_scale.
        estimate_view(sums->pixel_sums, sums->pixels, sums->replicas, unit, camera->width, camera->height,
                      [&](std::size_t k) {
                          if (!camera->covered[k]) return 0.0;
                          const int x = static_cast<int>(k % camera->width), y = static_cast<int>(k / camera->width);
                          return camera_model->pixel_solid_angle(x, y) * transport.pixel_info[k].scale;
                      },
                      result.camera, result.camera_stderr, result.camera_replicas);
        result.noise_nrmse_camera = nrmse_of(result.camera, result.camera_stderr, &result.camera_covered);
    }
    if (camera && sums->volume_pixels > 0 && !transport.volume_scale.empty()) {
        // L_pix = (unit / (Omega_pix s_k)) sum x (reference_volume.cpp); every pixel is measured.
        estimate_view(sums->volume_sums, sums->volume_pixels, sums->replicas, unit, camera->width, camera->height,
                      [&](std::size_t k) {
                          const int x = static_cast<int>(k % camera->width), y = static_cast<int>(k / camera->width);
                          return camera_model->pixel_solid_angle(x, y) * transport.volume_scale[k];
                      },
                      result.camera_volume, result.camera_volume_stderr, result.camera_volume_replicas);
        result.noise_nrmse_volume = nrmse_of(result.camera_volume, result.camera_volume_stderr, nullptr);
    }
    // The ledger in watts: all replicas together are R n photons, L per light-set.
    const double watts = transport.scale * sums->lights / (static_cast<double>(sums->per_replica) * sums->replicas);
    const FluxLedger& u = sums->ledger_units;
    result.ledger = {u.emitted * watts, u.deposited_receiver * watts, u.deposited_other * watts, u.direct * watts,
                     u.escaped * watts, u.absorbed * watts, u.scattered * watts, u.truncated * watts};
    result.photons = sums->per_replica * sums->replicas;
    result.replicas = static_cast<int>(sums->replicas);
    result.sums = std::move(sums);
    return result;
}

}  // namespace caustics::detail
