// caustic_mapping: Shah, Konttinen, Pattanaik 2007 (docs/papers.md), on the shared software raster.
// Per frame, as the paper's render passes (Sec. III.B):
//   1. receivers (diffuse objects) -> positions texture from the light (map x map; a six-face cube map
//      for point lights whose receivers leave one frustum, Sec. III.F);
//   2. specular objects -> front positions/normals at grid x grid (one vertex per texel); closed
//      dielectrics also -> back-face positions/normals (Wyman's double-surface refraction);
//   3. per grid vertex: refract (or reflect), estimate the exit point against the back-face texture and
//      the receiver point against the receivers' texture (estimator.hpp), weight (Eq. 6 or radiometric,
//      Eq. 7 absorption), splat into the caustic map (additive; footprints in splats.hpp), optional
//      low-pass;
//   4. receiver map and camera view: project each point into the light view, depth test against the
//      receivers' texture, read the caustic map, divide by the receiver area of a texel -> irradiance
//      (lookup.hpp: every point is looked up on the fly, in every render).
#include "caustic_mapping.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "elliptic_splats.hpp"
#include "estimator_lanes.hpp"
#include "lookup.hpp"
#include "splats.hpp"
#include <caustics/util/timing.hpp>

namespace caustics::caustic_mapping {

void Counters::add(const Counters& o) {
    covered += o.covered, grazing += o.grazing, null_value += o.null_value, null_exit += o.null_exit;
    not_converged += o.not_converged, oscillating += o.oscillating, bisection += o.bisection;
    bad_derivative += o.bad_derivative, tir += o.tir, nonfinite += o.nonfinite, lookups += o.lookups;
    lost_outside += o.lost_outside, missed += o.missed;
}

namespace {

// Refraction of unit I through unit N facing against I (dot(I, N) < 0), eta = n_from / n_to.
bool refract(const glm::dvec3& I, const glm::dvec3& N, double eta, glm::dvec3& T, double& cos_i, double& cos_t) {
    cos_i = -glm::dot(I, N);
    const double k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if (k < 0.0) return false;
    cos_t = std::sqrt(k);
    T = glm::normalize(eta * I + (eta * cos_i - cos_t) * N);
    return true;
}

// Unpolarised Fresnel transmittance from index n1 into n2.
double fresnel_t(double cos_i, double cos_t, double n1, double n2) {
    const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}

class CausticMapping final : public Method {
public:
    explicit CausticMapping(const ParamSet& p) : base_(settings_from(p)), s_(base_) {}

    Capability capabilities(const Scene& scene) const override;
    void update(const FrameGeometry& frame) override {
        s_ = frame_settings(frame, base_);   // past the first focus: the fold regime's grid and map
        batches_ = build_batches(frame, s_.grid);
        frame_ = &frame;
        frame_index_ = frame.frame;
    }
    CausticOutput render(const FrameGeometry& frame, const RenderRequest& request) override;
    AccuracyClaim accuracy_claim(const FrameGeometry& frame) const override { return claim_for(frame, base_); }

private:
    void draw_gbuffers(const FrameGeometry& frame, const Light& light, Counters& c, std::int64_t& clipped);
    void trace(const Scene& scene, const Light& light, Counters& total);
    // One grid texel's light on its way through trace(): its flux, weight so far and current ray.
    struct TracedTexel {
        std::size_t i;
        const Batch* batch;
        double flux, weight;
        glm::dvec3 v, origin, dir;
        bool alive;
    };
    // A row's texels and the estimator's batches (scratch reused across rows).
    struct TraceRow {
        std::vector<TracedTexel> texels;
        std::vector<EstimateRay> rays;
        std::vector<EstimateResult> results;
        std::vector<glm::dvec3> normals;
        std::vector<std::size_t> which;
    };
    // Light carried by grid texel (x, y): E0 * texel area or I * texel solid angle.
    double texel_flux(const Light& light, int x, int y) const;
    // trace()'s passes over one row: the refraction (or reflection) at the front face of every covered
    // texel, the exit points of closed dielectrics and the refraction out, the receiver points and the
    // landing.
    void enter_row(int y, const Scene& scene, const Light& light, double paper_scale, TraceRow& row, Counters& c) const;
    void exit_row(const Scene& scene, TraceRow& row, Counters& c) const;
    void land_row(TraceRow& row, Counters& c);

    Settings base_;   // the parameters
    Settings s_;      // this frame's: base_, or the fold regime's grid and map (frame_settings)
    std::vector<Batch> batches_;
    const FrameGeometry* frame_ = nullptr;
    int frame_index_ = -1;

    LightProjection object_view_;
    GBuffer front_, back_;
    bool have_back_ = false;
    PositionsTexture receivers_;    // faces + G-buffers of the receivers
    PositionsTexture back_tex_;     // the back faces of closed dielectrics (one face, grid x grid)
    GBufferRaster raster_;
    SplatRaster splatter_;
    EllipticSplatter elliptic_splatter_;
    std::vector<FaceSplat> landing_;   // per grid texel: where its light lands (value 0: nowhere)
    std::vector<std::vector<Splat>> face_splats_;
    std::vector<std::vector<EllipticSplat>> face_ellipses_;
    std::vector<Image> caustic_;    // per face: flux per texel [W]
    double radius_used_ = 0.0;
    ReceiverScratch receiver_scratch_;   // refilled by every render
    LookupMask lookup_mask_;             // rebuilt by every render that looks up
};

Capability CausticMapping::capabilities(const Scene& scene) const {
    if (scene.lights.size() != 1) return Capability::no("needs exactly one light (directional or point)");
    if (scene.medium.present && (scene.medium.absorption > 0.0 || scene.medium.scattering > 0.0 || scene.medium.ior != 1.0))
        return Capability::no("participating media are not supported");
    int specular = 0;
    Bounds3 bounds;
    for (const Object& o : scene.objects) {
        if (!o.material.is_specular()) continue;
        ++specular;
        if (o.material.type == MaterialType::Dielectric && o.material.dispersion > 0.0)
            return Capability::no("dispersion is not supported (one index per dielectric)");
        if (o.shape == ShapeType::Sphere) {
            bounds.extend(o.center - glm::dvec3(o.radius));
            bounds.extend(o.center + glm::dvec3(o.radius));
        } else if (o.shape == ShapeType::Mesh) {
            for (const glm::vec3& p : o.mesh.positions) bounds.extend(glm::dvec3(p));
        }
    }
    if (specular == 0) return Capability::no("the scene has no specular (dielectric or mirror) object");
    const Light& l = scene.lights[0];
    if (l.type == LightType::Point && bounds.valid() && glm::all(glm::greaterThan(l.position, bounds.lo)) &&
        glm::all(glm::lessThan(l.position, bounds.hi)))
        return Capability::no("a point light inside a specular object's bounds is not supported");
    return Capability::yes();
}

void CausticMapping::draw_gbuffers(const FrameGeometry& frame, const Light& light, Counters& c, std::int64_t& clipped) {
    Bounds3 spec, recv;
    bool have_double = false;
    for (const Batch& b : batches_) (b.role == Role::Receiver ? recv : spec).extend(b.bounds);
    for (const Batch& b : batches_) have_double |= b.role == Role::DoubleSurface;
    const bool point = light.type == LightType::Point;
    // The object's grid: a frustum fitted to the specular objects (one vertex per texel).
    if (point) {
        if (!fit_perspective(light.position, spec, s_.grid, s_.grid, object_view_, 85.0))
            throw std::runtime_error("caustic_mapping: the specular objects do not fit one light frustum");
    } else {
        object_view_ = fit_orthographic(light.direction, spec, s_.grid, s_.grid);
    }
    // Front faces of every specular object, and back faces of closed dielectrics (one set-up for both).
    front_.clear(s_.grid, s_.grid);
    if (have_double) back_.clear(s_.grid, s_.grid);
    for (const Batch& b : batches_) {
        if (b.role == Role::Receiver) continue;
        if (b.role == Role::DoubleSurface)
            clipped += raster_.draw_front_back(object_view_, b.triangles(), DepthTest::Less, front_, back_).clipped;
        else
            clipped += raster_.draw(object_view_, b.triangles(), CullMode::None, DepthTest::Less, front_).clipped;
    }
    have_back_ = have_double;
    if (have_double) {
        back_tex_.faces.assign(1, object_view_);
        back_tex_.maps.resize(1);
        std::swap(back_tex_.maps[0], back_);
        back_tex_.cube = false;
        back_tex_.bilinear = s_.bilinear;
    }
    // Receivers' positions texture: one frustum or a cube map. Its window covers the receivers (with room
    // for the extrapolated rim) and also the specular objects seen from the light: the estimator's first
    // lookup is the light ray through the specular vertex itself (d = 0) and its later lookups move along
    // the refracted ray towards the landing point, so under tilted light they fall beside the receivers
    // by the refracted ray's displacement. A window fitted to the receivers alone returns the null value
    // there and the light that lands near the downstream edge is lost (Sec. III.D's null-value case).
    receivers_.bilinear = s_.bilinear;
    receivers_.faces.clear();
    const int rim = s_.extend < 0 ? kRimTexels : std::min(s_.extend, s_.map / 8);   // at most an eighth of the map
    const double margin = std::max(0.01, rim / static_cast<double>(s_.map - 2 * rim));
    if (!point) {
        receivers_.faces.push_back(receivers_view(light.direction, recv, spec, s_.map, margin));
        receivers_.cube = false;
    } else {
        // off: one frustum, clamped to 80 degrees off-axis (receivers beyond it get no caustic: counted).
        LightProjection single;
        const bool fits = s_.cube != CubeMode::On &&
                          receivers_view(light.position, recv, spec, s_.map, s_.cube == CubeMode::Off ? 80.0 : 60.0,
                                         margin, s_.cube == CubeMode::Off, single);
        receivers_.cube = !fits;
        if (fits) receivers_.faces.push_back(single);
        else for (const LightProjection& f : cube_faces(light.position, s_.map)) receivers_.faces.push_back(f);
    }
    receivers_.maps.resize(receivers_.faces.size());
    for (std::size_t f = 0; f < receivers_.faces.size(); ++f) {
        receivers_.maps[f].clear(s_.map, s_.map, DepthTest::Less, false);   // positions and depth only
        for (const Batch& b : batches_)
            if (b.role == Role::Receiver)
                clipped += raster_.draw(receivers_.faces[f], b.triangles(), CullMode::None, DepthTest::Less,
                                        receivers_.maps[f]).clipped;
        extend_positions(receivers_.maps[f], s_.extend < 0 ? s_.map : std::min(s_.extend, s_.map / 8));
    }
    (void)frame;
    (void)c;
}

double CausticMapping::texel_flux(const Light& light, int x, int y) const {
    const bool point = light.type == LightType::Point;
    const double strength = point ? light.intensity : light.irradiance;
    return strength * (point ? object_view_.texel_solid_angle(x + 0.5, y + 0.5) : object_view_.texel_area());
}

void CausticMapping::trace(const Scene& scene, const Light& light, Counters& total) {
    const int g = s_.grid;
    // Eq. 6 needs V (covered texels) and, to carry units, the total flux through them.
    double paper_scale = 0.0;
    if (s_.flux == FluxWeight::Paper) {
        double sum = 0.0;
        std::int64_t covered = 0;
        for (int y = 0; y < g; ++y)
            for (int x = 0; x < g; ++x)
                if (front_.id[front_.index(x, y)] >= 0) {
                    ++covered;
                    sum += texel_flux(light, x, y);
                }
        paper_scale = covered > 0 ? sum / static_cast<double>(covered) : 0.0;
    }
    landing_.assign(static_cast<std::size_t>(g) * g, FaceSplat{0, {glm::vec2(0.0f), 0.0f}});
    tbb::combinable<Counters> counters;
    // A row at a time, in passes: the refraction at the front face of every covered texel, then the exit
    // points' estimates of the whole row (four rays at once: estimator_lanes.hpp), the refraction out,
    // the receiver points' estimates, and the landing. Each texel's operations are those of one texel at
    // a time, in the same order; only the counters (integer sums) are added in another order.
    tbb::parallel_for(tbb::blocked_range<int>(0, g, 4), [&](const tbb::blocked_range<int>& rows) {
        Counters& c = counters.local();
        TraceRow row;
        row.texels.reserve(static_cast<std::size_t>(g));
        for (int y = rows.begin(); y != rows.end(); ++y) {
            enter_row(y, scene, light, paper_scale, row, c);
            exit_row(scene, row, c);
            land_row(row, c);
        }
    });
    counters.combine_each([&](const Counters& c) { total.add(c); });
}

void CausticMapping::enter_row(int y, const Scene& scene, const Light& light, double paper_scale, TraceRow& row,
                               Counters& c) const {
    const bool point = light.type == LightType::Point;
    row.texels.clear();
    for (int x = 0; x < s_.grid; ++x) {
        const std::size_t i = front_.index(x, y);
        const int id = front_.id[i];
        if (id < 0) continue;
        ++c.covered;
        const Batch& b = batches_[static_cast<std::size_t>(id)];
        const Material& mat = *b.material;
        const glm::dvec3 v(front_.position[i]);
        glm::dvec3 n(front_.normal[i]);
        const glm::dvec3 L = point ? glm::normalize(v - light.position) : glm::normalize(light.direction);
        if (b.role != Role::DoubleSurface && glm::dot(n, L) > 0.0) n = -n;   // open surfaces: either side
        double weight = 1.0, cos_i = -glm::dot(L, n), cos_t = 0.0;
        if (!(cos_i > 0.0)) {   // interpolated normal facing away at a silhouette
            ++c.grazing;
            continue;
        }
        const double flux = s_.flux == FluxWeight::Paper ? paper_scale * cos_i : texel_flux(light, x, y);
        glm::dvec3 dir;
        if (b.role == Role::Mirror) {
            dir = L + 2.0 * cos_i * n;
        } else {
            if (!refract(L, n, 1.0 / mat.ior, dir, cos_i, cos_t)) {
                ++c.tir;
                continue;
            }
            if (scene.fresnel) weight *= fresnel_t(cos_i, cos_t, 1.0, mat.ior);
        }
        row.texels.push_back({i, &b, flux, weight, v, v, dir, true});
    }
}

void CausticMapping::exit_row(const Scene& scene, TraceRow& row, Counters& c) const {
    // Exit points: the same estimator against the back-face texture, started from the front-to-back
    // distance of each texel (Wyman's d_V).
    row.rays.clear();
    row.which.clear();
    for (std::size_t k = 0; k < row.texels.size(); ++k) {
        const TracedTexel& t = row.texels[k];
        if (t.batch->role != Role::DoubleSurface) continue;
        double start = s_.estimator.d0;
        if (back_tex_.maps[0].id[t.i] >= 0) start = glm::length(glm::dvec3(back_tex_.maps[0].position[t.i]) - t.v);
        row.rays.push_back({t.v, t.dir, start});
        row.which.push_back(k);
    }
    row.results.resize(row.rays.size());
    row.normals.resize(row.rays.size());   // the back face's normal at each exit point (the estimate's last lookup)
    estimate_rays(back_tex_, s_.estimator, row.rays.data(), row.rays.size(), row.results.data(), row.normals.data());
    for (std::size_t e_k = 0; e_k < row.which.size(); ++e_k) {
        TracedTexel& t = row.texels[row.which[e_k]];
        const EstimateResult& e = row.results[e_k];
        const glm::dvec3& ne = row.normals[e_k];
        const Material& mat = *t.batch->material;
        c.lookups += e.lookups;
        c.oscillating += e.oscillating, c.bisection += e.bisected, c.bad_derivative += e.bad_derivative;
        c.not_converged += !e.converged;
        t.alive = false;
        if (!e.hit) {
            ++c.null_exit;
            c.nonfinite += e.nonfinite;
            continue;
        }
        const double inside = glm::length(e.point - t.v);
        if (s_.absorption && mat.absorption > 0.0) t.weight *= std::exp(-mat.absorption * inside);   // Eq. 7
        const glm::dvec3 N = glm::dot(t.dir, ne) > 0.0 ? -ne : ne;
        glm::dvec3 out_dir;
        double cos_i = 0.0, cos_t = 0.0;
        if (!refract(t.dir, N, mat.ior, out_dir, cos_i, cos_t)) {
            ++c.tir;
            continue;
        }
        if (scene.fresnel) t.weight *= fresnel_t(cos_i, cos_t, mat.ior, 1.0);
        t.origin = e.point;
        t.dir = out_dir;
        t.alive = true;
    }
}

void CausticMapping::land_row(TraceRow& row, Counters& c) {
    row.rays.clear();
    row.which.clear();
    for (std::size_t k = 0; k < row.texels.size(); ++k) {
        if (!row.texels[k].alive) continue;
        row.rays.push_back({row.texels[k].origin, row.texels[k].dir, s_.estimator.d0});
        row.which.push_back(k);
    }
    row.results.resize(row.rays.size());
    estimate_rays(receivers_, s_.estimator, row.rays.data(), row.rays.size(), row.results.data(), nullptr);
    for (std::size_t e_k = 0; e_k < row.which.size(); ++e_k) {
        const TracedTexel& t = row.texels[row.which[e_k]];
        const EstimateResult& e = row.results[e_k];
        const glm::dvec3 &origin = t.origin, &dir = t.dir;
        double weight = t.weight;
        c.lookups += e.lookups;
        c.oscillating += e.oscillating, c.bisection += e.bisected, c.bad_derivative += e.bad_derivative;
        c.not_converged += e.hit && !e.converged;
        if (!e.hit) {
            // A null value outside the receivers' window: the window holds every receiver's rectangle, so
            // no light ray through the estimate meets a receiver; the light leaves past the receivers'
            // edges (as the exact mapping's rays beyond the floor do), which is not a failure of the
            // estimator. Inside the window a null value is a hole: lost.
            Texel where;
            if (e.null_value && !receivers_.locate(origin + e.d * dir, where)) {
                ++c.missed;
                continue;
            }
            c.null_value += e.null_value;
            c.nonfinite += e.nonfinite;
            continue;
        }
        // Single surfaces (water): attenuation between the surface and the receiver (Sec. III.E).
        const Material& mat = *t.batch->material;
        if (t.batch->role == Role::SingleSurface && s_.absorption && mat.absorption > 0.0)
            weight *= std::exp(-mat.absorption * glm::length(e.point - origin));
        Texel where;
        if (!receivers_.locate(e.point, where)) {
            ++c.lost_outside;
            continue;
        }
        {   // Landed on the extrapolated rim, off every receiver: counted, and still splatted so that the
            // footprints of the light landing just inside an edge stay whole.
            const GBuffer& rg = receivers_.maps[static_cast<std::size_t>(where.face)];
            const int tx = std::min(static_cast<int>(where.px), rg.width - 1), ty = std::min(static_cast<int>(where.py), rg.height - 1);
            if (rg.id[rg.index(tx, ty)] == kExtended) ++c.missed;
        }
        const float value = static_cast<float>(t.flux * weight);
        if (!std::isfinite(value)) {
            ++c.nonfinite;
            continue;
        }
        landing_[t.i] = {where.face, {glm::vec2(static_cast<float>(where.px), static_cast<float>(where.py)), value}};
    }
}

CausticOutput CausticMapping::render(const FrameGeometry& frame, const RenderRequest& request) {
    CausticOutput out;
    const Scene& scene = *frame.scene;
    const Capability cap = capabilities(scene);
    if (!cap.supported) throw std::runtime_error("caustic_mapping: " + cap.reason);
    if (frame_ != &frame || frame_index_ != frame.frame || batches_.size() != frame.objects.size()) update(frame);
    const Light& light = scene.lights[0];
    Counters c;
    std::int64_t clipped = 0;

    Stopwatch clock;
    draw_gbuffers(frame, light, c, clipped);
    out.stages_ms.emplace_back("gbuffers", clock.ms());

    clock.reset();
    trace(scene, light, c);
    out.stages_ms.emplace_back("estimator", clock.ms());

    clock.reset();
    const std::size_t faces = receivers_.faces.size();
    face_splats_.resize(faces);
    // Auto radius: 2.5 grid spacings measured in caustic-map texels (sigma = 0.71 spacing), the spacing
    // being the ratio of the two light-space texel sizes (same eye: tangent sizes for point lights).
    const double ratio = std::sqrt(object_view_.texel_area() / receivers_.faces[0].texel_area());
    radius_used_ = s_.splat_radius > 0.0 ? s_.splat_radius : 2.5 * ratio;
    if (s_.adaptive) radius_used_ = s_.splat_radius > 0.0 ? s_.splat_radius : 1.0;   // the adaptive minimum
    int isolated_splats = 0;
    if (s_.elliptic) {
        face_ellipses_.resize(faces);
        isolated_splats = build_elliptic_splats(landing_, s_.grid, elliptic_sigma(fold_resolution(s_)),
                                                static_cast<float>(radius_used_), face_ellipses_);
    } else {
        isolated_splats = build_splats(landing_, s_.grid, s_.adaptive ? FootprintMode::Adaptive : FootprintMode::Fixed,
                                       static_cast<float>(radius_used_), face_splats_);
    }
    caustic_.resize(faces);
    SplatStats splat_stats;
    for (std::size_t f = 0; f < faces; ++f) {
        if (caustic_[f].width != s_.map || caustic_[f].height != s_.map) {
            caustic_[f] = Image(s_.map, s_.map);
        } else {   // 2.4 MB at map 768: cleared in parallel
            auto& px = caustic_[f].pixels;
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, px.size(), std::size_t{1} << 16),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  std::fill(px.begin() + static_cast<std::ptrdiff_t>(r.begin()),
                                            px.begin() + static_cast<std::ptrdiff_t>(r.end()), 0.0f);
                              });
        }
        const SplatStats st = s_.elliptic ? elliptic_splatter_.draw(face_ellipses_[f], caustic_[f])
                                          : splatter_.draw(face_splats_[f], s_.splat, radius_used_, caustic_[f]);
        splat_stats.splatted += st.splatted, splat_stats.outside += st.outside, splat_stats.nonfinite += st.nonfinite;
        if (s_.lowpass >= 1.0) gaussian_lowpass(caustic_[f], s_.lowpass);
    }
    out.stages_ms.emplace_back("splat", clock.ms());

    LookupCounts looked;
    clock.reset();   // the lookup mask is timed with the first lookup stage that runs
    if (request.receiver || request.camera) lookup_mask_.build(receivers_, caustic_);
    if (request.receiver) {
        const ReceiverChart& chart = *request.receiver;
        const int n = s_.bin_samples > 0 ? s_.bin_samples : auto_bin_samples(receivers_, chart);
        receiver_irradiance(out.receiver, receiver_scratch_, receivers_, caustic_, lookup_mask_, chart, n, s_.depth_bias,
                            looked);
        out.stages_ms.emplace_back("receiver_lookup", clock.ms());
        clock.reset();
    }
    if (request.camera) {
        const CameraGBuffer& gb = *request.camera;
        camera_irradiance(out.camera, receivers_, caustic_, lookup_mask_, gb, s_.depth_bias, looked);
        out.stages_ms.emplace_back("camera_lookup", clock.ms());
    }
    if (s_.debug_maps) {
        Image m = caustic_[0];
        out.debug["caustic_map"] = std::move(m);
    }
    Health& h = out.health;
    h.add("covered_texels", c.covered);
    h.add("null_value", c.null_value);
    h.add("null_exit", c.null_exit);
    h.add("lost_samples", c.null_value + c.null_exit + c.tir + c.grazing + c.lost_outside + splat_stats.outside);
    // Light that lands off every receiver (beyond the window, or on the extrapolated rim): not lost, there
    // is no receiver there.
    h.add("missed_receivers", c.missed);
    h.add("not_converged", c.not_converged);
    h.add("oscillating", c.oscillating);
    h.add("bisection_fallbacks", c.bisection);
    h.add("bad_derivative", c.bad_derivative);
    h.add("total_internal_reflections", c.tir);
    h.add("grazing_texels", c.grazing);
    h.add("splats", splat_stats.splatted);
    h.add("isolated_splats", isolated_splats);   // adaptive footprint with no landed neighbour: minimum size
    h.add("splats_outside_map", splat_stats.outside + c.lost_outside);
    h.add("nonfinite", c.nonfinite + splat_stats.nonfinite);
    h.add("estimator_lookups", c.lookups);
    h.add("lookups_outside_map", looked.outside);
    h.add("shadowed_lookups", looked.shadowed);   // failed the depth test where the map holds caustic flux
    h.add("clipped_triangles", clipped);
    h.add("cube_map", receivers_.cube ? 1 : 0);
    h.add("refined_past_focus", s_.grid != base_.grid || s_.map != base_.map ? 1 : 0);
    return out;
}

}  // namespace

std::unique_ptr<Method> make_caustic_mapping(const ParamSet& p) { return std::make_unique<CausticMapping>(p); }

}  // namespace caustics::caustic_mapping
