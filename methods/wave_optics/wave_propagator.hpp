#pragma once
// The grid-level engine of the wave_optics method (Stam 1996, "Random Caustics"): a periodic scalar field
// u(x, y) on an nx x ny grid over one period lx x ly, transformed once (FFTW) and propagated to any depth
// by a Fourier-domain transfer function, giving the intensity |u|^2 there. The method (wave_optics.cpp)
// builds the phase screen from the water surface and looks the intensities up on the receiver; tests use
// this class directly.
//
// The field may ride on a carrier (oblique light): u_total = exp(2 pi i fc . x) u, fc = carrier_bins / L,
// any real bins: only u need be periodic (Floquet), so the carrier need not lie on the grid's frequency
// lattice and the light keeps its exact direction. Only u is stored; its spectrum bin f is propagated with the transfer
// function of the total frequency f + fc, relative to the carrier itself, and with the carrier's lateral
// walk removed ("shifted" propagation):
//   I_z(x) here  =  |u_total(x + z w_c, z)|^2,   w_c = carrier walk per unit depth (carrier_walk()).
// The caller shifts its lookups by z w_c. This keeps the pattern centred in the periodic window, and the
// band limit below measures walks relative to the carrier (Matsushima 2010, shifted angular spectrum).
//
// Propagators (lambda = wavelength in the medium, kz(f) = sqrt(1/lambda^2 - |f|^2)):
//   angular_spectrum  H = exp(2 pi i z (kz(f + fc) - kz(fc))) exp(2 pi i z f . w_c), zero where
//                     |f + fc| >= 1/lambda (evanescent) or where the band limit removes it: the transfer
//                     function is sampled at df = 1/L, so its phase may advance at most half a cycle per
//                     sample, i.e. the component's lateral walk relative to the carrier must stay within
//                     half a period: z |r(f + fc) - r(fc)| <= L/2 per axis, r(f) = f / kz(f) (Matsushima &
//                     Shimobaba 2009, Eqs. 11-13, evaluated per bin instead of through their fy = 0 bound).
//   fresnel           H = exp(-i pi lambda z (|f + fc|^2 - |fc|^2)) exp(2 pi i z f . w_c) (paraxial; its own
//                     walk is w_c = lambda fc, giving exp(-i pi lambda z |f|^2)). Unitary. Its sampling
//                     criterion is z <= L^2 / (lambda N) per axis (Voelz & Roggemann 2009).
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/blocks/fft/fft.hpp>

namespace caustics::wave_optics {

enum class Propagator { AngularSpectrum, Fresnel };

struct WaveSetup {
    int nx = 0, ny = 0;               // grid
    double lx = 1.0, ly = 1.0;        // period [m]
    double wavelength = 0.0;          // in the medium [m]
    Propagator propagator = Propagator::AngularSpectrum;
    glm::dvec2 carrier_bins{0.0, 0.0};  // carrier frequency fc = (bx / lx, by / ly), fractional allowed
    // The lateral walk per unit depth removed from the propagated field (the caller shifts its lookups
    // by depth * walk). Default: the carrier's own walk. The method passes the true refracted beam's
    // tan(theta_t) so that every wavelength and both propagators share one lookup frame.
    std::optional<glm::dvec2> shift_walk;
};

struct PropagationStats {
    double total_energy = 0.0;          // sum of |U|^2 over the spectrum (Parseval: N^2 * mean |u|^2 ... scaled)
    double evanescent_energy = 0.0;     // removed: |f + fc| >= 1/lambda
    double band_limited_energy = 0.0;   // removed by the band limit
    bool sampling_ok = true;            // the propagator's sampling criterion held
    double lost_fraction() const {
        return total_energy > 0.0 ? (evanescent_energy + band_limited_energy) / total_energy : 0.0;
    }
};

// Accumulation target of propagate(): out[i] += weight * I[i].
struct IntensityTarget {
    float* out = nullptr;
    float weight = 1.0f;
    bool assign = false;   // out[i] = weight * I[i] instead of +=
};

class WavePropagator {
public:
    explicit WavePropagator(const WaveSetup& setup, FftRigor rigor = FftRigor::Measure);

    const WaveSetup& setup() const { return setup_; }
    // Lateral walk per unit depth removed from the field (shift_walk, or the carrier's own walk):
    // dimensionless, tan of the angle per axis.
    glm::dvec2 carrier_walk() const { return walk_; }
    // The carrier's propagation direction in the medium (unit, z < 0 downwards).
    glm::dvec3 carrier_direction() const;

    // u = exp(i * phase_scale * height[k]) (height: nx * ny, row-major), then its spectrum.
    // Returns the number of grid cells whose phase step to the next cell in x or y exceeds pi (the phase
    // screen is under-resolved there).
    std::int64_t set_phase_screen(const float* height, float phase_scale);
    // Arbitrary field (tests), then its spectrum.
    void set_field(const ComplexF* field);
    const ComplexBuffer& spectrum() const { return spectrum_; }

    // Propagates the current field to `depth` >= 0 and accumulates weight * |u|^2 into each target
    // (nx * ny floats; intensity 1 = the incident plane wave's, before any loss).
    PropagationStats propagate(double depth, const IntensityTarget* targets, int target_count);

    // Whether the Fresnel criterion holds at this depth (angular spectrum: see propagate()'s stats).
    bool fresnel_sampling_ok(double depth) const;
    // Band-limit test of one spectrum bin (ix, iy) at `depth`, angular spectrum: 0 keep, 1 evanescent,
    // 2 band-limited. Exposed for tests that recompute the removed energy independently.
    int as_bin_class(int ix, int iy, double depth) const;
    // Signed frequency index of bin k for an n-point transform.
    static int signed_index(int k, int n) { return k <= (n - 1) / 2 ? k : k - n; }

private:
    WaveSetup setup_;
    Fft2D fft_;
    ComplexBuffer spectrum_;
    ComplexBuffer work_;
    glm::dvec2 walk_{0.0};
    // Per bin: phase per unit depth (radians / m) and band-limit rate q (keep when depth * q <= 1;
    // negative for evanescent bins, 0 for the Fresnel propagator).
    std::vector<double> rate_;
    std::vector<double> limit_;
    std::vector<std::uint8_t> evanescent_;   // 1 where limit_ < 0 (a compact copy for the per-depth pass)
    // Energy of the current spectrum, total and evanescent (depth-independent); reset with each new field.
    struct SpectrumSums {
        double total = 0.0, evanescent = 0.0;
    };
    std::optional<SpectrumSums> spectrum_sums_;
    // Transfer functions of recent depths (normalised by 1 / (nx ny)), so that repeated frames at the
    // same receiver depths only multiply: at most kCacheBytes per propagator, else computed per call.
    // Keeping them across frames is exact: H depends only on the setup (fixed for the propagator's
    // life; a parameter change builds a new propagator) and the depth (the key), never on the surface.
    static constexpr std::size_t kCacheBytes = std::size_t(256) << 20;
    std::vector<std::pair<double, ComplexBuffer>> cache_;
    const ComplexF* transfer(double depth);
    void fill_transfer(double depth, ComplexF* H) const;
};

}  // namespace caustics::wave_optics
