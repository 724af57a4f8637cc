#pragma once
// RayTracer's batches (ray_tracer.cpp) complete a group's hits on analytic spheres and height fields
// together: one call per object of exact_sphere_hits or HeightField::sample_normals, four hits per AVX2
// vector, with the same bits as exact_sphere_hit and sample_normal one hit at a time.
#include <cstddef>

#include <glm/glm.hpp>

#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/sphere_hits.hpp>
#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

// A group of at most Group hits' sphere and height-field entries, waiting for the rest of their
// completion. An entry whose object is null is done (finish groups the entries by object).
template <int Group>
struct DeferredHits {
    int spheres = 0, fields = 0;
    const Object* sphere[Group];
    const HeightField* field[Group];
    const glm::dvec3 *origin[Group], *dir[Group];
    Hit* sphere_hit[Group];
    Hit* field_hit[Group];
    void add_sphere(const Object* o, const glm::dvec3& org, const glm::dvec3& d, Hit& h) {
        sphere[spheres] = o;
        origin[spheres] = &org, dir[spheres] = &d;
        sphere_hit[spheres++] = &h;
    }
    void add_field(const HeightField* f, Hit& h) {
        field[fields] = f;
        field_hit[fields++] = &h;
    }
    void finish() {
        finish_spheres();
        finish_fields();
    }
    // Each sphere's hits in one call (hit.t holds Embree's distance until then).
    void finish_spheres() {
        for (int i = 0; i < spheres; ++i) {
            const Object* o = sphere[i];
            if (!o) continue;
            double ox[Group], oy[Group], oz[Group], dx[Group], dy[Group], dz[Group], t[Group];
            double px[Group], py[Group], pz[Group], nx[Group], ny[Group], nz[Group];
            Hit* waiting[Group];
            int n = 0;
            for (int j = i; j < spheres; ++j) {
                if (sphere[j] != o) continue;
                waiting[n] = sphere_hit[j];
                ox[n] = origin[j]->x, oy[n] = origin[j]->y, oz[n] = origin[j]->z;
                dx[n] = dir[j]->x, dy[n] = dir[j]->y, dz[n] = dir[j]->z;
                t[n] = sphere_hit[j]->t;
                ++n;
                sphere[j] = nullptr;
            }
            exact_sphere_hits(o->center, o->radius, static_cast<std::size_t>(n),
                              {ox, oy, oz, dx, dy, dz, t, px, py, pz, nx, ny, nz});
            for (int k = 0; k < n; ++k) {
                Hit& h = *waiting[k];
                h.t = t[k];
                h.position = {px[k], py[k], pz[k]};
                h.geometric_normal = h.shading_normal = {nx[k], ny[k], nz[k]};
            }
        }
        spheres = 0;
    }
    // Each field's hits in one call; then, as complete() does for one hit, the shading normal turned to
    // the geometric normal's side.
    void finish_fields() {
        for (int i = 0; i < fields; ++i) {
            const HeightField* f = field[i];
            if (!f) continue;
            double x[Group], y[Group], nx[Group], ny[Group], nz[Group];
            Hit* waiting[Group];
            int n = 0;
            for (int j = i; j < fields; ++j) {
                if (field[j] != f) continue;
                waiting[n] = field_hit[j];
                x[n] = field_hit[j]->position.x, y[n] = field_hit[j]->position.y;
                ++n;
                field[j] = nullptr;
            }
            f->sample_normals(x, y, static_cast<std::size_t>(n), nx, ny, nz);
            for (int k = 0; k < n; ++k) {
                glm::dvec3 shading(nx[k], ny[k], nz[k]);
                if (glm::dot(shading, waiting[k]->geometric_normal) < 0.0) shading = -shading;
                waiting[k]->shading_normal = shading;
            }
        }
        fields = 0;
    }
};

}  // namespace caustics
