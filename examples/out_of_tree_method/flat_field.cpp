// flat_field: the irradiance a flat water surface would transmit, with no caustic at all. It serves the
// harness's no-caustic baseline (caustics/frame/baseline.hpp) as a method: per receiver bin, the
// directional lights' irradiance refracted by the water's base plane (Snell, Fresnel if the scene asks,
// Beer-Lambert absorption along the refracted path), zero where that path enters outside the water.
// The camera view shows, at each pixel on the receiver, the bin it falls in.
//
// The same file builds into the `caustics` program when put in methods/flat_field/ of the repository.
#include <memory>

#include <caustics/api/method.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/frame/baseline.hpp>

namespace flat_field {
namespace {

using namespace caustics;

// The scenes the flat-interface irradiance is defined for (as flat_interface_baseline decides them):
// directional lights, and one specular object, a height-field dielectric.
Capability scene_kind(const Scene& scene) {
    if (scene.lights.empty()) return Capability::no("needs a light");
    for (const Light& light : scene.lights)
        if (light.type != LightType::Directional) return Capability::no("needs directional lights only");
    int specular = 0, water = 0;
    for (const Object& object : scene.objects) {
        if (!object.material.is_specular()) continue;
        ++specular;
        water += object.shape == ShapeType::HeightField && object.material.type == MaterialType::Dielectric;
    }
    if (specular != 1 || water != 1)
        return Capability::no("needs exactly one specular object, a height-field dielectric (water)");
    return Capability::yes();
}

class FlatField final : public Method {
public:
    Capability capabilities(const Scene& scene) const override { return scene_kind(scene); }

    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override {
        CausticOutput out;
        if (request.receiver) out.receiver = flat_interface_baseline(frame, *request.receiver);
        if (request.camera) out.camera = camera_view(frame, *request.camera, out.health);
        return out;
    }

    // It draws no caustic, so it claims nothing: its error is the baseline's by construction.
    AccuracyClaim accuracy_claim(const FrameGeometry&) const override {
        return AccuracyClaim::outside("draws no caustic: its error is the no-caustic baseline's");
    }

private:
    static Image camera_view(const FrameGeometry& frame, const CameraGBuffer& gbuffer, Health& health) {
        const Scene& scene = *frame.scene;
        const ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
        const Image map = flat_interface_baseline(frame, chart);
        Image view(gbuffer.width, gbuffer.height);
        for (int y = 0; y < gbuffer.height; ++y)
            for (int x = 0; x < gbuffer.width; ++x) {
                const std::size_t i = gbuffer.index(x, y);
                if (!gbuffer.covered[i]) continue;
                const int bin = gbuffer.object[i] == scene.receiver.object_index
                                    ? chart.bin_of(glm::dvec3(gbuffer.position[i]))
                                    : -1;
                if (bin < 0) {   // walls, or off the receiver: this method shades the receiver only
                    health.add("not_covered");
                    continue;
                }
                view.at(x, y) = map.at(bin % chart.width(), bin / chart.width());
            }
        return view;
    }
};

MethodInfo info() {
    MethodInfo m;
    m.name = "flat_field";
    m.doc = "The irradiance a flat water surface would transmit (no caustic): the harness's no-caustic "
            "baseline as a method, an example of a method built outside the repository";
    m.params = {
        {"grid", ParamType::Int, "1", 1, 1, {}, "no grid: the map is the receiver's own bins (only 1 is valid)"},
        {"iterations", ParamType::Int, "1", 1, 1, {}, "nothing iterates (only 1 is valid)"},
    };
    m.create = [](const ParamSet&) -> std::unique_ptr<Method> { return std::make_unique<FlatField>(); };
    return m;
}

}  // namespace
}  // namespace flat_field

CAUSTICS_REGISTER_METHOD(flat_field::info);
