// adaptive_beams: the scenes it renders and the regime where its error is claimed.
#include "claim.hpp"

#include <cstdio>
#include <string>

#include <caustics/blocks/regime/first_focus.hpp>

namespace caustics::adaptive_beams {

namespace {
constexpr double kMinFinestGrid = 64, kMaxFocusFraction = 0.4, kClaimError = 0.10;
}  // namespace

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

// Measured at the defaults (grid 16, 3 levels: finest 128) on the fixed and 200 drawn cases (README.md):
// the receiver error stays within kClaimError up to kMaxFocusFraction of the way to the refracted wave's
// first focus (blocks/regime); nearer the focus and past it the beams' cross-sections shrink towards the
// fold and the error grows. Below a finest grid of 64 it was not measured.
AccuracyClaim claim_for(const FrameGeometry& frame, const GridSettings& s) {
    const int finest = s.grid << (s.adaptive ? s.iterations : 0);
    std::vector<RegimeBound> bounds = {{"finest_grid", static_cast<double>(finest), kMinFinestGrid, false}};
    // Solid refractors are not claimed: the beams through a ball lens's rim fold into its ring caustic
    // (ball_lens: nrmse 0.24 at the defaults, 0.19 at twice the grid).
    const regime::WaterRegime w = regime::water_regime(frame);
    bounds.push_back({"water_interface", w.valid ? 1.0 : 0.0, 1.0, false});
    if (w.valid) bounds.push_back({"depth_over_first_focus", w.depth_over_first_focus(), kMaxFocusFraction, true});
    return regime::claim_within_bounds(std::move(bounds), kClaimError, [&](const RegimeBound& b) -> std::string {
        if (b.quantity == "finest_grid")
            return "finest light-space grid " + std::to_string(finest) + " below the " +
                   std::to_string(static_cast<int>(kMinFinestGrid)) + " where the claim was measured";
        if (b.quantity == "water_interface")
            return "no height-field water interface: solid refractors are not claimed (ball_lens, whose beams fold into "
                   "its ring caustic: nrmse 0.24 at the defaults)";
        char why[240];
        std::snprintf(why, sizeof why,
                      "the receiver lies %.3g m below the water, %.2f of the way to the first focus at %.3g m, beyond "
                      "the %.2f where the beams' error was measured within %.2f",
                      w.depth, b.value, w.focus.first_focus_depth, kMaxFocusFraction, kClaimError);
        return why;
    });
}

}  // namespace caustics::adaptive_beams
