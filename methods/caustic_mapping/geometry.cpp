#include "geometry.hpp"

#include <algorithm>
#include <cmath>

namespace caustics::caustic_mapping {

Role role_of(const Object& o) {
    switch (o.material.type) {
        case MaterialType::Diffuse: return Role::Receiver;
        case MaterialType::Mirror: return Role::Mirror;
        case MaterialType::Dielectric:
            return (o.shape == ShapeType::HeightField || o.shape == ShapeType::Plane) ? Role::SingleSurface
                                                                                       : Role::DoubleSurface;
    }
    return Role::Receiver;
}

TriangleMesh tessellate_sphere(const glm::dvec3& center, double radius, int slices) {
    slices = std::max(slices, 8);
    const int stacks = std::max(slices / 2, 4);
    TriangleMesh m;
    for (int j = 0; j <= stacks; ++j) {
        const double theta = M_PI * j / stacks;
        for (int i = 0; i <= slices; ++i) {
            const double phi = 2.0 * M_PI * i / slices;
            const glm::dvec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            m.positions.emplace_back(center + radius * n);
            m.normals.emplace_back(n);
        }
    }
    const unsigned row = static_cast<unsigned>(slices + 1);
    for (unsigned j = 0; j < static_cast<unsigned>(stacks); ++j)
        for (unsigned i = 0; i < static_cast<unsigned>(slices); ++i) {
            const unsigned a = j * row + i, b = a + 1, c = a + row, d = c + 1;
            // Counter-clockwise seen from outside (theta grows downwards from the north pole).
            if (j != 0) m.triangles.push_back({a, c, b});
            if (j + 1 != static_cast<unsigned>(stacks)) m.triangles.push_back({b, c, d});
        }
    return m;
}

TriangleMesh resample_heightfield(const HeightField& hf, int n) {
    n = std::max(n, 2);
    TriangleMesh m;
    const glm::dvec2 ext = hf.extent();
    m.positions.reserve(static_cast<std::size_t>(n) * n);
    m.normals.reserve(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double x = hf.origin.x + ext.x * i / (n - 1), y = hf.origin.y + ext.y * j / (n - 1);
            m.positions.emplace_back(x, y, hf.sample_height(x, y));
            m.normals.emplace_back(hf.sample_normal(x, y));
        }
    for (unsigned j = 0; j + 1 < static_cast<unsigned>(n); ++j)
        for (unsigned i = 0; i + 1 < static_cast<unsigned>(n); ++i) {
            const unsigned a = j * n + i, b = a + 1, c = a + n, d = c + 1;
            m.triangles.push_back({a, b, d});
            m.triangles.push_back({a, d, c});
        }
    return m;
}

std::vector<Batch> build_batches(const FrameGeometry& frame, int grid) {
    std::vector<Batch> batches;
    batches.reserve(frame.objects.size());
    for (std::size_t k = 0; k < frame.objects.size(); ++k) {
        const ObjectInstance& inst = frame.objects[k];
        Batch b;
        b.object = static_cast<int>(k);
        b.role = role_of(*inst.object);
        b.material = &inst.object->material;
        b.bounds = inst.bounds;
        if (inst.analytic_sphere) {
            b.own = tessellate_sphere(inst.object->center, inst.object->radius, std::max(24, grid));
        } else if (inst.heightfield && b.role != Role::Receiver) {
            // Specular height fields: about two vertices per grid texel, at most the field's own samples.
            const int n = std::min(std::max(inst.heightfield->nx, inst.heightfield->ny), 2 * grid + 1);
            b.own = resample_heightfield(*inst.heightfield, n);
        }
        batches.push_back(std::move(b));
    }
    // Pointers last: the vector no longer reallocates.
    for (std::size_t k = 0; k < batches.size(); ++k)
        batches[k].mesh = batches[k].own.empty() ? &frame.objects[k].mesh : &batches[k].own;
    for (Batch& b : batches) {
        if (!b.bounds.valid()) {
            for (const glm::vec3& p : b.mesh->positions) b.bounds.extend(glm::dvec3(p));
        }
    }
    return batches;
}

LightProjection receivers_view(const glm::dvec3& light_dir, const Bounds3& receivers, const Bounds3& specular, int map,
                               double margin) {
    Bounds3 both = receivers;
    if (specular.valid()) both.extend(specular);
    // The union's view places the eye in front of both; its rectangle is then narrowed to the two
    // objects' rectangles (the union box's corners would widen it under tilted light).
    LightProjection p = fit_orthographic(light_dir, both, map, map, margin);
    if (!specular.valid()) return p;
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (const Bounds3* b : {&receivers, &specular}) {
        double xl = 1e300, xh = -1e300, yl = 1e300, yh = -1e300;
        for (int k = 0; k < 8; ++k) {
            const glm::dvec3 v = p.view({(k & 1) ? b->hi.x : b->lo.x, (k & 2) ? b->hi.y : b->lo.y, (k & 4) ? b->hi.z : b->lo.z});
            xl = std::min(xl, v.x), xh = std::max(xh, v.x), yl = std::min(yl, v.y), yh = std::max(yh, v.y);
        }
        const double mx = std::max(margin * (xh - xl), 1e-6), my = std::max(margin * (yh - yl), 1e-6);
        x0 = std::min(x0, xl - mx), x1 = std::max(x1, xh + mx), y0 = std::min(y0, yl - my), y1 = std::max(y1, yh + my);
    }
    p.x0 = x0, p.x1 = x1, p.y0 = y0, p.y1 = y1;
    return p;
}

bool receivers_view(const glm::dvec3& eye, const Bounds3& receivers, const Bounds3& specular, int map,
                    double max_half_angle_deg, double margin, bool clamp, LightProjection& out) {
    if (specular.valid()) {
        Bounds3 both = receivers;
        both.extend(specular);
        if (fit_perspective(eye, both, map, map, out, max_half_angle_deg, margin, false)) return true;
    }
    return fit_perspective(eye, receivers, map, map, out, max_half_angle_deg, margin, clamp);
}

}  // namespace caustics::caustic_mapping
