// wave_pde: Mercier 2013, Sec. 4 ("Wave Interpretation"), Algorithm 3.
//
// update(frame): phi = 1 on the cells the water-air interface crosses, 0 elsewhere, zero initial
// velocity; leapfrog steps of the wave equation over the water volume padded by a damping band;
// the caustic texture is the sum of phi over the steps, mapped by a * max(0, C)^b (Sec. 4.1).
// By default (stop=arrival) each cell sums phi until the downward front has passed it by `margin`
// cells, and only a window of layers around the front is updated (see arrival_steps for why the sum
// to convergence, Algorithm 3's stop, carries no caustic).
// render(): trilinear lookups at the receiver points (harness/volume_texture_method, volume_grid).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <tbb/parallel_for.h>

#include "errors.hpp"
#include "frame.hpp"
#include "registry.hpp"
#include "timing.hpp"
#include "volume_grid.hpp"
#include "volume_texture_method.hpp"
#include "wave_solver.hpp"

namespace caustics {
namespace {

constexpr double kMaxCourant = 0.5773502691896258;  // 1 / sqrt(3): 3-D leapfrog stability bound

// cells: phi = 1 on cells the interface crosses (the paper): the interface's range over the cell's
// footprint (corners and centre) overlaps the cell's z-range. smooth: phi = exp(-d^2 / 2h^2) of the
// (normal) distance d to the interface, truncated at 3h: the same sheet without the grid-scale content
// that the leapfrog scheme carries at almost zero group velocity (which keeps a hard sheet ringing for
// thousands of steps before every |phi| < epsilon).
std::vector<float> interface_cells(const HeightField& hf, const VolumeShape& s, bool smooth) {
    std::vector<float> init(s.size(), 0.0f);
    const double h = s.spacing;
    tbb::parallel_for(0, s.ny, [&](int j) {
        for (int i = 0; i < s.nx; ++i) {
            const glm::dvec3 c = s.center(i, j, 0);
            if (smooth) {
                glm::dvec2 g;
                const double z = extended_height(hf, c.x, c.y, &g);
                const double n_z = 1.0 / std::sqrt(1.0 + glm::dot(g, g));
                for (int k = 0; k < s.nz; ++k) {
                    const double d = (s.origin.z + (k + 0.5) * h - z) * n_z / h;
                    if (std::fabs(d) < 3.0) init[s.index(i, j, k)] = static_cast<float>(std::exp(-0.5 * d * d));
                }
                continue;
            }
            double lo = 1e300, hi = -1e300;
            for (int q = 0; q < 5; ++q) {
                const double dx = q == 4 ? 0.0 : ((q & 1) ? 0.5 : -0.5) * h;
                const double dy = q == 4 ? 0.0 : ((q & 2) ? 0.5 : -0.5) * h;
                const double z = extended_height(hf, c.x + dx, c.y + dy);
                lo = std::min(lo, z);
                hi = std::max(hi, z);
            }
            for (int k = 0; k < s.nz; ++k) {
                const double z0 = s.origin.z + k * h, z1 = z0 + h;
                if (hi >= z0 && lo < z1) init[s.index(i, j, k)] = 1.0f;
            }
        }
    });
    return init;
}

class WavePde final : public VolumeTextureMethod {
public:
    explicit WavePde(const ParamSet& p)
        : VolumeTextureMethod(p),
          grid_(static_cast<int>(p.get_int("grid"))),
          steps_(static_cast<int>(p.get_int("iterations"))),
          epsilon_(p.get_float("epsilon")),
          smooth_init_(p.get_enum("init") == "smooth"),
          stop_epsilon_(p.get_enum("stop") == "epsilon"),
          margin_(p.get_float("margin")),
          sides_(p.get_enum("sides")) {
        settings_.courant = p.get_float("courant");
        settings_.sponge = static_cast<int>(p.get_int("sponge"));
        settings_.sponge_strength = p.get_float("sponge_strength");
        settings_.narrow_band = p.get_bool("narrow_band");
        settings_.clamp_negative = p.get_bool("clamp_negative");
    }

    Capability capabilities(const Scene& scene) const override {
        Capability base = VolumeTextureMethod::capabilities(scene);
        if (!base.supported || sides_ != "periodic") return base;
        // The texture box of frame 0 (the water's footprint does not change between frames).
        const FrameGeometry frame = build_frame_geometry(scene, 0);
        const ObjectInstance* water = find_water_interface(frame);
        if (water && tiles_box(*water->heightfield, caustic_volume(frame, *water, grid_, 0.0))) return base;
        return Capability::no("sides=periodic needs a tiling water surface (noise generator) whose period is "
                              "the texture box; use sides=auto, mirror or sponge");
    }

    void update(const FrameGeometry& frame) override {
        health_ = Health{};
        update_stages_.clear();
        const ObjectInstance* water = find_water_interface(frame);
        if (!water) throw InputError(frame.scene->path, "objects", "wave_pde needs a height-field dielectric interface");
        ior_ = water->object->material.ior;
        const HeightField& hf = *water->heightfield;
        const VolumeShape interior = caustic_volume(frame, *water, grid_, 0.0);
        wave::Settings settings = settings_;
        settings.sides = resolve_sides(hf, interior, frame.scene->path);
        // The damping band pads the z faces always, the x and y faces only where they are not mirror
        // or periodic.
        const int pad_xy = settings.sides == wave::Sides::Zero ? settings.sponge : 0, pad_z = settings.sponge;
        const VolumeShape full = interior.padded(pad_xy, pad_z);

        Stopwatch watch;
        wave::Simulation sim(full, settings);
        sim.set_initial(interface_cells(hf, full, smooth_init_));
        std::vector<float> accumulated(full.size(), 0.0f);
        update_stages_.emplace_back("init", watch.ms());

        watch.reset();
        const bool window = steps_ == 0 && !stop_epsilon_;
        const int cap = steps_ > 0 ? steps_ : stop_epsilon_ ? epsilon_step_cap(full) : arrival_steps(hf, interior);
        // stop=arrival: the layer of the downward front's centre at step 0 (cell centres at k + 1/2).
        const double front0 = (interface_top(hf) - full.origin.z) / full.spacing - 0.5;
        int step = 0;
        bool finite = true, settled = false;
        for (; step < cap; ++step) {
            // A layer accumulates until the front's centre is margin_ below it.
            const int top = window ? static_cast<int>(std::floor(front0 - settings_.courant * step + margin_))
                                   : std::numeric_limits<int>::max();
            if (window && top < settings_.sponge) break;  // every layer of the texture is done
            const double max_abs = sim.step(&accumulated, top);
            if (!std::isfinite(max_abs)) {
                finite = false;
                break;
            }
            if (steps_ == 0 && stop_epsilon_ && max_abs < epsilon_) {
                settled = true;
                ++step;
                break;
            }
        }
        sim.flush(&accumulated);
        steps_taken_ = step;
        update_stages_.emplace_back("solve", watch.ms());
        if (steps_ == 0 && stop_epsilon_ && !settled && finite) health_.add("not_converged");

        // The texture over the interior box; a * max(0, C)^b.
        watch.reset();
        texture_ = VolumeF(interior);
        std::int64_t negative = 0, nonfinite = 0;
        for (int k = 0; k < interior.nz; ++k)
            for (int j = 0; j < interior.ny; ++j)
                for (int i = 0; i < interior.nx; ++i) {
                    double c = accumulated[full.index(i + pad_xy, j + pad_xy, k + pad_z)];
                    if (!std::isfinite(c) || !finite) {
                        ++nonfinite;
                        c = 0.0;
                    }
                    if (c < 0.0) {
                        ++negative;
                        c = 0.0;
                    }
                    texture_.at(i, j, k) = post_process(c);
                }
        update_stages_.emplace_back("post_process", watch.ms());

        health_.add("clamped", sim.clamped() + negative);
        health_.add("nonfinite", nonfinite);
        health_.add("cfl_violations", settings_.courant > kMaxCourant ? 1 : 0);  // refused by the parameter range
        health_.add("steps", steps_taken_);
        health_.add("cells_updated", sim.cells_updated());
        set_interface(hf);
        mark_built(frame);
    }

    // The surface repeats with the box's period along x and y: a periodic field whose rectangle is
    // the texture box, up to round-off.
    static bool tiles_box(const HeightField& hf, const VolumeShape& box) {
        if (!hf.periodic) return false;
        const glm::dvec2 ext = hf.extent(), box_ext(box.extent());
        const double tol = 1e-6 * std::max(ext.x, ext.y);
        return std::fabs(box.origin.x - hf.origin.x) < tol && std::fabs(box.origin.y - hf.origin.y) < tol &&
               std::fabs(box_ext.x - ext.x) < tol && std::fabs(box_ext.y - ext.y) < tol;
    }
    wave::Sides resolve_sides(const HeightField& hf, const VolumeShape& box, const std::string& scene_path) const {
        if (sides_ == "sponge") return wave::Sides::Zero;
        if (sides_ == "mirror") return wave::Sides::Mirror;
        if (tiles_box(hf, box)) return wave::Sides::Periodic;
        if (sides_ == "periodic") throw InputError(scene_path, "sides", "periodic needs a water surface that tiles the texture box (auto, mirror or sponge otherwise)");
        return wave::Sides::Mirror;
    }

    // stop=arrival: an upper bound of the steps (the front's centre margin_ past the bottom of the
    // volume); the loop ends when the last layer of the texture stops accumulating. Why not Algorithm
    // 3's "until every |phi| < epsilon": summing the scheme over all steps gives courant^2 L(C) =
    // -sigma dt phi^0 for the total C, i.e. C is harmonic wherever the band does not damp the initial
    // sheet and carries no caustic; the caustic is in the partial sum T M_T (Kirchhoff's formula) just
    // after the front has passed, which each cell keeps.
    int arrival_steps(const HeightField& hf, const VolumeShape& interior) const {
        const double cells = (interface_top(hf) - interior.origin.z) / interior.spacing + margin_;
        return std::max(1, static_cast<int>(std::ceil(cells / settings_.courant))) + 1;
    }
    static double interface_top(const HeightField& hf) {
        double top = -1e300;
        for (float z : hf.height) top = std::max(top, static_cast<double>(z));
        return top;
    }
    // stop=epsilon: a cap far beyond the time a front needs to cross the padded domain and be absorbed.
    int epsilon_step_cap(const VolumeShape& full) const {
        return static_cast<int>(std::ceil(20.0 * (full.nx + full.ny + full.nz) / settings_.courant));
    }

private:
    int grid_, steps_;
    double epsilon_;
    bool smooth_init_, stop_epsilon_;
    double margin_;
    std::string sides_;
    wave::Settings settings_;
    int steps_taken_ = 0;
};

MethodInfo wave_pde_info() {
    MethodInfo info;
    info.name = "wave_pde";
    info.doc = "Mercier 2013, Sec. 4: 3-D caustic texture as the time-accumulated solution of the wave "
               "equation started from the water-air interface (explicit leapfrog, damping band, narrow "
               "band); receivers inside the volume read it by trilinear lookup. Relative values "
               "(normalize=flux scales them to the transmitted irradiance).";
    info.radiometric = false;
    info.params = {
        {"grid", ParamType::Int, "128", 4, 1024, {},
         "3-D texture: cells along the longer horizontal side of the water volume; z at the same spacing "
         "(the damping band adds `sponge` cells on every side)"},
        {"iterations", ParamType::Int, "0", 0, 1000000, {},
         "time steps of the wave simulation; 0 = until the `stop` rule holds"},
        {"stop", ParamType::Enum, "arrival", 0, 0, {"arrival", "epsilon"},
         "iterations=0: arrival = each cell sums phi until the front from the interface is `margin` cells "
         "past it (about depth / (c dt) steps; a window of layers around the front is updated; later "
         "steps only add wakes that cancel the caustic), epsilon = "
         "until every |phi| < epsilon (Algorithm 3; thousands of steps, and its limit is harmonic in "
         "the volume, i.e. without caustics)"},
        {"courant", ParamType::Float, "0.5", 0.01, kMaxCourant, {},
         "Courant number c dt / h of the leapfrog scheme; stable only up to 1/sqrt(3) = 0.5773502691896258"},
        {"init", ParamType::Enum, "cells", 0, 0, {"cells", "smooth"},
         "initial phi: cells (1 on cells the interface crosses, the paper) or smooth (exp(-d^2/2h^2) of "
         "the distance d to the interface: no grid-scale ringing, so stop=epsilon settles far sooner; "
         "with stop=arrival both give the same error within 1 %)"},
        {"margin", ParamType::Float, "3", 0.0, 64.0, {},
         "stop=arrival: a cell stops accumulating when the downward front's centre is this many cells "
         "past it (3: the initial sheet's half-width; 6 also takes the scheme's dispersive tail behind "
         "the pulse; much more adds the wakes that cancel the caustic)"},
        {"epsilon", ParamType::Float, "0.001", 1e-9, 1.0, {}, "iterations=0, stop=epsilon: stop when every |phi| is below this"},
        {"sides", ParamType::Enum, "auto", 0, 0, {"auto", "sponge", "mirror", "periodic"},
         "the volume's x and y faces: sponge = the damping band (the paper; the texture darkens within "
         "about sqrt(6 depth h) of them, where the accumulated sheet is cut off), mirror = zero normal "
         "derivative (the sheet continues as its mirror image), periodic = the field wraps (only for a "
         "tiling water surface whose period is the texture box), auto = periodic where it applies, else mirror"},
        {"sponge", ParamType::Int, "12", 0, 256, {},
         "damping band width in cells on the volume's faces (top and bottom; also the sides with "
         "sides=sponge), a smooth quadratic ramp so the domain boundary does not reflect"},
        {"sponge_strength", ParamType::Float, "0.5", 0.0, 100.0, {},
         "damping coefficient sigma (per unit time, c = h = 1) at the outer edge of the band"},
        {"narrow_band", ParamType::Bool, "true", 0, 0, {},
         "update only x rows next to non-zero values (Sec. 4: the wave has a finite speed)"},
        {"clamp_negative", ParamType::Bool, "false", 0, 0, {},
         "clamp phi to non-negative values after every step (Sec. 5.2; localizes the wave, adds error)"},
    };
    for (ParamSpec& spec : volume_texture_post_params("C")) info.params.push_back(std::move(spec));
    info.create = [](const ParamSet& p) -> std::unique_ptr<Method> { return std::make_unique<WavePde>(p); };
    return info;
}

}  // namespace

CAUSTICS_REGISTER_METHOD(wave_pde_info);

}  // namespace caustics
