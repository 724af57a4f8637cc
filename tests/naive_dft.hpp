#pragma once
// A plain double-precision 2-D DFT, O(n^3): the independent check of the FFT wrapper and of the wave
// propagators' spectra in the tests.
#include <complex>
#include <cstddef>
#include <numbers>
#include <vector>

namespace caustics::test_support {

// Separable: rows, then columns. sign -1 is the forward transform; +1 the inverse without 1/n.
inline std::vector<std::complex<double>> naive_dft(const std::vector<std::complex<double>>& a, int nx, int ny, int sign) {
    std::vector<std::complex<double>> rows(a.size()), out(a.size());
    for (int y = 0; y < ny; ++y)
        for (int k = 0; k < nx; ++k) {
            std::complex<double> s = 0.0;
            for (int x = 0; x < nx; ++x)
                s += a[static_cast<std::size_t>(y) * nx + x] * std::polar(1.0, sign * 2.0 * std::numbers::pi * k * x / nx);
            rows[static_cast<std::size_t>(y) * nx + k] = s;
        }
    for (int x = 0; x < nx; ++x)
        for (int k = 0; k < ny; ++k) {
            std::complex<double> s = 0.0;
            for (int y = 0; y < ny; ++y)
                s += rows[static_cast<std::size_t>(y) * nx + x] * std::polar(1.0, sign * 2.0 * std::numbers::pi * k * y / ny);
            out[static_cast<std::size_t>(k) * nx + x] = s;
        }
    return out;
}

}  // namespace caustics::test_support
