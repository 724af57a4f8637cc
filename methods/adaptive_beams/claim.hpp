#pragma once
// What adaptive_beams renders (capabilities) and the accuracy it claims (see README.md for the
// measurements behind the claim).
#include <caustics/api/method.hpp>

#include "light_grid.hpp"

namespace caustics::adaptive_beams {

Capability supports(const Scene& scene);
// The refinement levels the surfaces' beams get in `frame`: where the receiver lies beyond the reach of
// `settings`' measured regime on a water surface (past 0.7 of the way to its first focus at the defaults),
// the fewest levels up to fold_iterations whose regime reaches it (4 up to 1.2 x the focus, 5 up to 6 x at the
// defaults); else, and where no such level exists, settings.iterations. The render and the claim both use it,
// so that the claim describes the beams the render draws.
int surface_levels(const FrameGeometry& frame, const GridSettings& settings, int fold_iterations);
AccuracyClaim claim_for(const FrameGeometry& frame, const GridSettings& settings, int fold_iterations);

}  // namespace caustics::adaptive_beams
