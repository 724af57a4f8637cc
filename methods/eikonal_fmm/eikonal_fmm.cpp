// eikonal_fmm: Mercier 2013, "Eikonal Approximation for Real-Time Height Field Caustics", Sec. 3.
//
// update(frame) fills a 3-D caustic texture over the water volume: the eikonal solution phi (distance
// from the water-air interface, infinite refractive index: fronts move along the interface normals)
// by fast marching or a downward sweep, its curvature as the 7-point Laplacian (Eq. 3-4), the caustic
// value a * max(0, -Laplacian)^b (converging fronts have negative Laplacian; Sec. 4.1 mapping), and
// optionally the viscosity post-process of Sec. 3.3. render() reads the texture at receiver points.
//
// Parameters (the table below is the documentation `caustics list` prints):
//   grid        cells along the longer horizontal side of the volume (z at the same spacing)
//   iterations  viscosity post-process: xy dissipation steps per layer below threshold_height; 0 = off
//   solver      fmm (Sethian's fast marching, binary heap) | sweep (downward layer-by-layer sweeping)
//   order       1 | 2 (Rickett & Fomel second-order upwind differences)
//   init        vertex (Algorithm 1: interface vertices set their cell) | triangle (signed distance
//               from the cell centres near the interface to the surface triangles; Sec. 5.4's proposal)
//   boundary    none | embed (a larger domain) | paper (modified propagation costs, Algorithm 2)
//   ...
#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "eikonal_solver.hpp"
#include "errors.hpp"
#include "registry.hpp"
#include "timing.hpp"
#include "volume_grid.hpp"
#include "volume_texture_method.hpp"

namespace caustics {
namespace {

// Sec. 3.3: below the threshold height the fronts are assumed to have converged and the light to
// dissipate; each layer is the layer above after `steps` explicit xy diffusion steps (5-point,
// lambda = 1/5, total preserved), so the caustic structures spread in cones below the threshold. We
// diffuse instead of running the paper's xy wave equation so the texture stays non-negative.
void dissipate_below(VolumeF& tex, int threshold_layer, int steps, std::int64_t& clamped) {
    const VolumeShape& s = tex.shape;
    if (steps <= 0 || threshold_layer <= 0) return;
    std::vector<float> a(static_cast<std::size_t>(s.nx) * s.ny), b(a.size());
    const std::size_t layer = a.size();
    for (int k = std::min(threshold_layer, s.nz) - 1; k >= 0; --k) {
        std::copy_n(tex.data.begin() + static_cast<std::ptrdiff_t>((k + 1) * layer), layer, a.begin());
        for (int step = 0; step < steps; ++step) {
            // Explicit steps: every cell reads only the previous step, so rows run in parallel.
            tbb::parallel_for(0, s.ny, [&](int j) {
                for (int i = 0; i < s.nx; ++i) {
                    const std::size_t c = static_cast<std::size_t>(j) * s.nx + i;
                    const float v = a[c];
                    // Reflecting edges: a missing neighbour counts as the cell itself.
                    const float l = i > 0 ? a[c - 1] : v, r = i + 1 < s.nx ? a[c + 1] : v;
                    const float d = j > 0 ? a[c - s.nx] : v, u = j + 1 < s.ny ? a[c + s.nx] : v;
                    b[c] = v + 0.2f * (l + r + d + u - 4.0f * v);
                }
            });
            std::swap(a, b);
        }
        for (float& v : a)
            if (v < 0.0f) {
                v = 0.0f;
                ++clamped;
            }
        std::copy(a.begin(), a.end(), tex.data.begin() + static_cast<std::ptrdiff_t>(k * layer));
    }
}

class EikonalFmm final : public VolumeTextureMethod {
public:
    explicit EikonalFmm(const ParamSet& p)
        : VolumeTextureMethod(p),
          grid_(static_cast<int>(p.get_int("grid"))),
          dissipation_steps_(static_cast<int>(p.get_int("iterations"))),
          threshold_height_(p.get_float("threshold_height")),
          embed_margin_(p.get_float("embed_margin")),
          scaled_ior_(p.get_enum("ior_model") == "scaled"),
          embed_(p.get_enum("boundary") == "embed") {
        options_.solver = p.get_enum("solver") == "sweep" ? eikonal::Solver::Sweep : eikonal::Solver::Fmm;
        options_.order = static_cast<int>(p.get_int("order"));
        options_.init = p.get_enum("init") == "vertex" ? eikonal::Init::Vertex : eikonal::Init::Triangle;
        options_.boundary = p.get_enum("boundary") == "paper" ? eikonal::Boundary::Paper : eikonal::Boundary::None;
    }

    void update(const FrameGeometry& frame) override {
        health_ = Health{};
        update_stages_.clear();
        const ObjectInstance* water = find_water_interface(frame);
        if (!water) throw InputError(frame.scene->path, "objects", "eikonal_fmm needs a height-field dielectric interface");
        ior_ = water->object->material.ior;
        const HeightField& hf = *water->heightfield;
        const VolumeShape shape = caustic_volume(frame, *water, grid_, embed_ ? embed_margin_ : 0.0);
        eikonal::Stats stats;
        const VolumeD& phi = eikonal::solve(hf, shape, options_, stats, workspace_);
        update_stages_.emplace_back("init", stats.init_ms);
        update_stages_.emplace_back("boundary", stats.boundary_ms);
        update_stages_.emplace_back("solve", stats.solve_ms);

        Stopwatch watch;
        laplacian(phi, texture_);  // Eq. 3-4: curvature of the eikonal solution
        std::vector<std::int64_t> layer_nonfinite(static_cast<std::size_t>(shape.nz));
        tbb::parallel_for(0, shape.nz, [&](int k) {
            const std::size_t begin = shape.index(0, 0, k), end = begin + static_cast<std::size_t>(shape.nx) * shape.ny;
            for (std::size_t c = begin; c < end; ++c) {
                // Converging fronts (caustics) have negative curvature; air cells carry no light.
                const double conv = phi.data[c] > 0.0 ? std::max(0.0, -static_cast<double>(texture_.data[c])) : 0.0;
                float v = post_process(conv);
                if (!std::isfinite(v)) {
                    ++layer_nonfinite[static_cast<std::size_t>(k)];
                    v = 0.0f;
                }
                texture_.data[c] = v;
            }
        });
        std::int64_t nonfinite = 0;
        for (std::int64_t n : layer_nonfinite) nonfinite += n;
        update_stages_.emplace_back("curvature", watch.ms());

        // Viscosity post-process (Sec. 3.3) below the threshold height under the mean interface.
        set_interface(hf);
        std::int64_t clamped = 0;
        if (dissipation_steps_ > 0) {
            watch.reset();
            const double z_threshold = surface_z_ - threshold_height_;
            const int layer = static_cast<int>(std::floor((z_threshold - shape.origin.z) / shape.spacing));
            dissipate_below(texture_, std::clamp(layer, 0, shape.nz - 1), dissipation_steps_, clamped);
            update_stages_.emplace_back("dissipation", watch.ms());
        }
        health_.add("not_converged", stats.not_converged);
        health_.add("nonfinite", stats.nonfinite + nonfinite);
        health_.add("clamped", clamped);
        mark_built(frame);
    }

private:
    void configure_lookup(VolumeLookup& lookup) const override { lookup.scaled_ior = scaled_ior_; }

    int grid_, dissipation_steps_;
    double threshold_height_, embed_margin_;
    bool scaled_ior_, embed_;
    eikonal::Options options_;
    eikonal::Workspace workspace_;  // the eikonal solution; its storage is reused by the next update
};

MethodInfo eikonal_fmm_info() {
    MethodInfo info;
    info.name = "eikonal_fmm";
    info.doc = "Mercier 2013: 3-D caustic texture from the curvature (Laplacian) of the eikonal solution "
               "under a height-field water surface (fast marching or downward sweeping); receivers inside "
               "the volume read it by trilinear lookup. Relative values (normalize=flux scales them to the "
               "transmitted irradiance); assumes an infinite refractive index unless ior_model=scaled.";
    info.radiometric = false;
    info.params = {
        {"grid", ParamType::Int, "128", 4, 1024, {},
         "3-D texture: cells along the longer horizontal side of the water volume; z at the same spacing"},
        {"iterations", ParamType::Int, "0", 0, 10000, {},
         "viscosity post-process (Sec. 3.3): xy dissipation steps per layer below threshold_height; 0 = off"},
        {"solver", ParamType::Enum, "fmm", 0, 0, {"fmm", "sweep"},
         "fmm: fast marching with a binary heap (Sethian 1996); sweep: downward layer-by-layer fast "
         "sweeping, O(N), exact for fronts that move down"},
        {"order", ParamType::Int, "2", 1, 2, {},
         "upwind difference order: 1 (paper) or 2 (Rickett & Fomel 2000 one-sided 3-point differences)"},
        {"init", ParamType::Enum, "triangle", 0, 0, {"vertex", "triangle"},
         "front initialization: vertex (Algorithm 1, each interface vertex sets its cell) or triangle "
         "(signed distance from cell centres within 2 cells to the surface triangles, Sec. 5.4)"},
        {"boundary", ParamType::Enum, "paper", 0, 0, {"none", "embed", "paper"},
         "domain sides: none, embed (a larger domain, see embed_margin) or paper (modified propagation "
         "costs on the side faces, Algorithm 2)"},
        {"embed_margin", ParamType::Float, "0.25", 0.0, 2.0, {},
         "boundary=embed: fraction of the horizontal extent added on each side"},
        {"threshold_height", ParamType::Float, "0.3", 0.0, 1000.0, {},
         "depth [m] below the mean interface height where the dissipation post-process starts"},
        {"ior_model", ParamType::Enum, "infinite", 0, 0, {"infinite", "scaled"},
         "infinite: fronts along interface normals (the paper); scaled: depth along the mean refracted "
         "direction scaled by (n-1)/n so the paraxial focus lands at n R / (n-1) (Fig. 2b)"},
    };
    for (ParamSpec& spec : volume_texture_post_params("c")) info.params.push_back(std::move(spec));
    info.create = [](const ParamSet& p) -> std::unique_ptr<Method> { return std::make_unique<EikonalFmm>(p); };
    return info;
}

}  // namespace

CAUSTICS_REGISTER_METHOD(eikonal_fmm_info);

}  // namespace caustics
