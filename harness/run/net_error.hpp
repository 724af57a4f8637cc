#pragma once
// Errors net of the reference's own noise (docs/design.md section 6, issue 11).
//
// A Monte Carlo reference r = t + noise makes mean((m - r)^2) overestimate the method's true error
// mean((m - t)^2) by the reference's variance. With R independent replicas r_k the products
// (m - r_k)(m - r_l), k != l, are unbiased for (m - t)^2 in every bin (the replicas are independent), so
//   U = mean over bins of [ (sum_k d_k)^2 - sum_k d_k^2 ] / (R (R - 1)),   d_k = m - r_k,
// is an unbiased estimate of the squared error against the truth; it equals
// mean((m - r)^2) - mean(se^2) with se the replicas' standard error of r = mean(r_k). Its 95 % interval
// comes from the delete-one-replica jackknife with Student-t quantiles (R - 1 degrees of freedom).
// nrmse_net = sqrt(max(U, 0)) / mean(r); the interval's ends are transformed the same way.
// An exact truth (analytic closed form) has no replicas: the net error is then the plain error and the
// interval is that single value.
#include <cstdint>
#include <vector>

#include <caustics/util/image.hpp>

namespace caustics {

// What errors are measured against: the reference's mean and, for Monte Carlo, its replicas.
struct TruthMaps {
    const Image* mean = nullptr;                      // reference mean, or the analytic truth
    const std::vector<Image>* replicas = nullptr;     // null or empty: exact truth
    const Image* stderr_image = nullptr;              // per-bin standard error (null: exact)
    bool exact() const { return replicas == nullptr || replicas->size() < 2; }
};

struct NetError {
    double value = 0.0;          // sqrt(max(U, 0)) / mean(r)
    double lo = 0.0, hi = 0.0;   // its 95 % interval
    double squared = 0.0;        // U / mean(r)^2 (may be negative: within the reference's noise)
    bool includes_zero = false;  // the interval's lower end of U is <= 0
    bool valid = false;          // false when nothing could be compared (no pixels, zero mean)
};

// Net nrmse of `scale * method` against the truth over the pixels `mask` selects (null: all).
// `weights` (optional) turns it into a weighted mean square (relmse: 1 / (r^2 + eps)), reported
// without the normalisation by mean(r): NetError::value is then sqrt(max(U, 0)) and `squared` is U.
NetError net_error(const Image& method, const TruthMaps& truth, const std::vector<std::uint8_t>* mask,
                   double scale = 1.0, const std::vector<double>* weights = nullptr, double confidence = 0.95);

// relmse net of the reference noise: mean over bins of (m - t)^2 / (r^2 + eps), eps = (0.01 mean(r))^2,
// estimated as above with the weights taken at the reference mean.
double net_relmse(const Image& method, const TruthMaps& truth, const std::vector<std::uint8_t>* mask);

// Per-bin test of the method against the reference (Mitsuba's render tests): t = (m - r) / se with
// R - 1 degrees of freedom, two-sided, Sidak-corrected over the tested bins at family level `alpha`.
// Bins with se = 0 cannot be tested: if m == r there they pass, else they are counted as untestable.
struct ConsistencyTest {
    bool tested = false;         // false for an exact truth (nothing to test against)
    bool consistent = false;     // every tested bin passes
    std::int64_t bins_tested = 0, bins_failed = 0, untestable = 0;
    double worst_t = 0.0, threshold = 0.0;
};
ConsistencyTest consistency_test(const Image& method, const TruthMaps& truth, const std::vector<std::uint8_t>* mask,
                                 double scale = 1.0, double alpha = 0.01);

// The least-squares scale <m, r> / <m, m> over the mask (1 when m is zero).
double least_squares_scale(const Image& method, const Image& reference, const std::vector<std::uint8_t>* mask);

}  // namespace caustics
