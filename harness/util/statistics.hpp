#pragma once
// Small statistics the measurement protocol needs (docs/design.md section 6): Student-t tail probabilities
// and quantiles (standard errors from R replicas have R - 1 degrees of freedom), Sidak-corrected
// per-bin thresholds (as in Mitsuba's render tests), and distribution-free confidence intervals of a
// median from order statistics.
#include <cstddef>
#include <vector>

namespace caustics {

// Regularized incomplete beta function I_x(a, b), a, b > 0, x in [0, 1].
double incomplete_beta(double a, double b, double x);

// P(|T| > t) for Student's t with `dof` degrees of freedom (dof >= 1; dof = inf -> normal).
double student_t_two_sided_p(double t, double dof);

// The t with P(|T| > t) = p (0 < p < 1): the two-sided critical value.
double student_t_critical(double p, double dof);

// Per-test two-sided level that keeps the family-wise level `alpha` over `tests` independent tests:
// 1 - (1 - alpha)^(1 / tests).
double sidak_level(double alpha, std::size_t tests);

// A distribution-free interval of the median of `sorted` (ascending) at confidence >= `confidence`
// from order statistics (binomial(n, 1/2)); lo == hi == median for fewer than 6 samples (no interval).
struct MedianInterval {
    double median = 0.0, lo = 0.0, hi = 0.0;
    bool has_interval = false;
};
MedianInterval median_interval(const std::vector<double>& sorted, double confidence = 0.95);

}  // namespace caustics
