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

// Energy sum_k |u_k|^2 of one row and of its evanescent bins (mask 1), in four interleaved partial sums
// (independent dependency chains: a single running double sum is latency-bound), combined in a fixed
// order.
void row_energy(const ComplexF* u, const std::uint8_t* evanescent, int n, double& total, double& lost) {
    double t[4] = {0.0, 0.0, 0.0, 0.0}, l[4] = {0.0, 0.0, 0.0, 0.0};
    int i = 0;
    for (; i + 4 <= n; i += 4)
        for (int j = 0; j < 4; ++j) {
            const double e = std::norm(u[i + j]);
            t[j] += e;
            l[j] += evanescent[i + j] != 0 ? e : 0.0;
        }
    for (; i < n; ++i) {
        const double e = std::norm(u[i]);
        t[0] += e;
        l[0] += evanescent[i] != 0 ? e : 0.0;
    }
    total = (t[0] + t[1]) + (t[2] + t[3]);
    lost = (l[0] + l[1]) + (l[2] + l[3]);
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
    evanescent_.assign(static_cast<std::size_t>(nx) * ny, 0);
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
                evanescent_[k] = 1;
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
    spectrum_sums_.reset();
    std::vector<std::int64_t> aliased(static_cast<std::size_t>(ny), 0);
    // |a h_i - a h_j| > pi  <=>  |h_i - h_j| > pi / |a|.
    const float limit = std::numbers::pi_v<float> / std::max(std::abs(phase_scale), 1e-30f);
    // Each batch of rows is filled just before its row transforms run, while it is still in cache.
    fft_.forward_fused(spectrum_.data(), [&](int y0, int y1, ComplexF* rows) {
        for (int iy = y0; iy < y1; ++iy) {
            const float* h = height + static_cast<std::size_t>(iy) * nx;
            const float* h_next = height + static_cast<std::size_t>((iy + 1) % ny) * nx;
            float* row = reinterpret_cast<float*>(rows + static_cast<std::size_t>(iy - y0) * nx);
            for (int ix = 0; ix < nx; ++ix) {
                float s, c;
                fast_sincos(phase_scale * h[ix], s, c);
                row[2 * ix] = c;
                row[2 * ix + 1] = s;
            }
            // Phase steps to the next cell in x (periodic) and y.
            int count = 0;
            for (int ix = 0; ix + 1 < nx; ++ix)
                count += static_cast<int>(std::abs(h[ix + 1] - h[ix]) > limit) |
                         static_cast<int>(std::abs(h_next[ix] - h[ix]) > limit);
            const int last = nx - 1;
            count += static_cast<int>(std::abs(h[0] - h[last]) > limit) |
                     static_cast<int>(std::abs(h_next[last] - h[last]) > limit);
            aliased[static_cast<std::size_t>(iy)] = count;
        }
    });
    std::int64_t total = 0;
    for (std::int64_t c : aliased) total += c;
    return total;
}

void WavePropagator::set_field(const ComplexF* field) {
    spectrum_sums_.reset();
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
    // Uncached, H already sits in W: each batch of rows reads its own rows of H before replacing them.
    const ComplexF* H = cached != nullptr ? cached : W;
    // U H is formed batch by batch of rows just before their inverse transforms (no separate pass over
    // a product array), and |u|^2 is taken from each batch of columns as soon as its transform is done
    // (the field itself is never stored). The total and evanescent energies depend on the spectrum
    // only: summed with the first depth after each new spectrum (per row, then rows in order, so they
    // do not depend on the thread count) and reused for the other depths; only the band-limited energy
    // depends on the depth.
    const bool sum_spectrum = !spectrum_sums_.has_value();
    auto fill = [&](int y0, int y1, ComplexF* rows) {
        for (int iy = y0; iy < y1; ++iy) {
            double sum = 0.0, ev = 0.0, bl = 0.0;
            const std::size_t row = static_cast<std::size_t>(iy) * nx;
            ComplexF* dst = rows + static_cast<std::size_t>(iy - y0) * nx;
            if (sum_spectrum) row_energy(U + row, evanescent_.data() + row, nx, sum, ev);
            for (int ix = 0; ix < nx; ++ix) {
                const std::size_t k = row + ix;
                const float hr = H[k].real(), hi = H[k].imag();
                const float ur = U[k].real(), ui = U[k].imag();
                if (hr == 0.0f && hi == 0.0f && evanescent_[k] == 0) bl += static_cast<double>(std::norm(U[k]));
                dst[ix] = ComplexF(ur * hr - ui * hi, ur * hi + ui * hr);   // no NaN-checking complex multiply
            }
            total[static_cast<std::size_t>(iy)] = sum;
            evanescent[static_cast<std::size_t>(iy)] = ev;
            limited[static_cast<std::size_t>(iy)] = bl;
        }
    };
    auto consume = [&](int x0, int width, const ComplexF* block) {
        for (int t = 0; t < target_count; ++t) {
            const float w = targets[t].weight;
            for (int iy = 0; iy < ny; ++iy) {
                float* out = targets[t].out + static_cast<std::size_t>(iy) * nx + x0;
                const ComplexF* u = block + static_cast<std::size_t>(iy) * width;
                if (targets[t].assign) {
                    for (int i = 0; i < width; ++i) out[i] = w * std::norm(u[i]);
                } else {
                    for (int i = 0; i < width; ++i) out[i] += w * std::norm(u[i]);
                }
            }
        }
    };
    fft_.inverse_fused(W, fill, consume);
    if (sum_spectrum) spectrum_sums_ = SpectrumSums{ordered_sum(total), ordered_sum(evanescent)};
    PropagationStats stats;
    stats.total_energy = spectrum_sums_->total;
    stats.evanescent_energy = spectrum_sums_->evanescent;
    stats.band_limited_energy = ordered_sum(limited);
    if (setup_.propagator == Propagator::Fresnel)
        stats.sampling_ok = fresnel_sampling_ok(depth);
    else
        stats.sampling_ok = stats.band_limited_energy <= 1e-6 * stats.total_energy;
    return stats;
}

}  // namespace caustics::wave_optics
