// adaptive_beams: Liktor and Dachsbacher, "Real-Time Volume Caustics with Adaptive Beam Tracing" (I3D
// 2011), with the beam space and area function of Ernst et al. 2005: caustic beams generated from an
// adaptively refined projected grid in the light's image space, rendering the volume caustic radiance
// (camera_volume) of single-scattering homogeneous media and the surface caustics (receiver map, camera
// view) from the same beams.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include <caustics/api/method.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/util/timing.hpp>

#include "accumulate.hpp"
#include "claim.hpp"
#include "light_grid.hpp"

namespace caustics {
namespace adaptive_beams {
namespace {

class AdaptiveBeams final : public Method {
public:
    explicit AdaptiveBeams(const ParamSet& p) {
        grid_.grid = static_cast<int>(p.get_int("grid"));
        grid_.iterations = static_cast<int>(p.get_int("iterations"));
        grid_.adaptive = p.get_bool("adaptive");
        grid_.depth_threshold = p.get_float("depth_threshold");
        grid_.normal_threshold_deg = p.get_float("normal_threshold");
        grid_.focus_ratio = p.get_float("focus_ratio");
        grid_.deviation = p.get_float("deviation");
        grid_.camera_angle = p.get_float("camera_angle");
        grid_.fold_split = p.get_bool("fold_split");
        grid_.clamp_ratio = p.get_float("clamp_ratio");
        grid_.energy_cutoff = p.get_float("energy_cutoff");
        volume_iterations_ = static_cast<int>(p.get_int("volume_iterations"));
        fold_iterations_ = static_cast<int>(p.get_int("fold_iterations"));
        acc_.hull = p.get_enum("hull") == "prism" ? HullType::Prism : HullType::Tight;
        acc_.volume.samples = static_cast<int>(p.get_int("volume_samples"));
        acc_.volume.step = static_cast<int>(p.get_int("volume_step"));
        acc_.volume.refine = p.get_float("volume_refine");
        acc_.volume.subpixels = static_cast<int>(p.get_int("volume_subpixels"));
        acc_.volume.edge_subpixels = static_cast<int>(p.get_int("volume_edge_subpixels"));
        acc_.volume.lanes = p.get_bool("volume_lanes");
        acc_.volume.single = p.get_enum("volume_precision") == "float";
        acc_.volume.cull = p.get_float("volume_cull");
        acc_.receiver_samples = static_cast<int>(p.get_int("receiver_samples"));
        acc_.filter = static_cast<int>(p.get_int("filter"));
        acc_.surface_coverage = p.get_enum("camera_surface") == "coverage";
    }

    Capability capabilities(const Scene& scene) const override { return supports(scene); }
    Capability volume_capability(const Scene& scene) const override { return supports(scene); }

    // The frame's geometry moves: the tracer (the approximate ray tracing's stand-in, see README) is
    // per-frame work.
    void update(const FrameGeometry& frame) override {
        tracer_ = std::make_unique<RayTracer>(frame);
        frame_ = &frame;
    }

    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override {
        if (!tracer_ || frame_ != &frame)
            throw std::runtime_error("adaptive_beams: render() before update() of this frame");
        CausticOutput out;
        const Scene& scene = *frame.scene;
        Stopwatch clock;
        // Past 0.7 of the way to the first focus on water the surfaces' beams get the fewest levels up to
        // fold_iterations that keep the drawn cases within 0.05: past the focus the folds need a finest grid of
        // 256 (to 1.0 x), 512 (to 3 x) or 1024 (to 6 x) (README, "The aim at the defaults"); pool, 2.1 x past its
        // focus, pays 2x its frame for it.
        GridSettings surfaces = grid_;
        surfaces.iterations = surface_levels(frame, grid_, fold_iterations_);
        const bool refined = surfaces.iterations != grid_.iterations;
        const LightGrid grid(frame, *tracer_, surfaces);
        grid.generate(beams_, scratch_);
        const BeamSet& set = beams_;
        // The volume view's own beams where it asks for fewer levels: in-scattered light is smooth along
        // the camera rays, and on sphere_fog 2 levels take the volume view 0.59x the time of 3 for 1.6 % more
        // error (README, "Fewer beams for the volume"), while the surfaces need the finest level at the folds.
        const bool own_volume_set = request.camera_volume && grid_.adaptive && volume_iterations_ >= 0 &&
                                    volume_iterations_ < surfaces.iterations;
        BeamSet& volume_set = volume_beams_;
        if (own_volume_set) {
            GridSettings coarse = grid_;
            coarse.iterations = volume_iterations_;
            LightGrid(frame, *tracer_, coarse).generate(volume_set, scratch_);
        }
        out.stages_ms.emplace_back("beam_generation", clock.ms());
        AccumulateStats stats;
        if (request.camera || request.camera_volume) {
            clock.reset();
            CameraGBuffer own;
            const CameraGBuffer* g = request.camera;
            if (!g) {
                own = build_camera_gbuffer(*tracer_, scene.camera);
                g = &own;
            }
            if (own_volume_set) {
                if (request.camera) accumulate_camera(set, scene, *g, tracer_.get(), acc_, &out.camera, nullptr, stats);
                accumulate_camera(volume_set, scene, *g, tracer_.get(), acc_, nullptr, &out.camera_volume, stats);
            } else {
                accumulate_camera(set, scene, *g, tracer_.get(), acc_, request.camera ? &out.camera : nullptr,
                                  request.camera_volume ? &out.camera_volume : nullptr, stats);
            }
            // The camera's three stages (accumulate.hpp) and what the call spent beyond them.
            const double total = clock.ms();
            out.stages_ms.emplace_back("camera_hulls", stats.hulls_ms);
            out.stages_ms.emplace_back("camera_surface", stats.surface_ms);
            out.stages_ms.emplace_back("volume_view", stats.volume_ms);
            out.stages_ms.emplace_back("camera_other", std::max(0.0, total - stats.hulls_ms - stats.surface_ms - stats.volume_ms));
        }
        if (request.receiver) {
            clock.reset();
            accumulate_receiver(set, scene, *request.receiver, acc_, out.receiver, stats);
            out.stages_ms.emplace_back("surface_caustics", clock.ms());
        }
        const GridStats& st = set.stats;
        out.health.add("refined_past_focus", refined ? 1 : 0);   // 1: the surfaces' beams had fold_iterations levels
        out.health.add("beams_generated", st.beams_generated);
        out.health.add("beams_split", st.beams_split);
        out.health.add("discarded_tir", st.discarded_tir);
        out.health.add("discarded_energy", st.discarded_energy);
        out.health.add("flipped", st.flipped);
        out.health.add("degenerate", st.degenerate);
        out.health.add("lost_samples", st.lost);
        out.health.add("fill", stats.fill);
        out.health.add("clamped", stats.clamped);
        out.health.add("near_clipped", stats.near_clipped);
        out.health.add("offscreen", stats.offscreen);
        out.health.add("prism_fallback", stats.prism_fallback);
        out.health.add("volume_rays", stats.volume_rays);
        out.health.add("volume_refined", stats.volume_refined);
        out.health.add("volume_edge_pixels", stats.volume_edge_pixels);
        out.health.add("volume_culled", stats.volume_culled);
        out.health.add("volume_beams", !request.camera_volume ? 0
                                       : own_volume_set       ? volume_set.stats.beams_generated
                                                              : st.beams_generated);
        out.health.add("coverage_beams", stats.coverage_beams);
        std::int64_t nonfinite = 0;
        for (Image* img : {&out.receiver, &out.camera, &out.camera_volume})
            for (float& v : img->pixels)
                if (!std::isfinite(v)) {
                    ++nonfinite;
                    v = 0.0f;
                }
        out.health.add("nonfinite", nonfinite);
        return out;
    }

    AccuracyClaim accuracy_claim(const FrameGeometry& frame) const override {
        return claim_for(frame, grid_, fold_iterations_);
    }

private:
    GridSettings grid_;
    // The beams of the last frame and the generation's working storage, kept so that the next frame reuses
    // their memory.
    BeamSet beams_, volume_beams_;
    GridScratch scratch_;
    int volume_iterations_ = 1;   // the volume view's refinement levels; -1: the surfaces' beams
    int fold_iterations_ = 5;     // the surfaces' levels past the reach of `iterations` on water (surface_levels)
    AccumulateSettings acc_;
    std::unique_ptr<RayTracer> tracer_;
    const FrameGeometry* frame_ = nullptr;
};

}  // namespace

MethodInfo method_info() {
    MethodInfo info;
    info.name = "adaptive_beams";
    info.doc = "Liktor and Dachsbacher 2011, adaptive caustic beams (area function and prism of Ernst et al. 2005): "
               "beams from an adaptively refined light-space grid over the specular surfaces (refraction, two-sided "
               "refraction of closed dielectrics, mirrors), rasterised into the camera for the volume caustic "
               "radiance of homogeneous single-scattering media and point-in-beam surface caustics. One light; "
               "refuses dispersion and Fresnel reflection off solids.";
    info.radiometric = true;
    info.params = {
        {"grid", ParamType::Int, "32", 2, 512, {},
         "initial light-space grid cells per side (the paper: 16 with 3-4 levels; 32 with 2 levels has the same "
         "finest grid, and its split oracle does not miss sines shorter than two initial cells; with adaptive=false "
         "the uniform grid, the paper's comparison is 64)",
         {"16", "32"}},
        {"iterations", ParamType::Int, "2", 0, 6, {},
         "refinement levels of the split oracle (the paper: 3-4; the surfaces may get more past the focus on water: "
         "fold_iterations); ignored with adaptive=false",
         {"2", "3"}},
        {"fold_iterations", ParamType::Int, "5", 0, 6, {},
         "most refinement levels of the surfaces' beams where the receiver lies beyond the reach of `iterations` "
         "on a water surface (at the defaults: past 0.7 of the way to its first focus): the fewest that keep the "
         "drawn cases within 0.05 (finest grid 256 to 1.0 x the focus, 512 to 3 x, 1024 to 6 x), else the fewest "
         "within the 0.10 claim; 0 or <= iterations: `iterations` throughout"},
        {"volume_iterations", ParamType::Int, "1", -1, 6, {},
         "camera_volume: refinement levels of the beams the volume view integrates, when fewer than the "
         "surfaces' (a second, coarser beam set; the surfaces keep theirs); -1: the same beams as the surfaces "
         "(refined past the focus too, see fold_iterations)"},
        {"adaptive", ParamType::Bool, "true", 0, 0, {}, "refine the grid by the split oracle (false: uniform grid)"},
        {"hull", ParamType::Enum, "tight", 0, 0, {"tight", "prism"},
         "bounding volume rasterised into the camera: tight (the paper's 6 triangles: convex hull of the beam's "
         "6 corners) or prism (Ernst et al. 2005's touching planes)"},
        {"depth_threshold", ParamType::Float, "2", 0.0, 1e6, {},
         "split where the light-space depth varies across a cell by more than this times its width (a surface "
         "steeper than atan(2) = 63 deg from the light's view, i.e. near a silhouette)"},
        {"normal_threshold", ParamType::Float, "15", 0.0, 180.0, {},
         "split where the corners' normals differ by more than this [deg] (a 0.5 m sphere at grid 16 turns 7 deg "
         "per cell at its centre: only the rim splits)"},
        {"focus_ratio", ParamType::Float, "1", 0.01, 1e9, {},
         "energy: split a convergent beam at refinement level L whose section where it ends is below 1/(this x 4^L) "
         "of its start (its light is 4^-L of an initial cell's, so only beams that end brighter than the light "
         "refine; on `sphere` 1 beat 4, 16 and 64 at equal beam count)"},
        {"deviation", ParamType::Float, "0.01", 0.0, 1e6, {},
         "split where the light's hit at a cell's edge midpoint or centre lies further than this x the cell's "
         "extent where its beam ends from where the bilinear beam puts it (the ray map bends; on `sphere` 0.05 "
         "halved the error of 0.2 for 7 % more beams; 0.01 keeps drawn sine cases within 0.10 up to 0.7 of the "
         "way to the first focus, where 0.05 reaches 0.12 at 0.6 of the way)"},
        {"fold_split", ParamType::Bool, "true", 0, 0, {},
         "split cells one of whose beams passes a focus (its cross-section's area changes sign) before it ends: past "
         "the first focus the folds of the ray map lie inside such beams, whose constant density smears them"},
        {"camera_angle", ParamType::Float, "0.05", 0.0, 10.0, {},
         "split beams wider than this [rad] seen from the camera at the closest point of their central ray "
         "(0.05 rad = 26 pixels at 768 rows and 45 deg)"},
        {"clamp_ratio", ParamType::Float, "0.001", 1e-9, 1.0, {},
         "at a focus |A(y)| is clamped to at least this times the beam's start area (counted as clamped)"},
        {"energy_cutoff", ParamType::Float, "0.001", 0.0, 1.0, {},
         "beams are extruded until their flux density (divergence and extinction) falls below this fraction of "
         "its start value"},
        {"volume_samples", ParamType::Int, "1", 1, 4, {},
         "Gauss-Legendre points per exact ray-beam interval (1: the paper's single midpoint sample; 2 changed "
         "sphere_fog's camera_volume error by 0.5 %, within the reference's interval, for 12-24 % more volume time)"},
        {"volume_step", ParamType::Int, "2", 1, 16, {},
         "camera_volume: node spacing [pixels]; pixels between nodes are interpolated bilinearly where the block "
         "is smooth (1: every pixel evaluated, the paper)",
         {"1", "2"}},
        {"volume_refine", ParamType::Float, "1.0", 0.0, 1e6, {},
         "camera_volume: a block is evaluated in full where its nodes' radiances differ by more than this fraction "
         "of their mean (0: every block whose nodes differ at all), or its pixels see another object or a depth 5 % off the bilinear one"},
        {"volume_subpixels", ParamType::Int, "2", 1, 16, {},
         "camera_volume: rays per side of a fully evaluated pixel of a refined block (stratified over the pixel's "
         "square, each to its own first hit: the box filter at the light cone's edges; 1: the centre, the paper)"},
        {"volume_edge_subpixels", ParamType::Int, "1", 1, 16, {},
         "camera_volume: rays per side of a refined pixel whose sub-rays' radiances spread by more than "
         "volume_refine of their mean (a hull's edge crosses it: the light cone's surface); at most "
         "volume_subpixels, or volume_subpixels 1 (one ray: no spread to test): no second pass"},
        {"volume_lanes", ParamType::Bool, "true", 0, 0, {},
         "evaluate the volume view's ray-beam integrals four rays at a time in AVX2 lanes where the CPU has AVX2 "
         "(the same values to the bit; false: one ray at a time, for timing comparisons)"},
        {"volume_precision", ParamType::Enum, "double", 0, 0, {"double", "float"},
         "camera_volume: the arithmetic of each fragment's ray-beam integral (float: the beam's constants and the "
         "ray rounded to single precision and everything after in it, one ray at a time: what float lanes would "
         "cost in error; there are no float lanes, and this one-ray path is slower than the double lanes)"},
        {"volume_cull", ParamType::Float, "0", 0.0, 1.0, {},
         "camera_volume: leave out the beams whose mean radiance over their hull (in-scattered power over the image "
         "pixels it spans times its squared distance) is below this fraction of the 99th percentile of the beams' "
         "(0: none; measured not to pay, README \"The levers\")"},
        {"receiver_samples", ParamType::Int, "3", 1, 8, {},
         "point-in-beam samples per side of each receiver bin (their mean is the bin's mean irradiance)"},
        {"camera_surface", ParamType::Enum, "coverage", 0, 0, {"coverage", "point"},
         "camera view's surface caustics: coverage (a beam that ends on one plane, or leaves the plane receiver's edge, "
         "splits its flux among the pixels by the exact area its end section on the plane covers: each pixel's box "
         "average; other beams point-in-beam) or point "
         "(point-in-beam at every pixel centre, then the tent filter: the paper, Sec. 5.3 and 7)"},
        {"filter", ParamType::Int, "1", 0, 8, {},
         "radius [pixels] of the tent low-pass filter on the camera view's point-in-beam surface caustics (Sec. 7; "
         "0: off)"},
    };
    info.create = [](const ParamSet& p) -> std::unique_ptr<Method> { return std::make_unique<AdaptiveBeams>(p); };
    return info;
}

}  // namespace adaptive_beams

CAUSTICS_REGISTER_METHOD(adaptive_beams::method_info);

}  // namespace caustics
