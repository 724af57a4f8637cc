#include <caustics/blocks/volume/volume_texture_method.hpp>

namespace caustics {

std::vector<ParamSpec> volume_texture_post_params(const std::string& value) {
    return {
        {"a", ParamType::Float, "1", 1e-12, 1e12, {}, "post-process a * " + value + "^b of the caustic value " + value + " (Sec. 4.1): a"},
        {"b", ParamType::Float, "1", 0.05, 10.0, {}, "post-process a * " + value + "^b (Sec. 4.1): exponent b"},
        {"normalize", ParamType::Enum, "flux", 0, 0, {"flux", "raw"},
         "flux: scale so the receiver's mean equals the irradiance a flat interface transmits; raw: texture values"},
    };
}

VolumeTextureMethod::VolumeTextureMethod(const ParamSet& p)
    : a_(p.get_float("a")), b_(p.get_float("b")), normalize_flux_(p.get_enum("normalize") == "flux") {}

Capability VolumeTextureMethod::capabilities(const Scene& scene) const {
    const std::string why = volume_caustics_unsupported(scene);
    return why.empty() ? Capability::yes() : Capability::no(why);
}

void VolumeTextureMethod::set_interface(const HeightField& interface) {
    double mean = 0.0;
    for (float z : interface.height) mean += z;
    surface_z_ = interface.height.empty() ? 0.0 : mean / static_cast<double>(interface.height.size());
    water_lo_ = interface.origin;
    water_hi_ = interface.origin + interface.extent();
}

CausticOutput VolumeTextureMethod::render(const FrameGeometry& frame, const RenderRequest& request) {
    if (built_scene_ != frame.scene || built_frame_ != frame.frame) update(frame);
    VolumeLookup lookup;
    lookup.texture = &texture_;
    lookup.normalize_flux = normalize_flux_;
    lookup.ior = ior_;
    lookup.surface_z = surface_z_;
    lookup.water_lo = water_lo_;
    lookup.water_hi = water_hi_;
    configure_lookup(lookup);
    CausticOutput out = render_volume_texture(frame, request, lookup);
    for (const auto& [name, n] : health_.counters) out.health.add(name, n);
    return out;
}

}  // namespace caustics
