// The `noise` height-field generator, after Stam, "Periodic Caustic Textures" (papers/004): a random
// fractal surface made by filtering 3-D white noise (x, y, t) with a power law in space and a
// Gaussian-like filter in time. Synthesising it with the FFT makes it periodic in both: the tile repeats
// over the field's rectangle and the animation loops after `period` seconds.
//
// Choices (the article gives only the idea):
//   - White noise: standard normal samples from our own splitmix64 + Box-Muller, so the bits do not
//     depend on the standard library's distributions.
//   - Spatial filter (amplitude): |k|^(-spectral_exponent / 2) for 2 pi / max_wavelength <= |k| <=
//     2 pi / min_wavelength (defaults: the tile size and two grid cells), 0 elsewhere and at k = 0; the
//     Nyquist rows are dropped so that spectral derivatives stay real.
//   - Temporal filter: exp(-m^2 / (2 s^2)) over the temporal frequency index m (cycles per period), with
//     s = max(1, time_samples / 8): slow, smooth motion that still loops.
//   - Heights and gradients (i k H) are inverse transforms of the same spectrum; the whole volume is
//     scaled so the RMS height is `amplitude`.
//   - Frame time t maps to t / period * time_samples slices, linearly interpolated, wrapping.
#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <list>
#include <memory>
#include <mutex>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <caustics/util/fftw_lock.hpp>
#include <caustics/util/rng.hpp>
#include "detail/heightfield_generators.hpp"

namespace caustics::detail {

namespace {

// The synthesised (time_samples x cells_y x cells_x) volume of heights (zero mean, RMS = amplitude) and
// gradients, row-major with x fastest.
struct NoiseVolume {
    int nt = 0, ny = 0, nx = 0;
    std::vector<float> height, grad_x, grad_y;
};

template <class T>
struct FftwDeleter {
    void operator()(T* p) const { fftwf_free(p); }
};


std::shared_ptr<const NoiseVolume> synthesise(const HeightFieldDesc& d) {
    const int nx = d.resolution.x, ny = d.resolution.y, nt = std::max(1, d.time_samples);
    const std::size_t n_real = static_cast<std::size_t>(nt) * ny * nx;
    const int nxc = nx / 2 + 1;
    const std::size_t n_complex = static_cast<std::size_t>(nt) * ny * nxc;

    std::unique_ptr<float, FftwDeleter<float>> real(static_cast<float*>(fftwf_malloc(sizeof(float) * n_real)));
    std::unique_ptr<fftwf_complex, FftwDeleter<fftwf_complex>> spectrum(
        static_cast<fftwf_complex*>(fftwf_malloc(sizeof(fftwf_complex) * n_complex)));
    std::unique_ptr<fftwf_complex, FftwDeleter<fftwf_complex>> work(
        static_cast<fftwf_complex*>(fftwf_malloc(sizeof(fftwf_complex) * n_complex)));
    if (!real || !spectrum || !work) throw std::bad_alloc();

    fftwf_plan forward, inverse;
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        // FFTW_ESTIMATE: no timing-dependent planning, and the arrays are not overwritten while planning.
        forward = fftwf_plan_dft_r2c_3d(nt, ny, nx, real.get(), spectrum.get(), FFTW_ESTIMATE);
        inverse = fftwf_plan_dft_c2r_3d(nt, ny, nx, work.get(), real.get(), FFTW_ESTIMATE);
    }
    if (!forward || !inverse) throw std::runtime_error("noise generator: FFTW could not plan the transform");

    // 3-D white noise.
    SplitMix64 rng{d.seed};
    for (std::size_t k = 0; k < n_real; k += 2) {
        const double r = std::sqrt(-2.0 * std::log(rng.uniform_nonzero()));
        const double a = 2.0 * std::numbers::pi * rng.uniform_nonzero();
        real.get()[k] = static_cast<float>(r * std::cos(a));
        if (k + 1 < n_real) real.get()[k + 1] = static_cast<float>(r * std::sin(a));
    }
    fftwf_execute(forward);

    // Filter: power law in space, Gaussian in time.
    const double two_pi = 2.0 * std::numbers::pi;
    const double lx = d.size.x, ly = d.size.y;
    const double cell = std::max(lx / nx, ly / ny);
    const double k_min = two_pi / (d.max_wavelength > 0.0 ? d.max_wavelength : std::max(lx, ly));
    const double k_max = two_pi / (d.min_wavelength > 0.0 ? d.min_wavelength : 2.0 * cell);
    const double s_t = std::max(1.0, nt / 8.0);
    std::vector<double> kxs(static_cast<std::size_t>(nxc)), kys(static_cast<std::size_t>(ny));
    for (int i = 0; i < nxc; ++i) kxs[static_cast<std::size_t>(i)] = two_pi * i / lx;
    for (int j = 0; j < ny; ++j) kys[static_cast<std::size_t>(j)] = two_pi * (j <= ny / 2 ? j : j - ny) / ly;
    for (int t = 0; t < nt; ++t) {
        const int m = t <= nt / 2 ? t : t - nt;
        const double time_filter = std::exp(-0.5 * (m / s_t) * (m / s_t));
        for (int j = 0; j < ny; ++j) {
            for (int i = 0; i < nxc; ++i) {
                const std::size_t idx = (static_cast<std::size_t>(t) * ny + j) * nxc + i;
                const double kx = kxs[static_cast<std::size_t>(i)], ky = kys[static_cast<std::size_t>(j)];
                const double k = std::sqrt(kx * kx + ky * ky);
                const bool nyquist = (nx % 2 == 0 && i == nx / 2) || (ny % 2 == 0 && j == ny / 2);
                double f = 0.0;
                if (!nyquist && k > 0.0 && k >= k_min * (1.0 - 1e-12) && k <= k_max * (1.0 + 1e-12))
                    f = std::pow(k, -0.5 * d.spectral_exponent) * time_filter;
                spectrum.get()[idx][0] = static_cast<float>(spectrum.get()[idx][0] * f);
                spectrum.get()[idx][1] = static_cast<float>(spectrum.get()[idx][1] * f);
            }
        }
    }

    auto result = std::make_shared<NoiseVolume>();
    result->nt = nt;
    result->ny = ny;
    result->nx = nx;
    // component 0: height (H); 1: d/dx (i kx H); 2: d/dy (i ky H)
    for (int component = 0; component < 3; ++component) {
        for (int t = 0; t < nt; ++t) {
            for (int j = 0; j < ny; ++j) {
                for (int i = 0; i < nxc; ++i) {
                    const std::size_t idx = (static_cast<std::size_t>(t) * ny + j) * nxc + i;
                    const float re = spectrum.get()[idx][0], im = spectrum.get()[idx][1];
                    if (component == 0) {
                        work.get()[idx][0] = re;
                        work.get()[idx][1] = im;
                    } else {
                        const float k = static_cast<float>(component == 1 ? kxs[static_cast<std::size_t>(i)] : kys[static_cast<std::size_t>(j)]);
                        work.get()[idx][0] = -k * im;  // i k (re + i im) = -k im + i k re
                        work.get()[idx][1] = k * re;
                    }
                }
            }
        }
        fftwf_execute(inverse);
        std::vector<float>& out = component == 0 ? result->height : component == 1 ? result->grad_x : result->grad_y;
        out.assign(real.get(), real.get() + n_real);
    }
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        fftwf_destroy_plan(forward);
        fftwf_destroy_plan(inverse);
    }

    double sum2 = 0.0;
    for (float h : result->height) sum2 += static_cast<double>(h) * h;
    const double rms = std::sqrt(sum2 / static_cast<double>(n_real));
    const double scale = rms > 0.0 ? d.amplitude / rms : 0.0;
    for (auto* v : {&result->height, &result->grad_x, &result->grad_y})
        for (float& x : *v) x = static_cast<float>(x * scale);
    return result;
}

std::string cache_key(const HeightFieldDesc& d) {
    std::ostringstream s;
    s.precision(17);
    s << d.resolution.x << ' ' << d.resolution.y << ' ' << d.size.x << ' ' << d.size.y << ' ' << d.amplitude << ' '
      << d.spectral_exponent << ' ' << d.min_wavelength << ' ' << d.max_wavelength << ' ' << d.time_samples << ' '
      << d.seed;
    return s.str();
}

// A few recently used volumes, so consecutive frames of an animation do not resynthesise.
std::shared_ptr<const NoiseVolume> cached_volume(const HeightFieldDesc& d) {
    static std::mutex mutex;
    static std::list<std::pair<std::string, std::shared_ptr<const NoiseVolume>>> cache;
    constexpr std::size_t kCapacity = 3;
    const std::string key = cache_key(d);
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = cache.begin(); it != cache.end(); ++it) {
        if (it->first == key) {
            cache.splice(cache.begin(), cache, it);
            return cache.front().second;
        }
    }
    auto volume = synthesise(d);
    cache.emplace_front(key, volume);
    if (cache.size() > kCapacity) cache.pop_back();
    return volume;
}

}  // namespace

void generate_noise(const HeightFieldDesc& desc, double time, HeightField& hf) {
    const auto volume = cached_volume(desc);
    const NoiseVolume& v = *volume;
    // Slice coordinate, wrapping in time.
    double u = std::fmod(time / desc.period * v.nt, static_cast<double>(v.nt));
    if (u < 0.0) u += v.nt;
    if (!(u < v.nt)) u = 0.0;
    const int t0 = std::min(static_cast<int>(std::floor(u)), v.nt - 1);
    const int t1 = (t0 + 1) % v.nt;
    const float f = static_cast<float>(u - t0);
    const std::size_t slice = static_cast<std::size_t>(v.ny) * v.nx;
    hf.periodic = true;
    const float base = static_cast<float>(desc.base_height);
    for (int j = 0; j < hf.ny; ++j) {
        const int sj = j % v.ny;
        for (int i = 0; i < hf.nx; ++i) {
            const int si = i % v.nx;
            const std::size_t a = static_cast<std::size_t>(t0) * slice + static_cast<std::size_t>(sj) * v.nx + si;
            const std::size_t b = static_cast<std::size_t>(t1) * slice + static_cast<std::size_t>(sj) * v.nx + si;
            const std::size_t k = static_cast<std::size_t>(j) * hf.nx + i;
            hf.height[k] = base + ((1.0f - f) * v.height[a] + f * v.height[b]);
            hf.gradient[k] = glm::vec2((1.0f - f) * v.grad_x[a] + f * v.grad_x[b], (1.0f - f) * v.grad_y[a] + f * v.grad_y[b]);
        }
    }
}

}  // namespace caustics::detail
