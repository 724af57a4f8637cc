#pragma once
// Small numeric helpers of the wave_optics method: a branch-free single-precision sin/cos that the
// compiler vectorises (the phase screen and the transfer function need ~10^6 of them per frame, where
// libm's sincosf would dominate the frame time).
#include <cstdint>

namespace caustics::wave_optics {

// sin and cos of x for |x| < ~1e4 (Cody-Waite reduction by pi, then Taylor series to degree 13/14 on
// [-pi/2, pi/2]: truncation below 1e-9, so |s^2 + c^2 - 1| stays at float round-off, ~1e-7). Written
// without branches (rounding by the 1.5 * 2^23 shift, the sign from the parity bit) so that loops over
// it vectorise.
inline void fast_sincos(float x, float& s, float& c) {
    constexpr float kInvPi = 0.318309886183790672f;
    constexpr float kPiA = 3.140625f;                 // few mantissa bits: q * kPiA is exact
    constexpr float kPiB = 9.67653589793e-4f;         // pi - kPiA
    constexpr float kRound = 12582912.0f;             // 1.5 * 2^23: (y + kRound) - kRound = nearest integer
    const float y = x * kInvPi;
    const float qf = (y + kRound) - kRound;
    const std::int32_t q = static_cast<std::int32_t>(qf);
    const float r = (x - qf * kPiA) - qf * kPiB;      // in [-pi/2, pi/2]
    const float r2 = r * r;
    // sin r = r (1 - r^2/3! + r^4/5! - ... + r^12/13!)
    float ps = 1.6059043836821613e-10f;               // 1/13!
    ps = ps * r2 - 2.505210838544172e-8f;             // 1/11!
    ps = ps * r2 + 2.7557319223985893e-6f;            // 1/9!
    ps = ps * r2 - 1.984126984126984e-4f;             // 1/7!
    ps = ps * r2 + 8.333333333333333e-3f;             // 1/5!
    ps = ps * r2 - 1.6666666666666666e-1f;            // 1/3!
    ps = ps * r2 + 1.0f;
    // cos r = 1 - r^2/2! + ... + r^14/14!
    float pc = -1.1470745597729725e-11f;              // -1/14!
    pc = pc * r2 + 2.08767569878681e-9f;              // 1/12!
    pc = pc * r2 - 2.755731922398589e-7f;             // 1/10!
    pc = pc * r2 + 2.48015873015873e-5f;              // 1/8!
    pc = pc * r2 - 1.388888888888889e-3f;             // 1/6!
    pc = pc * r2 + 4.1666666666666664e-2f;            // 1/4!
    pc = pc * r2 - 0.5f;
    pc = pc * r2 + 1.0f;
    const float sign = static_cast<float>(1 - 2 * (q & 1));   // sin(r + q pi) = (-1)^q sin r, same for cos
    s = sign * (r * ps);
    c = sign * pc;
}

}  // namespace caustics::wave_optics
