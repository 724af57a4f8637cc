#pragma once
// Shared by the plugins that fill a 3-D caustic texture over the water volume once per frame and let
// receivers read it (Mercier 2013): the a * c^b post-process and normalization parameters (Sec. 4.1),
// the capability check, the rebuild when the frame changes, and the lookup render.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <caustics/api/method.hpp>
#include <caustics/api/params.hpp>
#include <caustics/blocks/volume/volume_grid.hpp>
#include <caustics/blocks/volume/volume_lookup.hpp>

namespace caustics {

// The parameters every volume-texture plugin takes: `a` and `b` of the post-process a * value^b
// (Sec. 4.1), and `normalize`. `value` names the quantity in the docs ("c", "C").
std::vector<ParamSpec> volume_texture_post_params(const std::string& value);

class VolumeTextureMethod : public Method {
public:
    Capability capabilities(const Scene& scene) const override;
    // Rebuilds the texture when the frame is not the one it was built for, then reads it.
    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override;

    // The texture of the last update() and the timings of its stages (for tests and benchmarks).
    const VolumeF& texture() const { return texture_; }
    const std::vector<std::pair<std::string, double>>& update_stages_ms() const { return update_stages_; }

protected:
    explicit VolumeTextureMethod(const ParamSet& p);  // reads a, b, normalize

    // a * value^b of a non-negative value.
    float post_process(double value) const { return static_cast<float>(a_ * (b_ == 1.0 ? value : std::pow(value, b_))); }
    // The lookups' water: its mean height (surface_z_, their depth origin) and its rectangle (light
    // enters through it only).
    void set_interface(const HeightField& interface);
    // Call at the end of update(): render() reads the texture without rebuilding it for this frame.
    void mark_built(const FrameGeometry& frame) {
        built_frame_ = frame.frame;
        built_scene_ = frame.scene;
    }
    // Lookup options beyond the shared ones (an ior model's mapping).
    virtual void configure_lookup(VolumeLookup& /*lookup*/) const {}

    double a_, b_;
    bool normalize_flux_;
    VolumeF texture_;
    double ior_ = 1.33, surface_z_ = 0.0;
    glm::dvec2 water_lo_{0.0}, water_hi_{0.0};
    Health health_;
    std::vector<std::pair<std::string, double>> update_stages_;

private:
    int built_frame_ = -1;
    const Scene* built_scene_ = nullptr;
};

}  // namespace caustics
