#include <caustics/run/run_errors.hpp>

#include <cmath>

#include <caustics/run/metrics.hpp>

namespace caustics {
namespace {

using nlohmann::json;

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

Baseline make_baseline(Image flat, const Image& truth_mean) {
    Baseline b;
    if (!flat.empty()) {
        b.map = std::move(flat);
        b.kind = "flat_interface";
        return b;
    }
    // The least-squares constant over the lit bins is their mean; unlit bins stay 0.
    double sum = 0.0;
    std::size_t lit = 0;
    for (float v : truth_mean.pixels)
        if (v > 0.0f) sum += v, ++lit;
    b.map = Image(truth_mean.width, truth_mean.height, 1);
    const float c = lit ? static_cast<float>(sum / static_cast<double>(lit)) : 0.0f;
    for (std::size_t k = 0; k < b.map.pixels.size(); ++k) b.map.pixels[k] = truth_mean.pixels[k] > 0.0f ? c : 0.0f;
    b.kind = "constant";
    return b;
}

json null_view_errors() {
    json j;
    for (const char* key : {"nrmse", "relmse", "psnr", "ssim", "nrmse_fit", "fit_scale", "nrmse_net", "nrmse_net_lo",
                            "nrmse_net_hi", "relmse_net", "nrmse_fit_net", "nrmse_fit_net_lo", "nrmse_fit_net_hi",
                            "consistent_with_reference", "baseline_nrmse", "baseline_nrmse_fit", "error_vs_baseline"})
        j[key] = nullptr;
    return j;
}

ViewErrors measure_view(const Image& method, const TruthMaps& truth, const std::vector<std::uint8_t>* mask,
                        bool radiometric, const Image* baseline) {
    ViewErrors v;
    json& j = v.json;
    j = null_view_errors();
    const bool fit = !radiometric;
    const ErrorMetrics e = compare_images(method, *truth.mean, fit, mask);
    v.samples = e.samples;
    if (e.samples == 0) return v;
    j["nrmse"] = number(e.nrmse);
    j["relmse"] = number(e.relmse);
    j["psnr"] = number(e.psnr);
    j["ssim"] = number(e.ssim);

    const NetError net = net_error(method, truth, mask);
    if (net.valid) {
        j["nrmse_net"] = number(net.value);
        j["nrmse_net_lo"] = number(net.lo);
        j["nrmse_net_hi"] = number(net.hi);
    }
    j["relmse_net"] = number(std::max(0.0, net_relmse(method, truth, mask)));
    double scale = 1.0;
    NetError ranked = net;
    if (fit) {   // a radiometric method is never fitted (docs/design.md section 3)
        j["nrmse_fit"] = number(e.nrmse_fit);
        j["fit_scale"] = number(e.fit_scale);
        scale = e.fit_scale;
        ranked = net_error(method, truth, mask, scale);
        if (ranked.valid) {
            j["nrmse_fit_net"] = number(ranked.value);
            j["nrmse_fit_net_lo"] = number(ranked.lo);
            j["nrmse_fit_net_hi"] = number(ranked.hi);
        }
    }
    v.net = ranked;
    const ConsistencyTest test = consistency_test(method, truth, mask, scale);
    j["consistent_with_reference"] = test.tested ? json(test.consistent) : json(nullptr);

    if (baseline && !baseline->empty() && ranked.valid) {
        const NetError plain = net_error(*baseline, truth, mask);
        const NetError fitted = net_error(*baseline, truth, mask, least_squares_scale(*baseline, *truth.mean, mask));
        j["baseline_nrmse"] = plain.valid ? number(plain.value) : json(nullptr);
        j["baseline_nrmse_fit"] = fitted.valid ? number(fitted.value) : json(nullptr);
        const NetError& same_kind = fit ? fitted : plain;
        if (same_kind.valid && same_kind.value > 0.0) {
            v.have_baseline = true;
            v.baseline_error = same_kind.value;
            j["error_vs_baseline"] = number(ranked.value / same_kind.value);
            v.no_better_than_flat = !(ranked.hi < same_kind.value);
        }
    }
    return v;
}

}  // namespace caustics
