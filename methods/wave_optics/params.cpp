// wave_optics' description and parameter table (params.hpp).
#include "params.hpp"

#include <sstream>

#include <caustics/blocks/fft/fft.hpp>

namespace caustics::wave_optics {

const char* const kDoc =
    "Stam 1996 wave optics: the refracted wave on the water's mean plane (screen=refracted, the default: "
    "exact Snell refraction, intercepted flux and lateral offset of each surface sample, "
    "refracted_screen.hpp; screen=thin: Stam's phase screen phi = k0 (n cos t_t - cos t_i) h) on a "
    "grid x grid FFT grid over one period of the surface; the wave propagates to the receiver depth by "
    "a Fourier-domain transfer function (angular spectrum, band-limited after Matsushima & Shimobaba "
    "2009 so the sampled filter is not aliased, or the paraxial Fresnel filter) and its intensity, times "
    "the transmitted irradiance, is E_c (radiometric: mean intensity = E0 cos t_i T exp(-Ka path) by "
    "Parseval). Needs one directional light and one height-field dielectric surface, and no other "
    "specular object. grid must be a product of 2, 3, 5, 7 (FFTW's fast sizes; other sizes are refused "
    "with the nearest valid ones). iterations has no meaning here: its only valid value is 1. "
    "wavelength is the wavelength in the water; 0 = auto: per frame, the shortest of 2 dx 2^(-k/4) "
    "(k = 0..16) at which the refracted field is sampled at 1.5 x its Nyquist rate (from the largest "
    "deviation of the refracted rays; health wavelength_um), so that the diffraction blur is as small as "
    "the grid allows; two grid spacings is Stam's (after Moravec); shorter than 1/8 of a grid spacing is "
    "refused. wavelengths > 1 averages that many wavelengths over [lambda, 2 lambda] "
    "(reduces spurious diffraction; with material dispersion the index spans ior + dispersion (shortest) "
    "to ior (longest)) and fills receiver_rgb. Oblique light: the exact carrier (Floquet: only the field "
    "relative to it is periodic). Claims accuracy (accuracy_claim) before the first focus where the "
    "diffraction blur is small against the caustic's features (regime.hpp; health past_first_focus = "
    "points deeper than the first focus, the paraxial or the traced one, whichever is shallower; "
    "diffraction_eps_pct = 100 eps at the deepest point, -1 past the focus). "
    "Non-periodic surfaces (edges that do not match) sit in a larger FFT window whose border, 1/16 of the "
    "surface's shorter side on every side and outside the surface, falls to the edge mean (health "
    "nonperiodic_surface = 1, tapered_lookups = receiver points lit within the reach of the border's "
    "light). depth_slices > 1 tabulates the intensity at that many depths between the shallowest and "
    "deepest receiver point and looks it up trilinearly (Stam); with 1 slice every point uses the mid "
    "depth (health depth_mismatch counts points more than 1 um off it). Health: sampling_violations "
    "(propagations whose sampling criterion failed: Fresnel z > L^2 / (lambda N); angular spectrum: the "
    "band limit removed more than 1 ppm of the energy), band_limited_ppm, evanescent_ppm, "
    "phase_aliased_cells (phase step > pi between neighbouring grid cells), screen_folded_cells and "
    "unlit_cells (surface samples whose refracted map folds or that face away from the light), not_covered (points above "
    "the water or lit from outside the surface's footprint). Transfer functions are cached per depth "
    "and wavelength; walls shadowing the light are ignored. Periodic textures (caustics synth): the intensity "
    "at the texture depth over the FFT period, periodic by construction, resampled bilinearly to the texels.";

std::vector<ParamSpec> param_table() {
    std::vector<ParamSpec> p;
    p.push_back({"grid", ParamType::Int, "512", 16, 4096, {},
                 "FFT size (grid x grid) the surface period is resampled to; a product of 2, 3, 5, 7",
                 {"256", "512"}});
    p.push_back({"iterations", ParamType::Int, "1", 1, 1, {}, "no meaning for this method: only 1 is valid"});
    p.push_back({"wavelength", ParamType::Float, "0", 0.0, 1e3, {},
                 "wavelength in the water [m]; 0 = auto (the shortest the grid samples for the surface's slopes, "
                 "at most two grid spacings, Stam's choice); at least 1/8 grid spacing"});
    p.push_back({"propagator", ParamType::Enum, "angular_spectrum", 0, 0, {"angular_spectrum", "fresnel"},
                 "transfer function: band-limited angular spectrum, or paraxial Fresnel (unitary)"});
    p.push_back({"wavelengths", ParamType::Int, "1", 1, 16, {},
                 "wavelengths averaged over [lambda, 2 lambda] (colour with dispersion; receiver_rgb when > 1)"});
    p.push_back({"blur", ParamType::Float, "0", 0.0, 1e3, {},
                 "Gaussian blur of the intensity, standard deviation [m] on the receiver (0 = none)"});
    p.push_back({"screen", ParamType::Enum, "refracted", 0, 0, {"refracted", "thin"},
                 "input field: refracted (exact Snell per surface sample, flux and offset to the mean plane) "
                 "or thin (Stam's phase screen k0 (n cos t_t - cos t_i) h, unit amplitude)"});
    p.push_back({"depth_slices", ParamType::Int, "1", 1, 64, {},
                 "intensity slices between the shallowest and deepest receiver point, looked up trilinearly"});
    return p;
}

std::string fast_size_hint(long long grid) {
    const int g = static_cast<int>(grid);
    int below = g;
    while (below > 1 && !is_fast_fft_size(below)) --below;
    const int above = next_fast_fft_size(g);
    std::ostringstream s;
    s << grid << " is not a product of 2, 3, 5 and 7 (FFTW plans such sizes slowly); nearest valid sizes: "
      << below << " and " << above << " (e.g. 256, 384, 500, 512, 640, 720, 768, 1000, 1024, 2048)";
    return s.str();
}

}  // namespace caustics::wave_optics
