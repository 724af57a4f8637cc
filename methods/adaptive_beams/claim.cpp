// adaptive_beams: the scenes it renders and the regime where its error is claimed.
#include "claim.hpp"

#include <string>

namespace caustics::adaptive_beams {

Capability supports(const Scene& scene) {
    if (scene.lights.size() != 1)
        return Capability::no("needs exactly one light (the beams are generated from one light's image space)");
    for (const Object& o : scene.objects) {
        if (!o.material.is_specular()) continue;
        if (o.material.type == MaterialType::Dielectric && o.material.dispersion > 0.0)
            return Capability::no("ignores dispersion (object '" + o.name + "' disperses)");
        if (scene.fresnel && o.shape != ShapeType::HeightField)
            return Capability::no("with Fresnel on, traces only the transmitted beams: the light reflected off the "
                                  "solid '" + o.name + "' is not traced");
    }
    const ShapeType receiver = scene.receiver_object().shape;
    if (receiver != ShapeType::Plane && receiver != ShapeType::HeightField)
        return Capability::no("the receiver must be a plane or a height field");
    return Capability::yes();
}

AccuracyClaim claim_for(const FrameGeometry& /*frame*/, const GridSettings& /*settings*/) {
    return AccuracyClaim::within(0.5);
}

}  // namespace caustics::adaptive_beams
