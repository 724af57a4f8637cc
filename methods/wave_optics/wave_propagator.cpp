// Fourier-domain propagation of a periodic field (Stam 1996; Moravec 1981): see wave_propagator.hpp.
#include "wave_propagator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "wave_math.hpp"

namespace caustics::wave_optics {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Sum over rows in a fixed order, so results do not depend on the thread count.
double ordered_sum(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s;
}

}  // namespace

WavePropagator::WavePropagator(const WaveSetup& setup, FftRigor rigor)
    : setup_(setup), fft_(setup.nx, setup.ny, rigor),
      spectrum_(static_cast<std::size_t>(setup.nx) * setup.ny),
      work_(static_cast<std::size_t>(setup.nx) * setup.ny) {
    const int nx = setup.nx, ny = setup.ny;
    const double lambda = setup.wavelength;
    if (nx < 2 || ny < 2) throw std::invalid_argument("WavePropagator: grid must be at least 2 x 2");
    if (!(lambda > 0.0) || !(setup.lx > 0.0) || !(setup.ly > 0.0))
        throw std::invalid_argument("WavePropagator: wavelength and period must be positive");
    const glm::dvec2 fc(setup.carrier_bins.x / setup.lx, setup.carrier_bins.y / setup.ly);
    const double k2 = 1.0 / (lambda * lambda);   // (1/lambda)^2, cycles^2 / m^2
    const bool as = setup.propagator == Propagator::AngularSpectrum;
    if (as) {
        const double kzc2 = k2 - glm::dot(fc, fc);
        if (!(kzc2 > 0.0)) throw std::invalid_argument("WavePropagator: the carrier is evanescent");
        walk_ = fc / std::sqrt(kzc2);
    } else {
        walk_ = lambda * fc;
    }
    if (setup.shift_walk) walk_ = *setup.shift_walk;
    const double kzc = as ? std::sqrt(k2 - glm::dot(fc, fc)) : 0.0;
    rate_.assign(static_cast<std::size_t>(nx) * ny, 0.0);
    limit_.assign(static_cast<std::size_t>(nx) * ny, 0.0);
    const double half_lx = 0.5 * setup.lx, half_ly = 0.5 * setup.ly;
    tbb::parallel_for(0, ny, [&](int iy) {
        const double fy = signed_index(iy, ny) / setup.ly;
        for (int ix = 0; ix < nx; ++ix) {
            const double fx = signed_index(ix, nx) / setup.lx;
            const std::size_t k = static_cast<std::size_t>(iy) * nx + ix;
            if (!as) {
                // -pi lambda (|f + fc|^2 - |fc|^2) + 2 pi f . walk
                rate_[k] = -std::numbers::pi * lambda * (fx * fx + fy * fy + 2.0 * (fx * fc.x + fy * fc.y)) +
                           kTwoPi * (fx * walk_.x + fy * walk_.y);
                continue;
            }
            const double tx = fx + fc.x, ty = fy + fc.y;
            const double kz2 = k2 - (tx * tx + ty * ty);
            if (!(kz2 > 0.0)) {
                limit_[k] = -1.0;   // evanescent
                continue;
            }
            const double kz = std::sqrt(kz2);
            rate_[k] = kTwoPi * (kz - kzc + fx * walk_.x + fy * walk_.y);
            // Walk per unit depth relative to the carrier, in units of half a period.
            const double qx = std::abs(tx / kz - walk_.x) / half_lx;
            const double qy = std::abs(ty / kz - walk_.y) / half_ly;
            limit_[k] = std::max(qx, qy);
        }
    });
}

glm::dvec3 WavePropagator::carrier_direction() const {
    return glm::normalize(glm::dvec3(walk_.x, walk_.y, -1.0));
}

std::int64_t WavePropagator::set_phase_screen(const float* height, float phase_scale) {
    const int nx = setup_.nx, ny = setup_.ny;
    std::vector<std::int64_t> aliased(static_cast<std::size_t>(ny), 0);
    ComplexF* u = spectrum_.data();
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 8), [&](const tbb::blocked_range<int>& r) {
        for (int iy = r.begin(); iy < r.end(); ++iy) {
            const float* h = height + static_cast<std::size_t>(iy) * nx;
            const float* h_next = height + static_cast<std::size_t>((iy + 1) % ny) * nx;
            ComplexF* row = u + static_cast<std::size_t>(iy) * nx;
            std::int64_t count = 0;
            for (int ix = 0; ix < nx; ++ix) {
                float s, c;
                fast_sincos(phase_scale * h[ix], s, c);
                row[ix] = ComplexF(c, s);
            }
            // Phase steps to the next cell in x (periodic) and y; |a h_i - a h_j| = |a (h_i - h_j)|.
            const float limit = std::numbers::pi_v<float> / std::max(std::abs(phase_scale), 1e-30f);
            for (int ix = 0; ix < nx; ++ix) {
                const float right = ix + 1 < nx ? h[ix + 1] : h[0];
                const bool big = std::abs(right - h[ix]) > limit || std::abs(h_next[ix] - h[ix]) > limit;
                count += big ? 1 : 0;
            }
            aliased[static_cast<std::size_t>(iy)] = count;
        }
    });
    fft_.forward(u);
    std::int64_t total = 0;
    for (std::int64_t c : aliased) total += c;
    return total;
}

void WavePropagator::set_field(const ComplexF* field) {
    std::copy(field, field + spectrum_.size(), spectrum_.data());
    fft_.forward(spectrum_.data());
}

bool WavePropagator::fresnel_sampling_ok(double depth) const {
    // The transfer function's phase z rate(f) / 2 pi may advance at most half a cycle per frequency
    // sample 1/L: z |lambda (f + fc) - walk| <= L/2 for |f| up to Nyquist N / (2 L). Without a shift this
    // is z <= L^2 / (lambda N).
    const double l = setup_.wavelength;
    const glm::dvec2 fc(setup_.carrier_bins.x / setup_.lx, setup_.carrier_bins.y / setup_.ly);
    const double sx = depth * (l * setup_.nx / (2.0 * setup_.lx) + std::abs(l * fc.x - walk_.x));
    const double sy = depth * (l * setup_.ny / (2.0 * setup_.ly) + std::abs(l * fc.y - walk_.y));
    return sx <= 0.5 * setup_.lx * (1.0 + 1e-12) && sy <= 0.5 * setup_.ly * (1.0 + 1e-12);
}

int WavePropagator::as_bin_class(int ix, int iy, double depth) const {
    if (setup_.propagator != Propagator::AngularSpectrum) return 0;
    const double q = limit_[static_cast<std::size_t>(iy) * setup_.nx + ix];
    if (q < 0.0) return 1;
    return depth * q > 1.0 ? 2 : 0;
}

void WavePropagator::fill_transfer(double depth, ComplexF* H) const {
    const int nx = setup_.nx, ny = setup_.ny;
    const double norm = 1.0 / (static_cast<double>(nx) * ny);   // the unnormalised inverse transform
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 8), [&](const tbb::blocked_range<int>& r) {
        for (int iy = r.begin(); iy < r.end(); ++iy) {
            for (int ix = 0; ix < nx; ++ix) {
                const std::size_t k = static_cast<std::size_t>(iy) * nx + ix;
                const double q = limit_[k];
                if (q < 0.0 || depth * q > 1.0) {
                    H[k] = ComplexF(0.0f, 0.0f);
                    continue;
                }
                double phase = depth * rate_[k];
                phase -= kTwoPi * std::nearbyint(phase * (1.0 / kTwoPi));   // exact reduction in double
                float s, c;
                fast_sincos(static_cast<float>(phase), s, c);
                H[k] = ComplexF(static_cast<float>(c * norm), static_cast<float>(s * norm));
            }
        }
    });
}

const ComplexF* WavePropagator::transfer(double depth) {
    for (const auto& [d, H] : cache_)
        if (d == depth) return H.data();
    const std::size_t bytes = spectrum_.size() * sizeof(ComplexF);
    if ((cache_.size() + 1) * bytes > kCacheBytes) {
        fill_transfer(depth, work_.data());   // no room: computed into the work buffer, multiplied in place
        return nullptr;
    }
    cache_.emplace_back(depth, ComplexBuffer(spectrum_.size()));
    fill_transfer(depth, cache_.back().second.data());
    return cache_.back().second.data();
}

PropagationStats WavePropagator::propagate(double depth, const IntensityTarget* targets, int target_count) {
    const int nx = setup_.nx, ny = setup_.ny;
    std::vector<double> total(static_cast<std::size_t>(ny), 0.0), evanescent(total), limited(total);
    const ComplexF* U = spectrum_.data();
    ComplexF* W = work_.data();
    const ComplexF* cached = transfer(depth);
    const ComplexF* H = cached != nullptr ? cached : W;   // uncached: H already sits in W
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 8), [&](const tbb::blocked_range<int>& r) {
        for (int iy = r.begin(); iy < r.end(); ++iy) {
            double sum = 0.0, ev = 0.0, bl = 0.0;
            const std::size_t row = static_cast<std::size_t>(iy) * nx;
            for (int ix = 0; ix < nx; ++ix) {
                const std::size_t k = row + ix;
                const double e = std::norm(U[k]);
                sum += e;
                const float hr = H[k].real(), hi = H[k].imag();
                if (hr == 0.0f && hi == 0.0f) (limit_[k] < 0.0 ? ev : bl) += e;
                const float ur = U[k].real(), ui = U[k].imag();
                W[k] = ComplexF(ur * hr - ui * hi, ur * hi + ui * hr);   // no NaN-checking complex multiply
            }
            total[static_cast<std::size_t>(iy)] = sum;
            evanescent[static_cast<std::size_t>(iy)] = ev;
            limited[static_cast<std::size_t>(iy)] = bl;
        }
    });
    fft_.inverse(W);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, work_.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
        for (int t = 0; t < target_count; ++t) {
            float* out = targets[t].out;
            const float w = targets[t].weight;
            if (targets[t].assign) {
                for (std::size_t k = r.begin(); k < r.end(); ++k) out[k] = w * std::norm(W[k]);
            } else {
                for (std::size_t k = r.begin(); k < r.end(); ++k) out[k] += w * std::norm(W[k]);
            }
        }
    });
    PropagationStats stats;
    stats.total_energy = ordered_sum(total);
    stats.evanescent_energy = ordered_sum(evanescent);
    stats.band_limited_energy = ordered_sum(limited);
    if (setup_.propagator == Propagator::Fresnel)
        stats.sampling_ok = fresnel_sampling_ok(depth);
    else
        stats.sampling_ok = stats.band_limited_energy <= 1e-6 * stats.total_energy;
    return stats;
}

}  // namespace caustics::wave_optics
