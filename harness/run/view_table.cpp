#include <caustics/run/view_table.hpp>

#include <cmath>
#include <stdexcept>

#include <caustics/frame/baseline.hpp>

namespace caustics {
namespace {

const Image* nonempty(const Image& image) { return image.empty() ? nullptr : &image; }

std::pair<int, int> camera_size(const ViewSources& s) {
    return s.gbuffer ? std::make_pair(s.gbuffer->width, s.gbuffer->height) : std::make_pair(-1, -1);
}

// The receiver map: E_c per bin over the receiver chart, against the closed form where the frame has one,
// else the reference, beside the flat interface's map (or the best constant).
ViewSpec receiver_row() {
    ViewSpec v;
    v.name = "receiver";
    v.unit = "W/m^2";
    v.output = [](const CausticOutput& o) { return nonempty(o.receiver); };
    v.size = [](const ViewSources& s) { return std::make_pair(s.chart->width(), s.chart->height()); };
    v.truth = [](const ViewSources& s, ViewTruth& t) {
        if (s.analytic && s.analytic->available) {
            t.maps = {&s.analytic->receiver, nullptr, nullptr};
            t.kind = s.analytic->kind;
        } else if (s.reference) {
            t.maps = {&s.reference->receiver, &s.reference->receiver_replicas, &s.reference->receiver_stderr};
            t.kind = "reference";
        } else {
            return false;
        }
        t.has_baseline = true;
        t.baseline = make_baseline(s.flat ? *s.flat : flat_interface_baseline(*s.geometry, *s.chart), *t.maps.mean);
        return true;
    };
    v.missing_note = "method produced no receiver map";
    v.no_better_note = [](const std::string& kind) { return "no better than the no-caustic baseline (" + kind + ")"; };
    v.baseline_key = "baseline";
    v.primary = true;
    return v;
}

// The camera view: E_c at the pixels whose primary hit is a diffuse receiver (in both the method's G-buffer
// and the reference's), against the reference.
ViewSpec camera_row() {
    ViewSpec v;
    v.name = "camera";
    v.unit = "W/m^2";
    v.output = [](const CausticOutput& o) { return nonempty(o.camera); };
    v.size = camera_size;
    v.read_mask = [](const ViewSources& s) { return s.gbuffer ? &s.gbuffer->covered : nullptr; };
    v.truth = [](const ViewSources& s, ViewTruth& t) {
        if (!s.reference || s.reference->camera.empty() || !s.gbuffer) return false;
        const ReferenceResult& r = *s.reference;
        t.maps = {&r.camera, &r.camera_replicas, &r.camera_stderr};
        t.kind = "reference";
        t.mask = s.gbuffer->covered;
        if (r.camera_covered.size() == t.mask.size())
            for (std::size_t p = 0; p < t.mask.size(); ++p) t.mask[p] &= r.camera_covered[p];
        return true;
    };
    v.missing_note = "method produced no camera view";
    v.empty_note = "camera view: no pixel's primary hit is a diffuse receiver";
    return v;
}

// The volume view: L_v per camera pixel where the medium scatters, against the reference, beside the
// constant radiance over the pixels the reference lights.
ViewSpec camera_volume_row() {
    ViewSpec v;
    v.name = "camera_volume";
    v.unit = "W/(m^2 sr)";
    v.requested = [](const Scene& scene) { return scene_scatters(scene); };
    v.capability = [](const Method& m, const Scene& scene) { return m.volume_capability(scene); };
    v.refusal = "the scene's medium scatters (volume caustics, camera_volume, and extinction along every path): ";
    v.output = [](const CausticOutput& o) { return nonempty(o.camera_volume); };
    v.size = camera_size;
    v.truth = [](const ViewSources& s, ViewTruth& t) {
        if (!s.reference || s.reference->camera_volume.empty()) return false;
        const ReferenceResult& r = *s.reference;
        t.maps = {&r.camera_volume, &r.camera_volume_replicas, &r.camera_volume_stderr};
        t.kind = "reference";
        t.has_baseline = true;
        t.baseline = make_baseline(Image{}, r.camera_volume);
        return true;
    };
    v.missing_note = "method produced no camera_volume view";
    v.no_better_note = [](const std::string&) { return std::string("camera_volume: no better than the constant baseline"); };
    v.baseline_key = "baseline_volume";
    return v;
}

std::deque<ViewSpec>& table() {
    static std::deque<ViewSpec> rows = {receiver_row(), camera_row(), camera_volume_row()};
    return rows;
}

}  // namespace

const std::deque<ViewSpec>& view_table() { return table(); }

void register_view(ViewSpec spec) {
    for (const ViewSpec& v : table())
        if (v.name == spec.name) throw std::invalid_argument("register_view: a view named '" + spec.name + "' exists");
    if (!spec.output) {
        const std::string name = spec.name;
        spec.output = [name](const CausticOutput& o) -> const Image* {
            const auto it = o.views.find(name);
            return it == o.views.end() ? nullptr : nonempty(it->second);
        };
    }
    if (!spec.size) spec.size = camera_size;
    table().push_back(std::move(spec));
}

std::vector<const ViewSpec*> requested_views(const Scene& scene) {
    std::vector<const ViewSpec*> rows;
    for (const ViewSpec& v : view_table())
        if (!v.requested || v.requested(scene)) rows.push_back(&v);
    return rows;
}

std::vector<const ViewSpec*> supported_views(const Method& method, const Scene& scene) {
    std::vector<const ViewSpec*> out;
    if (!method.capabilities(scene).supported) return out;
    for (const ViewSpec* v : requested_views(scene))
        if (!v->capability || v->capability(method, scene).supported) out.push_back(v);
    return out;
}

Capability decide_capability(const Method& method, const Scene& scene) {
    Capability cap = method.capabilities(scene);
    if (!cap.supported) return cap;
    for (const ViewSpec* v : requested_views(scene)) {
        if (!v->capability) continue;
        const Capability c = v->capability(method, scene);
        if (!c.supported) return Capability::no(v->refusal + c.reason);
    }
    return cap;
}

ViewSources view_sources(const SceneFrame& sf, const ReferenceResult* reference, const AnalyticTruth* analytic,
                         const Image* flat) {
    return {&sf.scene(), &sf.geometry(), &sf.chart(), &sf.gbuffer(), reference, analytic, flat};
}

std::int64_t check_views(const CausticOutput& out, const ViewSources& sources, const std::string& method) {
    std::int64_t nonfinite = 0;
    for (const ViewSpec& v : view_table()) {
        const Image* image = v.output(out);
        if (!image) continue;
        const auto [w, h] = v.size(sources);
        if (w < 0) continue;   // size not known without the camera: neither checked nor read
        if (image->width != w || image->height != h || image->channels != 1)
            throw std::runtime_error("method " + method + " returned a " + v.name + " image of " +
                                     std::to_string(image->width) + "x" + std::to_string(image->height) + "x" +
                                     std::to_string(image->channels) + ", expected " + std::to_string(w) + "x" +
                                     std::to_string(h) + "x1");
        const std::vector<std::uint8_t>* mask = v.read_mask ? v.read_mask(sources) : nullptr;
        if (mask && mask->size() != image->pixels.size())
            throw std::runtime_error("view " + v.name + ": its read mask has " + std::to_string(mask->size()) +
                                     " entries for " + std::to_string(image->pixels.size()) + " pixels");
        for (std::size_t p = 0; p < image->pixels.size(); ++p)
            if ((!mask || (*mask)[p]) && !std::isfinite(image->pixels[p])) ++nonfinite;
    }
    return nonfinite;
}

std::vector<EvaluatedView> evaluate_views(const CausticOutput& out, const ViewSources& sources, bool radiometric) {
    std::vector<EvaluatedView> views;
    for (const ViewSpec* v : requested_views(*sources.scene)) {
        const Image* image = v->output(out);
        ViewTruth t;
        if (!image || !v->truth || !v->truth(sources, t)) continue;
        EvaluatedView e;
        e.spec = v;
        e.errors = measure_view(*image, t.maps, t.mask.empty() ? nullptr : &t.mask, radiometric,
                                t.has_baseline ? &t.baseline.map : nullptr);
        e.truth_kind = t.kind;
        e.baseline_kind = t.baseline.kind;
        e.has_baseline = t.has_baseline;
        e.exact_truth = t.maps.exact();
        views.push_back(std::move(e));
    }
    return views;
}

ClaimJudgement judge_claim(const AccuracyClaim& claim, double error, double baseline_error) {
    ClaimJudgement j;
    j.bound = claim.bound(baseline_error);
    j.met = error <= j.bound;
    return j;
}

}  // namespace caustics
