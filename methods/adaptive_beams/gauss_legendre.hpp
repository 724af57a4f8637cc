#pragma once
// Gauss-Legendre nodes and weights on [-1, 1] for 1 to 4 points: the quadrature of the ray-beam
// integral (beam.cpp's pointwise form and ray_beam.cpp's per-beam form use the same rule).
#include <algorithm>

namespace caustics::adaptive_beams {

struct GaussRule {
    int n;
    double x[4], w[4];
};

inline constexpr GaussRule kGaussRules[4] = {
    {1, {0.0}, {2.0}},
    {2, {-0.5773502691896257, 0.5773502691896257}, {1.0, 1.0}},
    {3, {-0.7745966692414834, 0.0, 0.7745966692414834}, {0.5555555555555556, 0.8888888888888888, 0.5555555555555556}},
    {4, {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526},
     {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538}},
};

// The rule of `points` (clamped to 1..4).
inline const GaussRule& gauss_rule(int points) { return kGaussRules[std::clamp(points, 1, 4) - 1]; }

}  // namespace caustics::adaptive_beams
