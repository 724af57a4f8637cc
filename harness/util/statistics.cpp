#include <caustics/util/statistics.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace caustics {
namespace {

// Continued fraction of the incomplete beta function (modified Lentz's method).
double beta_continued_fraction(double a, double b, double x) {
    constexpr double kTiny = 1e-300, kEps = 1e-15;
    const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
    double c = 1.0, d = 1.0 - qab * x / qap;
    if (std::abs(d) < kTiny) d = kTiny;
    d = 1.0 / d;
    double h = d;
    for (int m = 1; m <= 500; ++m) {
        const int m2 = 2 * m;
        double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < kTiny) d = kTiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        h *= d * c;
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < kTiny) d = kTiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < kEps) break;
    }
    return h;
}

}  // namespace

double incomplete_beta(double a, double b, double x) {
    if (!(x > 0.0)) return 0.0;
    if (!(x < 1.0)) return 1.0;
    const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) +
                                  b * std::log1p(-x));
    // The continued fraction converges fast for x < (a + 1) / (a + b + 2); use the symmetry otherwise.
    if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_continued_fraction(a, b, x) / a;
    return 1.0 - front * beta_continued_fraction(b, a, 1.0 - x) / b;
}

double student_t_two_sided_p(double t, double dof) {
    t = std::abs(t);
    if (!std::isfinite(t)) return 0.0;
    if (!std::isfinite(dof) || dof > 1e7) return std::erfc(t / std::sqrt(2.0));
    return incomplete_beta(0.5 * dof, 0.5, dof / (dof + t * t));
}

double student_t_critical(double p, double dof) {
    p = std::clamp(p, 1e-300, 1.0);
    // Bisection on a monotone function; the upper bound grows until it brackets.
    double lo = 0.0, hi = 1.0;
    while (student_t_two_sided_p(hi, dof) > p && hi < 1e12) hi *= 2.0;
    for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (student_t_two_sided_p(mid, dof) > p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

double sidak_level(double alpha, std::size_t tests) {
    if (tests <= 1) return alpha;
    // 1 - (1 - alpha)^(1/n) without cancellation.
    return -std::expm1(std::log1p(-alpha) / static_cast<double>(tests));
}

MedianInterval median_interval(const std::vector<double>& sorted, double confidence) {
    MedianInterval r;
    const std::size_t n = sorted.size();
    if (n == 0) return r;
    r.median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
    r.lo = r.hi = r.median;
    if (n < 6) return r;
    // The largest k with P(Binomial(n, 1/2) < k) <= (1 - confidence) / 2: [x_(k), x_(n+1-k)] (1-based)
    // covers the median with probability >= confidence.
    const double tail = 0.5 * (1.0 - confidence);
    double cdf = 0.0;
    std::size_t k = 0;
    const double log_half_n = static_cast<double>(n) * std::log(0.5);
    for (std::size_t j = 0; j < n; ++j) {
        const double pj = std::exp(std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0) + log_half_n);
        if (cdf + pj > tail) break;
        cdf += pj;
        k = j + 1;   // P(B <= j) <= tail, so the order statistic j + 1 is a valid lower bound
    }
    if (k == 0) return r;
    r.lo = sorted[k - 1];
    r.hi = sorted[n - k];
    r.has_interval = true;
    return r;
}

}  // namespace caustics
