// Analytic truth of the refracting sine surface (docs/design.md section 5). See analytic_truth.hpp.
//
// Transport conventions are the reference's (reference.cpp): air (index 1) above the height field, water
// below, refraction by Snell's law with the exact surface normal, Beer-Lambert absorption exp(-Ka L) over
// the path L in water, and with scene.fresnel the unpolarised Fresnel transmittance (reflected light
// escapes upwards; a reflected ray that could meet the surface again makes the closed form unavailable).
#include <caustics/reference/analytic_truth.hpp>

#include <cstdio>

#include <caustics/frame/baseline.hpp>

namespace caustics {

SinePlane::Strip SinePlane::trace(double s) const {
    Strip out;
    const double z = height(s), hp = slope(s);
    // Upward unit normal n = (-h', 1) / sqrt(1 + h'^2); the light d reaches the upper side where d . n < 0.
    const double norm = std::sqrt(1.0 + hp * hp);
    const double ns = -hp / norm, nz = 1.0 / norm;
    // A back-facing point (cos_i <= 0) carries no flux; its ray is still traced (as tangent) so that a
    // strip ending exactly at a crest's shadow edge has a landing point.
    const double cos_i = std::max(-(light_s * ns + light_z * nz), 0.0);
    out.z = z;
    out.front = cos_i > 0.0;
    out.refl_s = light_s + 2.0 * cos_i * ns;
    out.refl_z = light_z + 2.0 * cos_i * nz;
    // Snell's law, vector form: t = eta d + (eta cos_i - cos_t) n, eta = 1 / ior.
    const double eta = 1.0 / ior;
    const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0 && out.front) {
        out.tir = true;
        return out;
    }
    const double cos_t = std::sqrt(std::max(1.0 - sin2_t, 0.0));
    double ts = eta * light_s + (eta * cos_i - cos_t) * ns, tz = eta * light_z + (eta * cos_i - cos_t) * nz;
    const double tl = std::sqrt(ts * ts + tz * tz);
    out.dir_s = ts / tl;
    out.dir_z = tz / tl;
    if (!(out.dir_z < 0.0)) return out;   // sent upwards: the caller rejects the scene
    const double path = (z - floor_z) / -out.dir_z;
    out.landing = s + out.dir_s * path;
    // The beam's flux through the strip per unit s: E0 d . (-N) with N = (-h', 1) the unnormalised normal,
    // i.e. E0 (cos t + h' sin t) for a light tilted by t towards +s; equal to E0 cos_i |N|.
    double density = irradiance * cos_i * norm;
    if (fresnel && out.front) density *= fresnel_transmittance(cos_i, cos_t, 1.0, ior);
    if (absorption > 0.0) density *= std::exp(-absorption * path);   // Beer-Lambert
    out.density = density;
    return out;
}

bool SinePlane::meets_surface_again(double s0, double dir_s, double dir_z, bool below) const {
    const double a = std::fabs(amplitude), curvature = a * k * k;   // |h''| <= A k^2
    // A flat surface, or a vertical ray (a height field meets a vertical line once), cannot be met again.
    if (!(curvature > 0.0) || std::fabs(dir_s) < 1e-15) return false;
    const double side = below ? -1.0 : 1.0, sigma = dir_s > 0.0 ? 1.0 : -1.0;
    const double q = dir_z / std::fabs(dir_s);   // the ray's rise per unit of horizontal travel
    const double z0 = height(s0);
    // Horizontal travel until the ray leaves the band |z - base| <= A where the surface lies, or the water.
    double tau_end = sigma > 0.0 ? s_hi - s0 : s0 - s_lo;
    if (q < 0.0) tau_end = std::min(tau_end, (z0 - (base - a)) / -q);
    if (q > 0.0) tau_end = std::min(tau_end, (base + a - z0) / q);
    // g(tau) = side (ray z - surface z) > 0 while the ray stays on its side; g(0) = 0 and |g''| <= A k^2, so
    // from any tau, g stays positive for steps below the root of g + g' step - A k^2 step^2 / 2 = 0 (Taylor
    // with the bound). These safe steps never pass a crossing and converge quadratically onto one.
    double tau = 0.0, g = 0.0, gp = side * (q - sigma * slope(s0));
    if (!(gp > 0.0)) return true;   // tangent to the surface, or already across it
    for (int it = 0; it < 10000; ++it) {
        tau += (gp + std::sqrt(std::max(gp * gp + 2.0 * curvature * g, 0.0))) / curvature;
        if (tau >= tau_end) return false;
        const double s = s0 + sigma * tau;
        g = side * (z0 + q * tau - height(s));
        if (g <= 1e-12) return true;
        gp = side * (q - sigma * slope(s));
    }
    return true;   // still closing in on a tangency: count it as met
}

std::size_t sine_profile_segments(const SinePlane& plane, double bin_w) {
    // Sampling error: a strip's flux is spread uniformly over its image, exact for a linear map, so the
    // error is second order in the strip width (measured: each halving divides it by ~4, folds and shadow
    // edges included). 256 strips per bin and at least 4096 per wavelength keep every bin within ~2e-6
    // of the converged value on the sine scenes, past the focus and at 80 degrees (the worst case;
    // tests/test_analytic_truth.cpp, SamplingConverges), i.e. far below 1e-3, in ~8 ms for 256 bins.
    const double wavelength = 2.0 * 3.14159265358979323846 / plane.k;
    const double strip = std::min(bin_w / 256.0, wavelength / 4096.0);
    const double n = std::ceil((plane.s_hi - plane.s_lo) / strip);
    return static_cast<std::size_t>(std::clamp(n, 1024.0, 6.4e7));
}

bool sine_profile(const SinePlane& p, double lo, double hi, int bins, std::size_t segments,
                  std::vector<double>& flux, std::string& reason) {
    if (segments == 0) segments = sine_profile_segments(p, (hi - lo) / bins);
    StripHistogram histogram(lo, hi, bins);
    // March along the direction the light travels. Shadowing: the incoming ray to the surface point at
    // tau rises by cot(t) per unit of horizontal distance back towards the light, so it clears every crest
    // upstream iff G(tau) = h(tau) + tau cot(t) is at least its maximum over all upstream points. The lit
    // points are the running-maximum records of G: an exact test, O(1) per strip. A back-facing point
    // (d . n >= 0) has G' <= 0 and is never a record. At normal incidence nothing is shadowed.
    const double direction = p.light_s >= 0.0 ? 1.0 : -1.0;
    const double start = direction > 0.0 ? p.s_lo : p.s_hi, length = p.s_hi - p.s_lo;
    const bool oblique = std::fabs(p.light_s) > 1e-12;
    const double cot = oblique ? -p.light_z / std::fabs(p.light_s) : 0.0;
    auto s_at = [&](double tau) { return start + direction * tau; };
    auto G = [&](double tau) { return p.height(s_at(tau)) + tau * cot; };
    auto G_slope = [&](double tau) { return direction * p.slope(s_at(tau)) + cot; };
    // Re-hit checks (exact, per ray) are needed only for rays descending (or, reflected, rising) less
    // steeply than the steepest surface slope A k; they are done every `check_every` strips, i.e. at least
    // 4096 rays per wavelength, so only a re-hitting set narrower than that (carrying < 3e-4 of a period's
    // flux) could pass unnoticed.
    const double max_slope = std::fabs(p.amplitude) * p.k;
    const double wavelength = 2.0 * 3.14159265358979323846 / p.k;
    const std::size_t check_every =
        std::max<std::size_t>(1, static_cast<std::size_t>(wavelength / 4096.0 / (length / segments)));
    auto strip_at = [&](double tau) { return p.trace(s_at(tau)); };
    // Whether the ray entering (lit) at tau can be followed to the floor; else the reason.
    auto followable = [&](double tau, const SinePlane::Strip& st, bool check) {
        const char* why = nullptr;
        if (st.tir) why = "total internal reflection where the light enters (index below 1)";
        else if (!(st.dir_z < 0.0)) why = "a refracted ray travels upwards";
        else if (check && std::fabs(st.dir_z) <= max_slope * std::fabs(st.dir_s) &&
                 p.meets_surface_again(s_at(tau), st.dir_s, st.dir_z, true))
            why = "a refracted ray meets the surface again from below before the floor";
        else if (check && p.fresnel && std::fabs(st.refl_z) <= max_slope * std::fabs(st.refl_s) &&
                 p.meets_surface_again(s_at(tau), st.refl_s, st.refl_z, false))
            why = "a Fresnel-reflected ray meets the surface again";
        if (!why) return true;
        char where[64];
        std::snprintf(where, sizeof where, " (at s = %.6g m)", s_at(tau));
        reason = std::string(why) + where;
        return false;
    };
    auto add = [&](double tau_a, const SinePlane::Strip& a, double tau_b, const SinePlane::Strip& b) {
        histogram.add(a.landing, b.landing, 0.5 * (a.density + b.density) * (tau_b - tau_a));   // trapezoid
    };
    // Bisection for the first tau in (lo_tau, hi_tau] where pred holds (pred false at lo_tau, true at hi_tau).
    auto first_true = [](double lo_tau, double hi_tau, auto pred) {
        for (int it = 0; it < 60 && hi_tau - lo_tau > 1e-15; ++it) {
            const double mid = 0.5 * (lo_tau + hi_tau);
            (pred(mid) ? hi_tau : lo_tau) = mid;
        }
        return hi_tau;
    };

    double tau_prev = 0.0, record = G(0.0);
    SinePlane::Strip prev = strip_at(0.0);
    bool prev_lit = prev.front;   // the upstream edge sees the light unobstructed
    if (prev_lit && !followable(0.0, prev, true)) return false;
    for (std::size_t i = 1; i <= segments; ++i) {
        const double tau = length * static_cast<double>(i) / static_cast<double>(segments);
        const SinePlane::Strip cur = strip_at(tau);
        const double g = cur.z + tau * cot;   // G(tau) without a second sine
        const bool lit = cur.front && (!oblique || g >= record);
        if (lit && !followable(tau, cur, i % check_every == 0 || i == segments)) return false;
        if (prev_lit && lit) {
            add(tau_prev, prev, tau, cur);
        } else if (prev_lit) {
            // Lit -> shadowed: G peaked inside the strip, at the crest point whose tangent ray is the
            // shadow's edge; the strip is lit up to it.
            const double peak = G_slope(tau) > 0.0
                                    ? tau_prev
                                    : first_true(tau_prev, tau, [&](double t) { return G_slope(t) <= 0.0; });
            if (peak > tau_prev) add(tau_prev, prev, peak, strip_at(peak));
            record = std::max(record, G(peak));
        } else if (lit) {
            // Shadowed -> lit: G climbs back to the record where the shadow's edge meets the surface.
            const double edge =
                first_true(tau_prev, tau, [&](double t) { return G_slope(t) > 0.0 && G(t) >= record; });
            const SinePlane::Strip at_edge = strip_at(edge);
            if (!followable(edge, at_edge, true)) return false;
            add(edge, at_edge, tau, cur);
        }
        record = std::max(record, g);
        tau_prev = tau;
        prev = cur;
        prev_lit = lit;
    }
    flux = histogram.flux();
    return true;
}

namespace {

bool near(double a, double b, double tol = 1e-9) { return std::fabs(a - b) <= tol; }

}  // namespace

AnalyticTruth analytic_truth(const FrameGeometry& frame, const ReceiverChart& chart) {
    AnalyticTruth out;
    auto fail = [&out](const std::string& why) {
        out.reason = why;
        return out;
    };
    const Scene& scene = *frame.scene;
    if (scene.lights.size() != 1)
        return fail("the closed form needs exactly one light, the scene has " + std::to_string(scene.lights.size()));
    const Light& light = scene.lights[0];
    if (light.type != LightType::Directional) return fail("the light is not directional");
    if (scene.medium.present) return fail("a participating medium fills the scene");
    if (scene.max_specular_depth < 1) return fail("max_specular_depth is below 1: no refracted light is followed");
    const int receiver_index = scene.receiver.object_index;
    const ObjectInstance* water = nullptr;
    for (const ObjectInstance& inst : frame.objects) {
        if (inst.object_index == receiver_index) continue;
        if (water) return fail("objects other than one height field and the receiver ('" + inst.object->name + "')");
        water = &inst;
    }
    if (!water) return fail("no object besides the receiver");
    const Object& wo = *water->object;
    const HeightFieldDesc& desc = wo.heightfield;
    if (wo.shape == ShapeType::Sphere) {
        const Object& ro = scene.receiver_object();
        if (ro.shape != ShapeType::Plane || ro.material.type != MaterialType::Diffuse)
            return fail("the receiver '" + ro.name + "' is not a diffuse plane");
        const double u_len = glm::length(ro.u), v_len = glm::length(ro.v);
        if (!near(ro.u.z, 0.0, 1e-9 * u_len) || !near(ro.v.z, 0.0, 1e-9 * v_len))
            return fail("the receiver is not horizontal");
        return ball_lens_truth(frame, chart, *water);
    }
    if (wo.shape != ShapeType::HeightField || !water->heightfield)
        return fail("'" + wo.name + "' is not a height field");
    if (desc.generator != HeightGenerator::Sine && desc.generator != HeightGenerator::Gaussian)
        return fail("the height field '" + wo.name + "' is neither a sine nor a Gaussian bump");
    if (wo.material.type != MaterialType::Dielectric) return fail("'" + wo.name + "' is not a dielectric");
    if (wo.material.dispersion != 0.0) return fail("the water is dispersive: its index varies over the band");
    const Object& ro = scene.receiver_object();
    if (ro.shape != ShapeType::Plane) return fail("the receiver '" + ro.name + "' is not a plane");
    if (ro.material.type != MaterialType::Diffuse) return fail("the receiver '" + ro.name + "' is not diffuse");
    {
        const double u_len = glm::length(ro.u), v_len = glm::length(ro.v);
        if (!near(ro.u.z, 0.0, 1e-9 * u_len) || !near(ro.v.z, 0.0, 1e-9 * v_len))
            return fail("the receiver is not horizontal");
    }
    if (desc.generator == HeightGenerator::Gaussian) return radial_bump_truth(frame, chart, *water);

    // The sine's direction, as the generator normalises it, must run along an edge of the water's
    // rectangle, so that its extent along the sine is the same at every point across it.
    const double len = glm::length(desc.direction);
    const glm::dvec2 d = len > 0.0 ? desc.direction / len : glm::dvec2(1.0, 0.0);
    if (!near(std::fabs(d.x), 1.0) && !near(std::fabs(d.y), 1.0))
        return fail("the sine's direction is not along an edge of the water's rectangle");
    const glm::dvec2 w(-d.y, d.x);   // across the sine
    const glm::dvec3 l = glm::normalize(light.direction);
    if (!near(l.x * w.x + l.y * w.y, 0.0)) return fail("the light is not in the sine's vertical plane");
    if (!(l.z < 0.0)) return fail("the light does not travel downwards");
    const double u_len = glm::length(ro.u), v_len = glm::length(ro.v);
    if (!near(ro.u.z, 0.0, 1e-9 * u_len) || !near(ro.v.z, 0.0, 1e-9 * v_len))
        return fail("the receiver is not horizontal");
    if (!near(glm::dot(ro.u, ro.v), 0.0, 1e-9 * u_len * v_len)) return fail("the receiver is not a rectangle");
    const double du = d.x * ro.u.x + d.y * ro.u.y, dv = d.x * ro.v.x + d.y * ro.v.y;
    const bool along_u = near(std::fabs(du), u_len, 1e-9 * u_len);
    if (!along_u && !near(std::fabs(dv), v_len, 1e-9 * v_len))
        return fail("neither the receiver's u nor its v is parallel to the sine's direction");

    SinePlane p;
    p.amplitude = desc.amplitude;
    p.k = 2.0 * 3.14159265358979323846 / desc.wavelength;
    p.offset = desc.phase + p.k * desc.speed * frame.time;   // as the generator (heightfield.cpp)
    p.base = desc.base_height;
    const glm::dvec2 lo = water->heightfield->origin, hi = lo + water->heightfield->extent();
    const double sa = d.x * lo.x + d.y * lo.y, sb = d.x * hi.x + d.y * hi.y;
    p.s_lo = std::min(sa, sb);
    p.s_hi = std::max(sa, sb);
    const double wa = w.x * lo.x + w.y * lo.y, wb = w.x * hi.x + w.y * hi.y;
    const double w_lo = std::min(wa, wb), w_hi = std::max(wa, wb);
    p.ior = wo.material.ior;
    p.absorption = wo.material.absorption;
    p.fresnel = scene.fresnel;
    p.light_s = l.x * d.x + l.y * d.y;
    p.light_z = l.z;
    p.irradiance = light.irradiance;
    p.floor_z = ro.center.z;
    if (!(p.floor_z < p.base - std::fabs(p.amplitude))) return fail("the receiver is not below the water");

    // The receiver's chart: `along` is its axis parallel to the sine, `across` the other.
    const glm::dvec3& along = along_u ? ro.u : ro.v;
    const glm::dvec3& across = along_u ? ro.v : ro.u;
    const int n_along = along_u ? chart.width() : chart.height(), n_across = along_u ? chart.height() : chart.width();
    const double c_s = d.x * ro.center.x + d.y * ro.center.y, a_s = d.x * along.x + d.y * along.y;
    const double c_w = w.x * ro.center.x + w.y * ro.center.y, b_w = w.x * across.x + w.y * across.y;
    std::vector<double> flux;
    std::string reason;
    if (!sine_profile(p, c_s - 0.5 * std::fabs(a_s), c_s + 0.5 * std::fabs(a_s), n_along, 0, flux, reason))
        return fail(reason);

    // Rays stay in their vertical plane, so across the sine the lit band is the water's extent: bin (i, j)
    // receives the profile's flux per unit width times its overlap with [w_lo, w_hi], over its area.
    out.receiver = Image(chart.width(), chart.height(), 1);
    for (int j = 0; j < n_across; ++j) {
        const double b0 = c_w + (static_cast<double>(j) / n_across - 0.5) * b_w;
        const double b1 = c_w + (static_cast<double>(j + 1) / n_across - 0.5) * b_w;
        const double overlap = std::max(0.0, std::min(std::max(b0, b1), w_hi) - std::max(std::min(b0, b1), w_lo));
        for (int i = 0; i < n_along; ++i) {
            const double f = flux[static_cast<std::size_t>(a_s > 0.0 ? i : n_along - 1 - i)];
            const int x = along_u ? i : j, y = along_u ? j : i;
            out.receiver.at(x, y) = static_cast<float>(f * overlap / chart.bin_area(x, y));
        }
    }
    out.available = true;
    out.kind = "analytic:sine";
    return out;
}

}  // namespace caustics
