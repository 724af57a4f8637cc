#pragma once
// Spectral ramp for dispersion (Stam, "Periodic Caustic Textures": triangles refracted with indices
// between n and n + dispersion, drawn "with colors coming from a nice spectral ramp").
#include <array>
#include <cmath>
#include <vector>

namespace caustics::caustic_triangles {

// CIE 1931 colour matching functions, multi-lobe Gaussian fit of Wyman, Sloan, Shirley, "Simple Analytic
// Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2), 2013, Eq. 2-4.
inline std::array<double, 3> cie_xyz(double nm) {
    auto g = [nm](double mu, double s1, double s2) {
        const double t = (nm - mu) / (nm < mu ? s1 : s2);
        return std::exp(-0.5 * t * t);
    };
    return {1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2),
            0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1),
            1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8)};
}

// Per-sample linear-sRGB weights for `samples` wavelengths: sample k has the index fraction
// f = (k + 1/2) / samples (index ior + f * dispersion) and, as higher indices belong to shorter
// wavelengths, wavelength 700 - 300 f nm. XYZ -> linear sRGB, negative lobes clamped to 0, each channel
// normalised to sum 1 over the samples so that a flat spectrum (no dispersion effect) stays white.
inline std::vector<std::array<float, 3>> spectral_weights(int samples) {
    std::vector<std::array<double, 3>> rgb(static_cast<std::size_t>(samples));
    std::array<double, 3> total{0.0, 0.0, 0.0};
    for (int k = 0; k < samples; ++k) {
        const double f = (k + 0.5) / samples;
        const auto [X, Y, Z] = cie_xyz(700.0 - 300.0 * f);
        const std::array<double, 3> c{3.2406 * X - 1.5372 * Y - 0.4986 * Z, -0.9689 * X + 1.8758 * Y + 0.0415 * Z,
                                      0.0557 * X - 0.2040 * Y + 1.0570 * Z};
        for (int ch = 0; ch < 3; ++ch) {
            rgb[static_cast<std::size_t>(k)][ch] = std::max(0.0, c[ch]);
            total[ch] += rgb[static_cast<std::size_t>(k)][ch];
        }
    }
    std::vector<std::array<float, 3>> w(static_cast<std::size_t>(samples));
    for (int k = 0; k < samples; ++k)
        for (int ch = 0; ch < 3; ++ch)   // a channel no sample reaches (few samples) falls back to grey
            w[static_cast<std::size_t>(k)][ch] = static_cast<float>(
                total[ch] > 0.0 ? rgb[static_cast<std::size_t>(k)][ch] / total[ch] : 1.0 / samples);
    return w;
}

}  // namespace caustics::caustic_triangles
