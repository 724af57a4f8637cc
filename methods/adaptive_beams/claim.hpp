#pragma once
// What adaptive_beams renders (capabilities) and the accuracy it claims (see README.md for the
// measurements behind the claim).
#include <caustics/api/method.hpp>

#include "light_grid.hpp"

namespace caustics::adaptive_beams {

Capability supports(const Scene& scene);
AccuracyClaim claim_for(const FrameGeometry& frame, const GridSettings& settings);

}  // namespace caustics::adaptive_beams
