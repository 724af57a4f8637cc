#pragma once
// Private to heightfield*.cpp: the generators that are not closed-form. Each fills `hf` (already sized
// by make_grid for the descriptor, heights set to base_height) with heights and per-vertex gradients.
#include <caustics/scene/heightfield/heightfield.hpp>

namespace caustics::detail {

HeightField make_grid(const HeightFieldDesc& desc);
// Per-vertex gradients from the heights (central differences inside, one-sided at the border).
void gradients_by_central_differences(HeightField& hf);

// Stam, Periodic Caustic Textures: power-law-in-space, Gaussian-in-time filtered 3-D noise (FFTW).
void generate_noise(const HeightFieldDesc& desc, double time, HeightField& hf);
// Deterministic damped 2-D wave equation with seeded Gaussian drops, stepped to `frame`.
void generate_waves(const HeightFieldDesc& desc, int frame, double fps, HeightField& hf);
// Height map image: base + amplitude * first channel, bilinearly resampled.
void generate_image(const HeightFieldDesc& desc, HeightField& hf);

}  // namespace caustics::detail
