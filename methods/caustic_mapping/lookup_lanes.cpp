#include "lookup_lanes.hpp"

#include "simd.hpp"

namespace caustics::caustic_mapping {
namespace {

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "project_row reads a row of glm::vec3 as packed floats");

// Where the lanes write (a RowLanes' arrays) with the view's texel scales: put() stores point i's
// view-space coordinates, 1 / depth and texel coordinates.
struct LaneWriter {
    double *vx, *vy, *vz, *inv, *px, *py;
    double x0, y1, sx, sy;
    LaneWriter(const ViewProjection& view, RowLanes& r)
        : vx(r.vx.data()), vy(r.vy.data()), vz(r.vz.data()), inv(r.inv_depth.data()), px(r.px.data()),
          py(r.py.data()), x0(view.x0), y1(view.y1), sx(view.sx), sy(view.sy) {}
    template <bool kPerspective>
    void put(int i, double x, double y, double z) const {
        vx[i] = x, vy[i] = y, vz[i] = z;
        texel_coordinates<kPerspective>(x0, y1, sx, sy, x, y, z, inv[i], px[i], py[i]);
    }
};

template <bool kPerspective>
inline void project_points(const ViewProjection& view, const glm::vec3* p, int n, const LaneWriter& w) {
    const double ex = view.eye.x, ey = view.eye.y, ez = view.eye.z;
    const double rx = view.right.x, ry = view.right.y, rz = view.right.z;
    const double ux = view.up.x, uy = view.up.y, uz = view.up.z;
    const double fx = view.forward.x, fy = view.forward.y, fz = view.forward.z;
    const float* q = reinterpret_cast<const float*>(p);
#pragma omp simd
    for (int i = 0; i < n; ++i) {
        const double dx = static_cast<double>(q[3 * i]) - ex, dy = static_cast<double>(q[3 * i + 1]) - ey,
                     dz = static_cast<double>(q[3 * i + 2]) - ez;
        w.put<kPerspective>(i, dx * rx + dy * ry + dz * rz, dx * ux + dy * uy + dz * uz, dx * fx + dy * fy + dz * fz);
    }
}

template <bool kPerspective>
inline void project_steps(const glm::dvec3& left, const glm::dvec3& step, int n, const LaneWriter& w) {
#pragma omp simd
    for (int a = 0; a < n; ++a) {
        const double s = a + 0.5;
        w.put<kPerspective>(a, left.x + s * step.x, left.y + s * step.y, left.z + s * step.z);
    }
}

}  // namespace

CAUSTICS_AVX2_CLONES
void project_row(const ViewProjection& view, bool perspective, const glm::vec3* p, int n, RowLanes& r) {
    if (perspective) project_points<true>(view, p, n, LaneWriter(view, r));
    else project_points<false>(view, p, n, LaneWriter(view, r));
}

CAUSTICS_AVX2_CLONES
void project_samples(const ViewProjection& view, bool perspective, const glm::dvec3& left, const glm::dvec3& step,
                     int n, RowLanes& r) {
    if (perspective) project_steps<true>(left, step, n, LaneWriter(view, r));
    else project_steps<false>(left, step, n, LaneWriter(view, r));
}

}  // namespace caustics::caustic_mapping
