#pragma once
// The error block of one run's metrics.json (docs/design.md section 6, issue 11): plain metrics against the
// truth, the same net of the reference's noise with 95 % intervals, the per-bin consistency test, and
// the comparison with the no-caustic baseline.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/util/image.hpp>
#include <caustics/run/net_error.hpp>

namespace caustics {

// The no-caustic baseline of a scene frame: what the flat interface would transmit, or the best
// constant over the bins the truth lights.
struct Baseline {
    Image map;
    std::string kind;   // "flat_interface" or "constant"
};
// `flat` is flat_interface_baseline()'s map (empty when the scene has no height-field interface).
Baseline make_baseline(Image flat, const Image& truth_mean);

struct ViewErrors {
    nlohmann::json json;            // the keys of error.receiver / error.camera
    NetError net;                   // the error the report ranks: nrmse_net, or nrmse_fit_net (not radiometric)
    bool have_baseline = false;
    double baseline_error = 0.0;    // the baseline's net error of the same kind
    // Not clearly below the baseline: the upper end of the run's 95 % interval reaches the baseline's error.
    bool no_better_than_flat = false;
    std::int64_t samples = 0;       // pixels compared
};

// `mask` selects pixels (null: all); `baseline` may be null (no comparison). Non-finite method values are
// the caller's to exclude (a run with any is unstable and not measured).
ViewErrors measure_view(const Image& method, const TruthMaps& truth, const std::vector<std::uint8_t>* mask,
                        bool radiometric, const Image* baseline);

// Every key measure_view writes, null: the error block of a run that measured nothing.
nlohmann::json null_view_errors();

}  // namespace caustics
