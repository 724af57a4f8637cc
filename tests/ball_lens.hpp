#pragma once
// The ball-lens closed form shared by the reference's and the methods' tests: a glass sphere (radius R,
// index n) over a floor, lit by parallel light along -z. The meridional ray entering at height h is
// traced through the sphere exactly (two refractions, no small-angle approximation) to its signed
// landing radius on the floor; where |r(h)| folds (dr/dh = 0) the irradiance has an integrable
// singularity, the caustic.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/scene.hpp>

namespace caustics::test_support {

struct BallLens {
    double radius = 0.5, ior = 1.5;
    double center_z = 1.0;    // sphere centre height
    double distance = 1.0;    // floor below the centre
    double floor_side = 2.0;  // floor plane extent (Object::u, Object::v)
    int bins = 128;           // receiver bins per side

    // Paraxial focus distance from the centre: n R / (2 (n - 1)).
    double paraxial_focus() const { return ior * radius / (2.0 * (ior - 1.0)); }

    Scene scene() const {
        Scene s;
        s.name = "ball_lens";
        Light light;
        light.type = LightType::Directional;
        light.direction = {0.0, 0.0, -1.0};
        light.irradiance = 1.0;
        s.lights.push_back(light);
        Object ball;
        ball.name = "ball";
        ball.shape = ShapeType::Sphere;
        ball.center = {0.0, 0.0, center_z};
        ball.radius = radius;
        ball.material.type = MaterialType::Dielectric;
        ball.material.ior = ior;
        Object floor;
        floor.name = "floor";
        floor.shape = ShapeType::Plane;
        floor.material.type = MaterialType::Diffuse;
        floor.center = {0.0, 0.0, center_z - distance};
        floor.u = {floor_side, 0.0, 0.0};
        floor.v = {0.0, floor_side, 0.0};
        s.objects = {ball, floor};
        s.receiver = {"floor", 1, bins, bins};
        return s;
    }

    // Signed landing radius of the meridional ray at height h (x = h, travelling -z); +inf if it never
    // reaches the floor.
    double landing_radius(double h) const {
        const double cos_i = std::sqrt(1.0 - (h / radius) * (h / radius));
        glm::dvec2 p(h, cos_i * radius);   // entry point (x, z relative to the centre)
        glm::dvec2 d(0.0, -1.0);
        auto refract = [](glm::dvec2 dir, glm::dvec2 nrm, double eta) {   // nrm faces the incoming ray
            const double ci = -glm::dot(dir, nrm);
            const double ct = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - ci * ci)));
            return eta * dir + (eta * ci - ct) * nrm;
        };
        d = refract(d, p / radius, 1.0 / ior);
        p += (-2.0 * glm::dot(p, d)) * d;   // second intersection with the circle
        d = refract(d, -p / radius, ior);
        if (d.y >= 0.0) return std::numeric_limits<double>::infinity();
        return p.x + d.x * (-distance - p.y) / d.y;
    }

    // Radii below r_max where |r(h)| folds, found on a grid of step dh.
    std::vector<double> folds(double dh, double r_max) const {
        std::vector<double> out;
        auto r = [&](double h) { return std::min(std::abs(landing_radius(h)), 1e3); };
        for (double h = dh; h < radius * (1.0 - 1e-6) - dh; h += dh) {
            const double a = r(h - dh), b = r(h), c = r(h + dh);
            if ((b - a) * (c - b) < 0.0 && b < r_max) out.push_back(b);
        }
        return out;
    }
};

}  // namespace caustics::test_support
