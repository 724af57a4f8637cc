// wave_optics: caustics as the intensity of a wave (Stam 1996, "Random Caustics: Natural Textures and
// Wave Theory Revisited"; Moravec 1981). A plane wave crosses the water surface, which delays its phase
// by the optical path difference (phi = k0 (n cos theta_t - cos theta_i) h, = k0 (n - 1) h at normal
// incidence), then propagates freely through the water to the receiver as a multiplication by a filter
// in the Fourier domain. The intensity |u|^2, scaled by the transmitted irradiance, is the caustic
// irradiance. See wave_propagator.hpp for the propagators and their band limit.
#include <algorithm>
#include <cstring>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/util/errors.hpp>
#include <caustics/blocks/fft/fft.hpp>
#include <caustics/blocks/regime/first_focus.hpp>
#include "refracted_screen.hpp"
#include "regime.hpp"
#include <caustics/api/registry.hpp>
#include <caustics/util/timing.hpp>
#include "params.hpp"
#include "wave_field_table.hpp"
#include "wave_math.hpp"
#include "wave_propagator.hpp"

namespace caustics::wave_optics {

namespace {

// One wavelength sample of the band.
struct Spectral {
    double lambda = 0.0;        // in the water [m]
    double n = 1.33;            // index of refraction
    double phase_per_m = 0.0;   // phase screen: radians per metre of height
    glm::dvec3 refracted{0.0, 0.0, -1.0};   // true refracted direction (mean surface)
    float rgb[3] = {0, 0, 0};   // channel weights (each channel's weights sum to 1 over the samples)
    std::unique_ptr<WavePropagator> propagator;
};

class WaveOpticsMethod final : public Method {
public:
    explicit WaveOpticsMethod(const ParamSet& p)
        : grid_(static_cast<int>(p.get_int("grid"))), wavelength_(p.get_float("wavelength")),
          fresnel_(p.get_enum("propagator") == "fresnel"),
          samples_(static_cast<int>(p.get_int("wavelengths"))), blur_(p.get_float("blur")),
          slices_(static_cast<int>(p.get_int("depth_slices"))), thin_screen_(p.get_enum("screen") == "thin") {
        if (!is_fast_fft_size(grid_)) throw InputError(kName, "grid", fast_size_hint(grid_));
    }

    Capability capabilities(const Scene& scene) const override {
        std::string why;
        if (!find_setup(scene, why)) return Capability::no(why);
        return Capability::yes();
    }
    // Periodic textures: the FFT field over the surface period is periodic by construction.
    Capability texture_capability(const Scene& scene) const override { return capabilities(scene); }

    void prepare(const Scene& scene) override {
        std::string why;
        if (!find_setup(scene, why)) throw InputError(scene.path, "objects", "wave_optics: " + why);
        const Object& water = scene.objects[static_cast<std::size_t>(water_index_)];
        const HeightFieldDesc& d = water.heightfield;
        // The FFT grid spans the surface rectangle (one period of the tiling), and a border around it
        // where the surface does not tile (FftWindow, chosen per frame); the frame's HeightField has the
        // same rectangle (size = resolution cells).
        surface_lx_ = lx_ = d.size.x;
        surface_ly_ = ly_ = d.size.y;
        spacing_ = std::max(lx_, ly_) / grid_;
        const double floor = 2.0 * spacing_ / std::ldexp(1.0, kMaxHalvings);
        if (wavelength_ > 0.0 && wavelength_ < floor * (1.0 - 1e-9)) {
            std::ostringstream s;
            s << "wavelength " << wavelength_ << " m is below 1/" << (1 << (kMaxHalvings - 1)) << " of a grid spacing ("
              << floor << " m for grid " << grid_ << " over " << lx_ << " x " << ly_
              << " m): use 0 (auto, from the surface's slopes) or a length >= " << floor << " m, or a larger grid";
            throw InputError(kName, "wavelength", s.str());
        }
        const Light& light = scene.lights.front();
        const glm::dvec3 dir = glm::normalize(light.direction);
        cos_i_ = -dir.z;
        irradiance_ = light.irradiance;
        absorption_ = water.material.absorption;
        // Mean-index refracted direction: the lookup frame (every sample's propagator removes this
        // walk), the irradiance projection and the absorption path.
        const double n_mid = water.material.ior + 0.5 * (samples_ > 1 ? water.material.dispersion : 0.0);
        const glm::dvec2 s_mid = glm::dvec2(dir.x, dir.y) / n_mid;
        refracted_ = glm::dvec3(s_mid.x, s_mid.y, -std::sqrt(std::max(0.0, 1.0 - glm::dot(s_mid, s_mid))));
        light_ = dir;
        ior_ = water.material.ior;
        dispersion_ = samples_ > 1 ? water.material.dispersion : 0.0;
        // Provisional: the automatic wavelength is chosen per frame from the surface (render()).
        build_spectral(wavelength_ > 0.0 ? wavelength_ : 2.0 * spacing_);
        transmittance_ = scene.fresnel ? fresnel_transmittance(cos_i_, n_mid) : 1.0;
        scene_fresnel_ = scene.fresnel;
        stats_of_ = nullptr;
        screens_.clear();
        screens_used_ = 0;
        table_ = std::make_unique<WaveFieldTable>(grid_, grid_, samples_ > 1);
    }

    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override;

    void update(const FrameGeometry& frame) override {
        const HeightField& hf = *frame.objects.at(static_cast<std::size_t>(water_index_)).heightfield;
        window_ = fft_window(hf, surface_lx_, surface_ly_);
        stats_ = frame_stats(hf, window_, table_.get());
        exact_focus_ = caustics::regime::analyze_focus(hf, light_, ior_, mean_level(hf)).first_focus_depth;
        use_window(window_);
        stats_of_ = &hf;
        stats_version_ = hf_version(hf);
    }

    // Inside the geometric-optics regime (regime.hpp) at the deepest receiver point: the error factor
    // measured on the sine cases with margin (README.md); outside: the bound with its numbers.
    AccuracyClaim accuracy_claim(const FrameGeometry& frame) const override {
        const HeightField& hf = *frame.objects.at(static_cast<std::size_t>(water_index_)).heightfield;
        const ReceiverChart chart(frame, 2, 2);
        double depth = 0.0;
        const double level = mean_level(hf);
        // Light entering outside the surface (a non-tiling surface's border, FftWindow) is not the scene's.
        // Entry points of the light reaching a 9 x 9 net of the receiver: the flat surface's beam, less the
        // reach of the rays the slopes (the surface's and the border's) bend (reach_per_m).
        const FftWindow window = window_for(hf);
        const double spacing = window.spacing(grid_);
        const glm::dvec2 beam_walk = glm::dvec2(refracted_.x, refracted_.y) / std::max(1e-9, -refracted_.z);
        const SurfaceStats stats = stats_for(hf);
        const double reach = reach_per_m(stats);
        double margin = 1e300;
        for (int j = 0; j <= 8; ++j)
            for (int i = 0; i <= 8; ++i) {
                const glm::dvec3 p = chart.point(i / 8.0, j / 8.0);
                const double z = level - p.z;
                depth = std::max(depth, z);
                const glm::dvec2 rel = glm::dvec2(p) - z * beam_walk - glm::dvec2(hf.origin);
                margin = std::min(margin, std::min({rel.x, rel.y, surface_lx_ - rel.x, surface_ly_ - rel.y}) -
                                              std::max(z, 0.0) * reach);
            }
        const caustics::regime::WaterRegime w = caustics::regime::water_regime(frame);
        const Regime r = regime(stats, depth, window, w.focus.first_focus_depth);
        const double lambda = wavelength_for(stats, spacing);
        const double sampling = sampling_margin(lambda, spacing, stats.deviation);
        std::vector<RegimeBound> bounds = {{"border_margin_m", margin, 0.0, false},
                                           {"depth_over_first_focus", w.depth_over_first_focus(), kMaxFocusFraction, true},
                                           {"diffraction_epsilon", r.epsilon, kMaxEpsilon, true},
                                           {"spread_half_periods", r.spread, 1.0, true},
                                           {"depth_over_feature_length", w.feature_length > 0.0 ? w.depth / w.feature_length : 0.0,
                                            kMaxDepthOverFeature, true},
                                           {"sampling_margin", sampling, kSamplingMargin, false}};
        if (!bounds[0].holds()) {
            std::ostringstream s;
            s.precision(3);
            s << "wave_optics: light reaching the receiver may enter outside the surface (the closest entry, less the "
                 "reach of the rays the slopes bend, lies "
              << margin << " m from its edge";
            if (!window.periodic)
                s << "; the surface does not tile: the FFT window's border of " << window.pad
                  << " m stands in for what lies beyond it";
            s << ")";
            return AccuracyClaim::outside(s.str(), bounds);
        }
        if (!bounds[5].holds()) {
            std::ostringstream s;
            s.precision(3);
            s << "wave_optics: the refracted field's phase steps up to " << 1.0 / std::max(sampling, 1e-9)
              << " x pi per grid cell (rays deviate up to " << stats.deviation << " from the flat surface's at wavelength "
              << lambda << " m, spacing " << spacing << " m): it is sampled at " << sampling
              << " x its Nyquist rate, below " << kSamplingMargin << " (a longer wavelength or a larger grid)";
            return AccuracyClaim::outside(s.str(), bounds);
        }
        if (!bounds[1].holds()) {
            std::ostringstream s;
            s.precision(3);
            s << "wave_optics: the receiver lies " << w.depth << " m below the water, " << bounds[1].value
              << " of the way to the first focus at " << w.focus.first_focus_depth << " m, beyond " << kMaxFocusFraction
              << ": near and past the focus the coherent wave's fringes and fold diffraction converge to the "
                 "geometric irradiance only weakly as the wavelength shrinks (averaged over a receiver bin, blur = "
                 "bin / sqrt(12), the error falls as the wavelength: sine_deep 0.91, 0.50, 0.24, 0.12 at grids 512 "
                 "to 4096; drawn cases past the focus 0.16-0.64 at grid 2048; a grid of 8192 or more would be "
                 "needed for 0.10)";
            return AccuracyClaim::outside(s.str(), bounds);
        }
        if (!bounds[4].holds()) {
            std::ostringstream s;
            s.precision(3);
            s << "wave_optics: the receiver lies " << w.depth << " m below the water, " << bounds[4].value
              << " x the surface's feature length " << w.feature_length << " m, beyond " << kMaxDepthOverFeature
              << ": the diffraction of the band-limited wave blurs short features deep down";
            return AccuracyClaim::outside(s.str(), bounds);
        }
        const std::string why = regime_violation(r);
        return why.empty() ? AccuracyClaim::within(kClaimError, bounds) : AccuracyClaim::outside("wave_optics: " + why, bounds);
    }

private:
    static double mean_level(const HeightField& hf) {
        double sum = 0.0;
        for (float z : hf.height) sum += z;
        return hf.height.empty() ? 0.0 : sum / static_cast<double>(hf.height.size());
    }
    // The regime at `depth` below the mean level, for the longest wavelength propagated.
    // From the height field's vertices (the claim and the health agree; the FFT grid's bilinear
    // resampling would add kinks to the curvature).
    // The surface's part is computed by update() (it depends on the frame's geometry only, like an
    // acceleration structure) and kept for the frame's renders and claim; computed here otherwise.
    // exact_focus: blocks/regime's first focus below the mean level (estimate_regime).
    Regime regime(const SurfaceStats& stats, double depth, const FftWindow& window, double exact_focus) const {
        return estimate_regime(stats, light_, n_mid(),
                               wavelength_for(stats, window.spacing(grid_)) * (samples_ > 1 ? 2.0 : 1.0), depth,
                               std::min(window.lx, window.ly), exact_focus);
    }
    double n_mid() const { return ior_ + 0.5 * dispersion_; }
    bool updated_for(const HeightField& hf) const { return stats_of_ == &hf && stats_version_ == hf_version(hf); }
    FftWindow window_for(const HeightField& hf) const {
        return updated_for(hf) ? window_ : fft_window(hf, surface_lx_, surface_ly_);
    }
    SurfaceStats stats_for(const HeightField& hf) const {
        return updated_for(hf) ? stats_ : frame_stats(hf, window_for(hf), nullptr);
    }
    // The surface's statistics from its vertices; with a border (a non-tiling surface), the deviation is
    // the larger of the surface's and that of the whole window as the FFT grid samples it: the border's
    // slopes must be sampled too, and their light's reach kept off the receiver. `table` resamples the
    // window (update() passes the method's own; the const claim path, null, a scratch one).
    SurfaceStats frame_stats(const HeightField& hf, const FftWindow& window, WaveFieldTable* table) const {
        SurfaceStats stats = surface_stats(hf, light_, n_mid());
        if (window.pad > 0.0) {
            std::unique_ptr<WaveFieldTable> scratch;
            if (table == nullptr) table = (scratch = std::make_unique<WaveFieldTable>(grid_, grid_, false)).get();
            const SurfaceSamples& s = table->resample(hf, window, surface_lx_, surface_ly_);
            const SurfaceStats grid = surface_stats(s.height.data(), grid_, grid_, window.lx / grid_, window.ly / grid_,
                                                    true, light_, n_mid());
            stats.deviation = std::max(stats.deviation, grid.deviation);
        }
        return stats;
    }
    // How far sideways the rays the slopes bend reach, per metre of depth: z |t_xy - t0_xy| / cos^3(t_t),
    // first order in the deviation, widened by its second-order factor 1 + deviation.
    double reach_per_m(const SurfaceStats& stats) const {
        return stats.deviation * (1.0 + stats.deviation) / std::pow(std::max(1e-3, -refracted_.z), 3);
    }
    // The shortest wavelength propagated for a surface with these statistics: the set one, or the
    // automatic choice from the refracted field's largest spatial frequency (regime.hpp).
    double wavelength_for(const SurfaceStats& stats, double spacing) const {
        return wavelength_ > 0.0 ? wavelength_ : auto_wavelength(spacing, stats.deviation);
    }
    // The propagators' FFT window: a new size changes the grid spacing, so they are rebuilt.
    void use_window(const FftWindow& window) {
        if (window.lx == lx_ && window.ly == ly_) return;
        lx_ = window.lx;
        ly_ = window.ly;
        spacing_ = window.spacing(grid_);
        lambda_ = -1.0;
    }
    // Identifies the heights a HeightField holds now (its buffer and size, and a few samples), so that a
    // surface changed in place between update() and render() is not read from stale statistics.
    static std::size_t hf_version(const HeightField& hf) {
        std::size_t v = reinterpret_cast<std::uintptr_t>(hf.height.data()) ^ (hf.height.size() << 1);
        for (std::size_t k = 0; k < hf.height.size(); k += 1 + hf.height.size() / 64) {
            std::uint32_t bits;
            std::memcpy(&bits, &hf.height[k], sizeof bits);
            v = v * 1000003u ^ bits;
        }
        return v;
    }
    const HeightField* stats_of_ = nullptr;
    std::size_t stats_version_ = 0;
    SurfaceStats stats_;
    FftWindow window_;             // the FFT window of the frame update() saw
    double exact_focus_ = 1e300;   // blocks/regime's first focus of that frame
    bool find_setup(const Scene& scene, std::string& why) const;
    void build_spectral(double lambda);
    void fill_table(const SurfaceSamples& surface, const std::vector<double>& depths, CausticOutput& out);
    LookupGeometry lookup_geometry(const HeightField& hf, const SurfaceSamples& surface,
                                   const std::vector<double>& depths) const;
    int grid_;
    double wavelength_;
    bool fresnel_;
    int samples_;
    double blur_;
    int slices_;
    bool thin_screen_;
    mutable int water_index_ = -1;
    double surface_lx_ = 1.0, surface_ly_ = 1.0;   // the surface's rectangle
    double lx_ = 1.0, ly_ = 1.0;                   // the window the propagators were built for (use_window)
    double lambda_ = 0.0, spacing_ = 1.0, ior_ = 1.33, dispersion_ = 0.0;
    double cos_i_ = 1.0, irradiance_ = 1.0, absorption_ = 0.0, transmittance_ = 1.0;
    bool scene_fresnel_ = false;
    glm::dvec3 light_{0.0, 0.0, -1.0};
    // Refracted screens of the current frame, one per distinct index (samples share them without
    // dispersion; the first screens_used_ are current, the buffers are kept between frames), and the
    // field buffer handed to the propagators.
    std::vector<std::pair<double, RefractedScreen>> screens_;
    std::size_t screens_used_ = 0;
    std::vector<ComplexF> field_;
    const RefractedScreen& screen_for(const SurfaceSamples& surface, double n, CausticOutput& out);
    glm::dvec3 refracted_{0.0, 0.0, -1.0};
    std::vector<Spectral> spectral_;
    std::unique_ptr<WaveFieldTable> table_;
    std::vector<ShadePoint> points_;   // per-frame scratch of render()
    std::vector<glm::vec4> values_;
};

bool WaveOpticsMethod::find_setup(const Scene& scene, std::string& why) const {
    if (scene.lights.size() != 1 || scene.lights.front().type != LightType::Directional) {
        why = "needs exactly one directional light (a plane wave)";
        return false;
    }
    if (!(glm::normalize(scene.lights.front().direction).z < -1e-6)) {
        why = "the directional light must shine downwards onto the water surface";
        return false;
    }
    int water = -1;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const Object& o = scene.objects[i];
        if (!o.material.is_specular()) continue;
        if (o.shape == ShapeType::HeightField && o.material.type == MaterialType::Dielectric && water < 0) {
            water = static_cast<int>(i);
            continue;
        }
        why = "models one height-field water surface; '" + o.name + "' is another specular object";
        return false;
    }
    if (water < 0) {
        why = "needs a height-field dielectric (water) surface";
        return false;
    }
    if (scene.receiver.object_index == water) {
        why = "the receiver is the water surface itself";
        return false;
    }
    water_index_ = water;
    return true;
}

// Step 4 of render(): per wavelength, phase screen and forward transform, then one inverse transform per
// depth slice into the table (then the optional blur). Adds stage timings and health to `out`.
void WaveOpticsMethod::fill_table(const SurfaceSamples& surface, const std::vector<double>& depths, CausticOutput& out) {
    Stopwatch watch;
    auto lap = [&watch] {
        const double t = watch.ms();
        watch.reset();
        return t;
    };
    table_->begin(static_cast<int>(depths.size()));
    double phase_ms = 0.0, propagate_ms = 0.0;
    std::int64_t violations = 0, aliased = 0;
    double band_ppm = 0.0, evan_ppm = 0.0;
    screens_used_ = 0;
    if (!depths.empty()) {
        for (std::size_t m = 0; m < spectral_.size(); ++m) {
            Spectral& sp = spectral_[m];
            if (thin_screen_) {
                aliased += sp.propagator->set_phase_screen(surface.height.data(), static_cast<float>(sp.phase_per_m));
            } else {
                const RefractedScreen& screen = screen_for(surface, sp.n, out);
                aliased += screen_field(screen, grid_, 2.0 * std::numbers::pi / (sp.n * sp.lambda), field_);
                sp.propagator->set_field(field_.data());
            }
            phase_ms += lap();
            for (std::size_t s = 0; s < depths.size(); ++s) {
                IntensityTarget targets[4];
                const int count = table_->targets(static_cast<int>(s), static_cast<int>(m), 1.0f / samples_, sp.rgb, targets);
                const PropagationStats st = sp.propagator->propagate(depths[s], targets, count);
                if (!st.sampling_ok) ++violations;
                if (st.total_energy > 0.0) {
                    band_ppm = std::max(band_ppm, 1e6 * st.band_limited_energy / st.total_energy);
                    evan_ppm = std::max(evan_ppm, 1e6 * st.evanescent_energy / st.total_energy);
                }
            }
            propagate_ms += lap();
        }
    }
    out.stages_ms.emplace_back("phase_fft", phase_ms);
    out.stages_ms.emplace_back("propagate", propagate_ms);
    out.health.add("sampling_violations", violations);
    out.health.add("phase_aliased_cells", aliased);
    out.health.add("band_limited_ppm", std::llround(band_ppm));
    out.health.add("evanescent_ppm", std::llround(evan_ppm));
    if (blur_ > 0.0) table_->blur(blur_, lx_, ly_);
    out.stages_ms.emplace_back("blur", lap());
}

// The refracted screen for index n (built once per frame and index).
const RefractedScreen& WaveOpticsMethod::screen_for(const SurfaceSamples& surface, double n, CausticOutput& out) {
    for (std::size_t k = 0; k < screens_used_; ++k)
        if (screens_[k].first == n) return screens_[k].second;
    RefractionSetup rs;
    rs.nx = rs.ny = grid_;
    rs.lx = lx_;
    rs.ly = ly_;
    rs.light = light_;
    rs.ior = n;
    rs.fresnel = scene_fresnel_;
    rs.absorption = absorption_;
    if (screens_used_ == screens_.size()) screens_.emplace_back();
    screens_[screens_used_].first = n;
    RefractedScreen& screen = screens_[screens_used_++].second;
    build_refracted_screen(surface.height.data(), rs, screen);
    out.health.add("screen_folded_cells", screen.folded_cells);
    out.health.add("unlit_cells", screen.unlit_cells);
    return screen;
}

// The propagators for the wavelength samples over [lambda, 2 lambda] (prepare(), and render() when the
// automatic wavelength changes with the surface).
void WaveOpticsMethod::build_spectral(double lambda) {
    lambda_ = lambda;
    const glm::dvec3 dir = light_;
    const glm::dvec2 beam_walk = glm::dvec2(refracted_.x, refracted_.y) / (-refracted_.z);
    // Wavelength samples over [lambda, 2 lambda]; blue (short) gets the highest index.
    spectral_.clear();
    spectral_.resize(static_cast<std::size_t>(samples_));
    const double n_lo = ior_, dn = dispersion_;
    double rgb_sum[3] = {0, 0, 0};
    for (int m = 0; m < samples_; ++m) {
        Spectral& sp = spectral_[static_cast<std::size_t>(m)];
        const double t = samples_ > 1 ? static_cast<double>(m) / (samples_ - 1) : 0.0;
        sp.lambda = lambda * (1.0 + t);
        sp.n = n_lo + dn * (1.0 - t);
        const double tc[3] = {1.0, 0.5, 0.0};   // R, G, B centres on the band
        for (int c = 0; c < 3; ++c) {
            sp.rgb[c] = samples_ > 1 ? static_cast<float>(std::max(0.0, 1.0 - std::abs(t - tc[c]) / 0.5)) : 1.0f;
            rgb_sum[c] += sp.rgb[c];
        }
        // Snell at the mean surface: the transverse wave vector is continuous.
        const glm::dvec2 s_t = glm::dvec2(dir.x, dir.y) / sp.n;    // sin(theta_t) vector
        const double cos_t = std::sqrt(std::max(0.0, 1.0 - glm::dot(s_t, s_t)));
        sp.refracted = glm::dvec3(s_t.x, s_t.y, -cos_t);
        const double lambda0 = sp.n * sp.lambda;                  // vacuum wavelength
        sp.phase_per_m = 2.0 * std::numbers::pi / lambda0 * (sp.n * cos_t - cos_i_);
        // Carrier: the exact transverse frequency s_t / lambda (the field without it is periodic, so
        // it need not lie on the lattice 1 / L; snapping it tilted the light by up to lambda / 2L).
        const glm::dvec2 bins(s_t.x / sp.lambda * lx_, s_t.y / sp.lambda * ly_);
        WaveSetup setup;
        setup.nx = setup.ny = grid_;
        setup.lx = lx_;
        setup.ly = ly_;
        setup.wavelength = sp.lambda;
        setup.propagator = fresnel_ ? Propagator::Fresnel : Propagator::AngularSpectrum;
        setup.carrier_bins = bins;
        setup.shift_walk = beam_walk;
        sp.propagator = std::make_unique<WavePropagator>(setup);
    }
    for (auto& sp : spectral_)
        for (int c = 0; c < 3; ++c) sp.rgb[c] = rgb_sum[c] > 0.0 ? static_cast<float>(sp.rgb[c] / rgb_sum[c]) : 1.0f / samples_;
}

// Lookup frame of the table for the frame's surface (step 5 of render(), and textures).
LookupGeometry WaveOpticsMethod::lookup_geometry(const HeightField& hf, const SurfaceSamples& surface,
                                                 const std::vector<double>& depths) const {
    LookupGeometry geo;
    geo.origin = glm::dvec2(hf.origin) - glm::dvec2(surface.window.pad);
    geo.lx = lx_;
    geo.ly = ly_;
    geo.level = surface.level;
    geo.depths = depths;
    geo.walk = spectral_.front().propagator->carrier_walk();
    geo.refracted = refracted_;
    geo.pad = surface.window.pad;
    geo.reach_per_m = reach_per_m(stats_for(hf));
    geo.irradiance = irradiance_ * cos_i_ * transmittance_;
    geo.absorption = absorption_;
    return geo;
}

CausticOutput WaveOpticsMethod::render(const FrameGeometry& frame, const RenderRequest& request) {
    CausticOutput out;
    Stopwatch watch;
    auto lap = [&watch] {
        const double t = watch.ms();
        watch.reset();
        return t;
    };
    const HeightField& hf = *frame.objects.at(static_cast<std::size_t>(water_index_)).heightfield;
    if (!updated_for(hf)) update(frame);   // the window and the statistics, once per surface
    // 0. The wavelength for this surface and window (the propagators are rebuilt only when either changes).
    const FftWindow& window = window_;
    const double lambda = wavelength_for(stats_for(hf), spacing_);
    if (lambda != lambda_) build_spectral(lambda);
    out.health.add("wavelength_um", std::llround(1e6 * lambda_));
    // 1. The surface on the FFT grid over the window (bordered if its edges do not match), mean level removed.
    // A bordered window was resampled into the table by update() (frame_stats, for the border's deviation),
    // for this surface: those samples serve; a tiling surface's are taken here.
    const SurfaceSamples& surface =
        window.pad > 0.0 ? table_->samples() : table_->resample(hf, window, surface_lx_, surface_ly_);
    if (!window.periodic) out.health.add("nonperiodic_surface", 1);
    out.stages_ms.emplace_back("resample", lap());

    // Periodic texture (caustics synth): the table at the texture's one depth below the base level,
    // sampled periodically at the texel centres (the FFT field is periodic by construction).
    if (request.texture != nullptr) {
        const TextureRequest& tr = *request.texture;
        if (tr.width <= 0 || tr.height <= 0) throw std::invalid_argument("wave_optics: texture size must be positive");
        const double base = frame.scene->objects[static_cast<std::size_t>(water_index_)].heightfield.base_height;
        const double depth = surface.level - (base - tr.depth);   // below the mean level
        if (!(depth > 0.0)) throw std::invalid_argument("wave_optics: the texture plane must lie below the water");
        fill_table(surface, {depth}, out);
        lap();
        out.texture = Image(tr.width, tr.height, 1);
        if (samples_ > 1) out.texture_rgb = Image(tr.width, tr.height, 3);
        fill_periodic_texture(*table_, grid_, lookup_geometry(hf, surface, {depth}), out.texture,
                     samples_ > 1 ? &out.texture_rgb : nullptr);
        out.stages_ms.emplace_back("texture_lookup", lap());
        if (request.receiver == nullptr && request.camera == nullptr) return out;
    }

    // 2. The points to shade: receiver bin centres and covered camera pixels (the buffers are kept
    // between frames only to spare their allocation; every element is written below).
    std::vector<ShadePoint>& points = points_;
    points.clear();
    const ReceiverChart* chart = request.receiver;
    if (chart != nullptr) {
        const int width = chart->width(), height = chart->height();
        points.resize(static_cast<std::size_t>(width) * height);
        tbb::parallel_for(tbb::blocked_range<int>(0, height, 8), [&](const tbb::blocked_range<int>& r) {
            for (int j = r.begin(); j < r.end(); ++j)
                for (int i = 0; i < width; ++i) {
                    const double s = (i + 0.5) / width, t = (j + 0.5) / height;
                    points[static_cast<std::size_t>(j) * width + i] = {chart->point(s, t), chart->normal(s, t)};
                }
        });
    }
    const std::size_t receiver_points = points.size();
    const CameraGBuffer* gb = request.camera;
    std::vector<std::size_t> camera_pixels;
    if (gb != nullptr) {
        const int recv = frame.scene->receiver.object_index;
        for (std::size_t k = 0; k < gb->covered.size(); ++k) {
            if (!gb->covered[k] || gb->object[k] != recv) continue;
            camera_pixels.push_back(k);
            points.push_back({glm::dvec3(gb->position[k]), glm::dvec3(gb->normal[k])});
        }
    }
    // 3. Depth slices spanning the points below the water.
    double zmin = 1e300, zmax = -1e300;
    for (const ShadePoint& p : points) {
        const double z = surface.level - p.position.z;
        if (z > 0.0) {
            zmin = std::min(zmin, z);
            zmax = std::max(zmax, z);
        }
    }
    std::vector<double> depths;
    if (zmin <= zmax) {
        if (slices_ == 1) {
            depths.push_back(0.5 * (zmin + zmax));
        } else {
            for (int s = 0; s < slices_; ++s) depths.push_back(zmin + (zmax - zmin) * s / (slices_ - 1));
        }
    }
    // The regime at the deepest point (regime.hpp): points past the first focus, and eps in percent.
    if (!depths.empty()) {
        const Regime r = regime(stats_for(hf), zmax, window, exact_focus_);
        std::int64_t past = 0;
        for (const ShadePoint& p : points) past += surface.level - p.position.z > r.focus_depth ? 1 : 0;
        out.health.add("past_first_focus", past);
        out.health.add("diffraction_eps_pct", std::isfinite(r.epsilon) ? std::llround(std::min(100.0 * r.epsilon, 1e9)) : -1);
    }
    out.stages_ms.emplace_back("points", lap());

    // 4. Per wavelength: phase screen, forward transform, one inverse transform per slice.
    fill_table(surface, depths, out);
    lap();

    // 5. Look the intensity up at every point, scaled to irradiance.
    const LookupGeometry geo = lookup_geometry(hf, surface, depths);
    std::vector<glm::vec4>& values = values_;
    values.resize(points.size());   // lookup() writes every element
    LookupCounters counters;
    table_->lookup(geo, points, values, counters);
    out.health.add("not_covered", counters.not_covered);
    if (!window.periodic) out.health.add("tapered_lookups", counters.tapered);
    if (slices_ == 1 && !depths.empty()) {
        std::int64_t mismatch = 0;
        for (const ShadePoint& p : points) {
            const double z = surface.level - p.position.z;
            if (z > 0.0 && std::abs(z - depths.front()) > 1e-6) ++mismatch;
        }
        out.health.add("depth_mismatch", mismatch);
    }
    if (chart != nullptr) {
        out.receiver = Image(chart->width(), chart->height(), 1);
        if (samples_ > 1) out.receiver_rgb = Image(chart->width(), chart->height(), 3);
        for (std::size_t k = 0; k < receiver_points; ++k) {
            out.receiver.pixels[k] = values[k].x;
            if (samples_ > 1)
                for (int c = 0; c < 3; ++c) out.receiver_rgb.pixels[3 * k + c] = values[k][c + 1];
        }
    }
    if (gb != nullptr) {
        out.camera = Image(gb->width, gb->height, 1);
        for (std::size_t q = 0; q < camera_pixels.size(); ++q)
            out.camera.pixels[camera_pixels[q]] = values[receiver_points + q].x;
    }
    out.stages_ms.emplace_back("lookup", lap());
    return out;
}

MethodInfo make_info() {
    MethodInfo info;
    info.name = kName;
    info.doc = kDoc;
    info.radiometric = true;
    info.params = param_table();
    info.create = [](const ParamSet& p) -> std::unique_ptr<Method> { return std::make_unique<WaveOpticsMethod>(p); };
    return info;
}

}  // namespace

}  // namespace caustics::wave_optics

CAUSTICS_REGISTER_METHOD(caustics::wave_optics::make_info);
