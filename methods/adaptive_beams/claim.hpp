#pragma once
// What adaptive_beams renders (capabilities) and the accuracy it claims (see README.md for the
// measurements behind the claim).
#include <caustics/api/method.hpp>

#include "light_grid.hpp"

namespace caustics::adaptive_beams {

Capability supports(const Scene& scene);
// The refinement levels the surfaces' beams get in `frame`: `fold_iterations` where the receiver lies
// beyond the reach of `settings`' regime on a water surface (past fine_focus_limit of the way to its first
// focus at the defaults) and fold_iterations > settings.iterations, else settings.iterations. The render and
// the claim both use it, so that the claim describes the beams the render draws.
int surface_levels(const FrameGeometry& frame, const GridSettings& settings, int fold_iterations);
AccuracyClaim claim_for(const FrameGeometry& frame, const GridSettings& settings, int fold_iterations);

}  // namespace caustics::adaptive_beams
