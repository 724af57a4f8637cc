#include <caustics/sweep/sweep_spec.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <unordered_set>

#include <caustics/util/errors.hpp>
#include <caustics/util/json_reader.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/scene/scene_catalog.hpp>

namespace caustics {
namespace fs = std::filesystem;
using nlohmann::json;

std::vector<json> expand_axis_values(const json& value, const std::string& file, const std::string& key);

namespace {

void check_keys(const json& object, const std::set<std::string>& valid, const std::string& file,
                const std::string& where) {
    for (const auto& [key, value] : object.items()) {
        if (valid.count(key)) continue;
        std::string list;
        for (const auto& v : valid) list += (list.empty() ? "" : ", ") + v;
        throw InputError(file, where.empty() ? key : where + "." + key, "unknown key; valid keys: " + list);
    }
}

// The report block (scripts/report/report.py reads it): its keys and their kinds.
void check_report(const json& report, const std::string& file) {
    if (!report.is_object())
        throw InputError(file, "report", "must be an object of report settings (time_budget_ms, error_target, "
                                         "noise_ratio_target, paper_settings, image_settings), not " + describe_json(report));
    check_keys(report, {"time_budget_ms", "error_target", "noise_ratio_target", "paper_settings", "image_settings"}, file,
               "report");
    for (const char* key : {"time_budget_ms", "error_target", "noise_ratio_target"})
        if (report.contains(key) && (!report[key].is_number() || !(report[key].get<double>() > 0.0) ||
                                     !std::isfinite(report[key].get<double>())))
            throw InputError(file, std::string("report.") + key, "must be a finite number > 0, not " + describe_json(report[key]));
    for (const char* key : {"paper_settings", "image_settings"}) {
        if (!report.contains(key)) continue;
        const json& settings = report[key];
        const std::string where = std::string("report.") + key;
        if (!settings.is_object())
            throw InputError(file, where, "must be an object {method: {parameter: value}}, not " + describe_json(settings));
        for (const auto& [method, params] : settings.items()) {
            if (!params.is_object())
                throw InputError(file, where + "." + method, "must be an object {parameter: value}, not " + describe_json(params));
            for (const auto& [param, value] : params.items())
                if (value.is_object() || value.is_array())
                    throw InputError(file, where + "." + method + "." + param,
                                     "must be a number, string or boolean, not " + describe_json(value));
        }
    }
}

long long require_integer(const json& v, const std::string& file, const std::string& key, long long lo,
                          long long hi) {
    if (!v.is_number() || (v.is_number_float() && std::floor(v.get<double>()) != v.get<double>()))
        throw InputError(file, key, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    double d = v.get<double>();
    if (d < static_cast<double>(lo) || d > static_cast<double>(hi))
        throw InputError(file, key, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v.get<long long>();
}

const std::string kIntegerBound = "+-9007199254740992 (2^53, the largest integer a double holds exactly; "
                                  "results.csv and the report read numbers as doubles)";

// The value of a JSON number that is an integer within +-kMaxAxisInteger; false for any other value.
bool bounded_integer(const json& v, long long& out) {
    if (v.is_number_unsigned()) {
        const std::uint64_t u = v.get<std::uint64_t>();
        if (u > static_cast<std::uint64_t>(kMaxAxisInteger)) return false;
        out = static_cast<long long>(u);
        return true;
    }
    if (v.is_number_integer()) {
        const std::int64_t i = v.get<std::int64_t>();
        if (i > kMaxAxisInteger || i < -kMaxAxisInteger) return false;
        out = i;
        return true;
    }
    if (v.is_number_float()) {
        const double d = v.get<double>();
        if (!std::isfinite(d) || std::floor(d) != d || std::fabs(d) > static_cast<double>(kMaxAxisInteger)) return false;
        out = static_cast<long long>(d);
        return true;
    }
    return false;
}

std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b) {
    if (a == 0 || b == 0) return 0;
    return a > std::numeric_limits<std::uint64_t>::max() / b ? std::numeric_limits<std::uint64_t>::max() : a * b;
}

std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) {
    return a > std::numeric_limits<std::uint64_t>::max() - b ? std::numeric_limits<std::uint64_t>::max() : a + b;
}

std::string count_text(std::uint64_t n) {
    return n == std::numeric_limits<std::uint64_t>::max() ? "more than 18446744073709551615" : std::to_string(n);
}

// A scene entry: a path (it has a folder part or ends in .json), relative to the working folder or else to
// the spec's folder; otherwise the name of a shipped scene (scene/scene_catalog.hpp).
std::string resolve_scene(const std::string& entry, const std::string& file, const std::string& key) {
    const bool looks_like_path = entry.find('/') != std::string::npos || fs::path(entry).extension() == ".json";
    if (!looks_like_path) {
        if (auto named = find_named_scene(entry)) return named->lexically_normal().string();
        throw InputError(file, key, "unknown scene '" + entry + "': no file " +
                                        (scenes_directory() / (entry + ".json")).string() + "; " +
                                        scene_argument_valid_text());
    }
    const std::vector<fs::path> candidates{entry, fs::path(file).parent_path() / entry};
    for (const auto& c : candidates)
        if (fs::is_regular_file(c)) return c.lexically_normal().string();
    throw InputError(file, key, "unknown scene '" + entry + "': no file " + candidates.front().string());
}

std::string canonical_value(const json& v) {
    if (v.is_string()) return v.get<std::string>();
    if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
    if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
    std::ostringstream s;
    s.precision(15);
    s << v.get<double>();
    return s.str();
}

// Type check of one axis value against the parameter's declared type (ranges are the run's business).
void check_axis_type(const ParamSpec& spec, const json& v, const std::string& file, const std::string& key) {
    bool ok = false;
    long long integer = 0;
    switch (spec.type) {
    case ParamType::Int:
        ok = v.is_number() && std::floor(v.get<double>()) == v.get<double>();
        if (ok && !bounded_integer(v, integer))
            throw InputError(file, key, "value " + v.dump() + " is out of bounds: integers must be within " +
                                            kIntegerBound + "; valid: " + spec.valid_text());
        break;
    case ParamType::Float: ok = v.is_number() && std::isfinite(v.get<double>()); break;
    case ParamType::Bool: ok = v.is_boolean(); break;
    case ParamType::Enum: ok = v.is_string(); break;
    }
    if (!ok)
        throw InputError(file, key, "value " + v.dump() + " is not a " + to_string(spec.type) +
                                        "; valid: " + spec.valid_text());
}

std::string safe_token(const std::string& s) {
    std::string out;
    for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-') ? c : '_';
    return out;
}

// Frames of a scene (or the default ones): a list, range or pow2 of integers, each once.
std::vector<int> parse_frames(const json& value, const std::string& file, const std::string& key) {
    std::vector<int> frames;
    std::set<int> seen;
    for (const json& f : expand_axis_values(value, file, key)) {
        const int frame = static_cast<int>(require_integer(f, file, key, 0, 1000000));
        if (!seen.insert(frame).second)
            throw InputError(file, key, "frame " + std::to_string(frame) + " is given twice; give each frame once");
        frames.push_back(frame);
    }
    return frames;
}

// The identity of a scene file: its canonical path (links resolved), so one file is recognised however
// it is named.
std::string file_identity(const std::string& path) {
    std::error_code ec;
    const fs::path canonical = fs::canonical(path, ec);
    return ec ? fs::absolute(path).lexically_normal().string() : canonical.string();
}

// One axis description, checked and measured without expanding it.
struct AxisGenerator {
    enum class Kind { List, IntegerRange, FloatRange, Pow2 } kind = Kind::List;
    std::uint64_t count = 0;
    long long first = 0, step = 0;   // IntegerRange; Pow2: first = lo
    double start = 0.0, fstep = 0.0; // FloatRange
};

AxisGenerator read_generator(const json& value, const std::string& file, const std::string& key) {
    AxisGenerator g;
    if (value.is_array()) {
        for (const auto& v : value)
            if (!v.is_primitive() || v.is_null())
                throw InputError(file, key, "axis values must be numbers, strings or booleans");
        g.kind = AxisGenerator::Kind::List;
        g.count = value.size();
    } else if (value.is_object() && value.size() == 1 && value.contains("range")) {
        const json& r = value["range"];
        const std::string rkey = key + ".range";
        if (!r.is_array() || r.size() != 3 || !r[0].is_number() || !r[1].is_number() || !r[2].is_number())
            throw InputError(file, rkey, "must be [start, stop, step] numbers");
        if (r[0].is_number_integer() && r[1].is_number_integer() && r[2].is_number_integer()) {
            long long start = 0, stop = 0, step = 0;
            if (!bounded_integer(r[0], start) || !bounded_integer(r[1], stop) || !bounded_integer(r[2], step))
                throw InputError(file, rkey, "start, stop and step must be integers within " + kIntegerBound);
            if (step == 0 || (stop != start && (stop - start > 0) != (step > 0)))
                throw InputError(file, rkey, "step must be non-zero and lead from start to stop");
            g.kind = AxisGenerator::Kind::IntegerRange;
            g.first = start;
            g.step = step;
            g.count = static_cast<std::uint64_t>((stop - start) / step) + 1;   // |stop - start| <= 2^54: no overflow
        } else {
            const double start = r[0].get<double>(), stop = r[1].get<double>(), step = r[2].get<double>();
            if (!std::isfinite(start) || !std::isfinite(stop) || !std::isfinite(step) || !std::isfinite(stop - start))
                throw InputError(file, rkey, "start, stop and step must be finite numbers");
            const double steps = step == 0.0 ? -1.0 : (stop - start) / step;
            if (!(steps >= 0.0))
                throw InputError(file, rkey, "step must be non-zero and lead from start to stop");
            g.kind = AxisGenerator::Kind::FloatRange;
            g.start = start;
            g.fstep = step;
            const double count = std::floor(steps + 1e-9) + 1.0;
            g.count = count >= 1.8e19 ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(count);
        }
    } else if (value.is_object() && value.size() == 1 && value.contains("pow2")) {
        const json& r = value["pow2"];
        const std::string pkey = key + ".pow2";
        const std::string form = "must be [lo, hi] with lo <= hi both powers of two (e.g. [32, 512])";
        if (!r.is_array() || r.size() != 2 || !r[0].is_number_integer() || !r[1].is_number_integer())
            throw InputError(file, pkey, form);
        long long bound[2] = {0, 0};
        for (int i = 0; i < 2; ++i)
            if (!bounded_integer(r[i], bound[i]))
                throw InputError(file, pkey, std::string(i ? "hi " : "lo ") + r[i].dump() + " is out of bounds: " + form +
                                                 ", within " + kIntegerBound);
        const auto is_pow2 = [](long long v) { return v > 0 && (v & (v - 1)) == 0; };
        if (!is_pow2(bound[0]) || !is_pow2(bound[1]) || bound[0] > bound[1]) throw InputError(file, pkey, form);
        g.kind = AxisGenerator::Kind::Pow2;
        g.first = bound[0];
        g.count = static_cast<std::uint64_t>(std::countr_zero(static_cast<std::uint64_t>(bound[1])) -
                                             std::countr_zero(static_cast<std::uint64_t>(bound[0]))) + 1;
    } else {
        throw InputError(file, key, "an axis is a list of values, {\"range\": [start, stop, step]} or {\"pow2\": [lo, hi]}");
    }
    if (g.count == 0) throw InputError(file, key, "empty axis: give at least one value");
    if (g.count > kMaxAxisValues)
        throw InputError(file, key, "the axis has " + count_text(g.count) + " values, more than " +
                                        std::to_string(kMaxAxisValues) + " (the most one axis may have)");
    return g;
}

// "methods": "all": every registered method, with an axis for each parameter whose table declares sweep
// values (ParamSpec::sweep); a method that declares none runs once, at its defaults.
json every_method_axes(const std::string& file) {
    json methods = json::object();
    for (const MethodInfo* info : registered_methods()) {
        json axes = json::object();
        for (const ParamSpec& p : info->params) {
            if (p.sweep.empty()) continue;
            json values = json::array();
            for (const std::string& v : p.sweep) values.push_back(param_json(info->name, p, v));
            axes[p.name] = values;
        }
        methods[info->name] = axes;
    }
    if (methods.empty()) throw InputError(file, "methods", "\"all\" names no method: none is registered in this program");
    return methods;
}

}  // namespace

std::uint64_t axis_value_count(const json& value, const std::string& file, const std::string& key) {
    return read_generator(value, file, key).count;
}

std::vector<json> expand_axis_values(const json& value, const std::string& file, const std::string& key) {
    const AxisGenerator g = read_generator(value, file, key);
    std::vector<json> out;
    out.reserve(g.count);
    for (std::uint64_t i = 0; i < g.count; ++i) {
        switch (g.kind) {
        case AxisGenerator::Kind::List: out.push_back(value[i]); break;
        case AxisGenerator::Kind::IntegerRange: out.push_back(g.first + static_cast<long long>(i) * g.step); break;
        case AxisGenerator::Kind::FloatRange: out.push_back(g.start + static_cast<double>(i) * g.fstep); break;
        case AxisGenerator::Kind::Pow2: out.push_back(g.first << i); break;
        }
    }
    return out;
}

namespace {

double require_number(const json& v, const std::string& path, const std::string& key, double lo, double hi) {
    if (!v.is_number() || !(v.get<double>() >= lo && v.get<double>() <= hi))
        throw InputError(path, key, "must be a number in [" + json(lo).dump() + ", " + json(hi).dump() + "]");
    return v.get<double>();
}

std::string require_truth(const json& v, const std::string& path, const std::string& key) {
    if (!v.is_string() || (v != "auto" && v != "analytic" && v != "reference"))
        throw InputError(path, key, "must be \"auto\", \"analytic\" or \"reference\"");
    return v.get<std::string>();
}

// Command-line axes (METHOD.AXIS=VALUES) written into the spec's methods, replacing or adding axes, so that
// they are checked like the file's.
void apply_axis_overrides(json& root, const std::vector<std::string>& axis_overrides) {
    std::set<std::string> overridden;
    for (const auto& text : axis_overrides) {
        const auto eq = text.find('='), dot = text.find('.');
        if (eq == std::string::npos || dot == std::string::npos || dot > eq)
            throw InputError("--axis", text, "expected METHOD.AXIS=VALUES, e.g. my_method.iterations=[1,2,4]");
        const std::string method = text.substr(0, dot), axis = text.substr(dot + 1, eq - dot - 1);
        if (!overridden.insert(method + "." + axis).second)
            throw InputError("--axis", text, method + "." + axis + " is given twice on the command line; give each axis once");
        // The method and its axis are named by the option, not by the spec file it would be written into.
        const MethodInfo& info = require_method(method, "--axis");
        if (std::none_of(info.params.begin(), info.params.end(), [&](const ParamSpec& p) { return p.name == axis; })) {
            std::string known;
            for (const ParamSpec& p : info.params) known += (known.empty() ? "" : ", ") + p.name;
            throw InputError("--axis", text, "unknown axis '" + axis + "' of " + method + "; its parameters: " + known);
        }
        json values;
        try {
            values = json::parse(text.substr(eq + 1));
        } catch (const json::parse_error&) {
            throw InputError("--axis", text, "VALUES must be JSON: [1,2,4], {\"range\":[1,5,1]} or {\"pow2\":[32,256]}");
        }
        if (!values.is_array() && !values.is_object()) values = json::array({values});
        root["methods"][method][axis] = values;
    }

}

// The scenes list: each entry once (by file and by run-id name), every frame within its animation.
std::vector<SweepScene> parse_scenes(const json& root, const std::string& path, const std::vector<int>& default_frames) {
    std::vector<SweepScene> scenes;
    if (!root.contains("scenes") || !root["scenes"].is_array() || root["scenes"].empty())
        throw InputError(path, "scenes", "must be a non-empty list of scene names or paths");
    std::map<std::string, std::size_t> scene_files;   // identity -> index of its entry
    std::map<std::string, std::size_t> scene_names;   // run-id token of the name -> index
    for (std::size_t i = 0; i < root["scenes"].size(); ++i) {
        const std::string key = "scenes[" + std::to_string(i) + "]";
        const json& entry = root["scenes"][i];
        SweepScene scene;
        if (entry.is_string()) {
            scene.path = resolve_scene(entry.get<std::string>(), path, key);
            scene.frames = default_frames;
        } else if (entry.is_object() && entry.contains("scene") && entry["scene"].is_string()) {
            check_keys(entry, {"scene", "frames", "noise_target", "truth"}, path, key);
            scene.path = resolve_scene(entry["scene"].get<std::string>(), path, key + ".scene");
            scene.frames = entry.contains("frames") ? parse_frames(entry["frames"], path, key + ".frames") : default_frames;
            if (entry.contains("noise_target"))
                scene.noise_target = require_number(entry["noise_target"], path, key + ".noise_target", 0.0, 10.0);
            if (entry.contains("truth")) scene.truth = require_truth(entry["truth"], path, key + ".truth");
        } else {
            throw InputError(path, key, "must be a scene name or path, or {\"scene\": NAME, \"frames\": [...]}");
        }
        const auto entry_text = [&](std::size_t j) {
            const json& e = root["scenes"][j];
            return e.is_string() ? e.get<std::string>() : e["scene"].get<std::string>();
        };
        const auto same_file = scene_files.find(file_identity(scene.path));
        if (same_file != scene_files.end())
            throw InputError(path, key, "'" + entry_text(i) + "' is the same scene file as scenes[" +
                                            std::to_string(same_file->second) + "] ('" + entry_text(same_file->second) +
                                            "'); give each scene once, with all its frames in one entry");
        const std::string name = fs::path(scene.path).stem().string();
        const auto same_name = scene_names.find(safe_token(name));
        if (same_name != scene_names.end())
            throw InputError(path, key, "scene name '" + name + "' (" + scene.path + ") is also the name of scenes[" +
                                            std::to_string(same_name->second) + "] (" + scenes[same_name->second].path +
                                            "); run ids and reference folders are named after the scene: rename one file");
        scene_files.emplace(file_identity(scene.path), i);
        scene_names.emplace(safe_token(name), i);
        // Every frame within the scene's animation (a frame past it was a run skipped at run time).
        {
            const Scene loaded = load_scene(scene.path);
            const bool own_frames = entry.is_object() && entry.contains("frames");
            for (int frame : scene.frames)
                if (frame >= loaded.animation.frames)
                    throw InputError(path, own_frames ? key + ".frames" : std::string("frames"),
                                     "frame " + std::to_string(frame) + " is past the animation of " + scene.path + " (" +
                                         std::to_string(loaded.animation.frames) + " frame(s): valid 0 to " +
                                         std::to_string(loaded.animation.frames - 1) + ")");
        }
        scenes.push_back(std::move(scene));
    }
    return scenes;
}

void parse_reference(const json& r, const std::string& path, ReferenceSettings& s) {
    if (!r.is_object()) throw InputError(path, "reference", "must be an object {\"photons\": N, \"seed\": S}");
    check_keys(r, {"photons", "seed", "noise_target", "photon_cap", "sampler", "replicas"}, path, "reference");
    using RS = ReferenceSettings;
    if (r.contains("noise_target")) s.noise_target = require_number(r["noise_target"], path, "reference.noise_target", 0.0, RS::kMaxNoiseTarget);
    if (r.contains("photon_cap"))
        s.photon_cap = static_cast<std::uint64_t>(require_integer(r["photon_cap"], path, "reference.photon_cap", RS::kMinPhotons, RS::kMaxPhotons));
    if (r.contains("replicas")) s.replicas = static_cast<int>(require_integer(r["replicas"], path, "reference.replicas", RS::kMinReplicas, RS::kMaxReplicas));
    if (r.contains("sampler") && (!r["sampler"].is_string() || !parse_sampler(r["sampler"].get<std::string>(), s.sampler)))
        throw InputError(path, "reference.sampler", "must be \"sobol\" or \"independent\"");
    if (r.contains("photons")) s.photons = static_cast<std::uint64_t>(require_integer(r["photons"], path, "reference.photons", RS::kMinPhotons, RS::kMaxPhotons));
    if (r.contains("seed")) s.seed = static_cast<std::uint64_t>(require_integer(r["seed"], path, "reference.seed", 0, RS::kMaxSeed));
    if (s.photon_cap < s.photons)
        throw InputError(path, "reference.photon_cap",
                         "is " + std::to_string(s.photon_cap) + ", below reference.photons " + std::to_string(s.photons) +
                             ": the cap must be at least the first round's photons");
}

void parse_timing(const json& t, const std::string& path, SweepSpec& spec) {
    if (!t.is_object()) throw InputError(path, "timing", "must be an object {\"warmup\": W, \"repeats\": R}");
    check_keys(t, {"warmup", "repeats", "timeout_s", "precision", "max_time_s"}, path, "timing");
    if (t.contains("precision")) spec.timing_precision = require_number(t["precision"], path, "timing.precision", 0.001, 1.0);
    if (t.contains("max_time_s")) spec.timing_max_s = require_number(t["max_time_s"], path, "timing.max_time_s", 0.0, 3600.0);
    if (t.contains("warmup")) spec.warmup = static_cast<int>(require_integer(t["warmup"], path, "timing.warmup", 0, 10000));
    if (t.contains("repeats")) spec.repeats = static_cast<int>(require_integer(t["repeats"], path, "timing.repeats", 1, 100000));
    if (t.contains("timeout_s")) {
        if (!t["timeout_s"].is_number() || t["timeout_s"].get<double>() < 0.0)
            throw InputError(path, "timing.timeout_s", "must be a number of seconds >= 0 (0: no limit)");
        spec.timeout_s = t["timeout_s"].get<double>();
    }
}

// The methods and their axes: known axes of registered methods, values of the parameter's type, each
// once; the sweep's size is checked by arithmetic before any axis is expanded.
std::vector<SweepMethod> parse_methods(const json& root, const std::string& path, const std::vector<SweepScene>& scenes) {
    std::vector<SweepMethod> methods;
    if (!root.contains("methods") || !root["methods"].is_object() || root["methods"].empty())
        throw InputError(path, "methods", "must be \"all\" or a non-empty object {method: {axis: values}}");
    // First the size, by arithmetic on the axes: a sweep too large to plan is refused before any axis
    // is expanded.
    const auto find_param = [&](const MethodInfo& info, const std::string& name, const std::string& axis) {
        for (const auto& p : info.params)
            if (p.name == axis) return &p;
        std::string known;
        for (const auto& p : info.params) known += (known.empty() ? "" : ", ") + p.name;
        throw InputError(path, "methods." + name + "." + axis, "unknown axis; parameters of " + name + ": " + known);
    };
    std::uint64_t scene_frames = 0, runs_per_frame = 0;
    for (const auto& scene : scenes) scene_frames = saturating_add(scene_frames, scene.frames.size());
    for (const auto& [name, axes] : root["methods"].items()) {
        const MethodInfo& info = require_method(name, path + ": methods." + name);
        if (!axes.is_object()) throw InputError(path, "methods." + name, "must be an object {axis: values}");
        std::uint64_t product = 1;
        for (const auto& [axis, values] : axes.items()) {
            (void)find_param(info, name, axis);
            product = saturating_mul(product, axis_value_count(values, path, "methods." + name + "." + axis));
        }
        runs_per_frame = saturating_add(runs_per_frame, product);
    }
    const std::uint64_t total = saturating_mul(scene_frames, runs_per_frame);
    if (total > kMaxSweepRuns)
        throw InputError(path, "methods",
                         "the sweep has " + count_text(total) + " runs (" + std::to_string(scene_frames) +
                             " scene frames x " + count_text(runs_per_frame) + " method runs each), more than " +
                             std::to_string(kMaxSweepRuns) + ", the most one sweep may have even with --yes; "
                             "split it into several sweeps or give fewer axis values");
    for (const auto& [name, axes] : root["methods"].items()) {
        const MethodInfo& info = require_method(name, path + ": methods." + name);
        SweepMethod m{name, {}};
        for (const auto& [axis, values] : axes.items()) {
            const std::string key = "methods." + name + "." + axis;
            const ParamSpec* param = find_param(info, name, axis);
            SweepAxis a{axis, {}};
            std::map<std::string, std::string> seen;   // canonical value -> the value as first given
            for (const json& v : expand_axis_values(values, path, key)) {
                check_axis_type(*param, v, path, key);
                std::string value = canonical_value(v);
                const auto [it, inserted] = seen.emplace(value, v.dump());
                if (!inserted)
                    throw InputError(path, key, "value " + value + " is given twice" +
                                                    (it->second == v.dump() ? std::string()
                                                                            : " (as " + it->second + " and " + v.dump() + ")") +
                                                    "; give each value once");
                a.values.push_back(std::move(value));
            }
            m.axes.push_back(std::move(a));
        }
        methods.push_back(std::move(m));
    }
    return methods;
}

}  // namespace

SweepSpec load_sweep_spec(const std::string& path, const std::vector<std::string>& axis_overrides) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "cannot read sweep spec (missing or unreadable file)");
    std::stringstream buffer;
    buffer << in.rdbuf();
    // nlohmann keeps the last of duplicate keys silently; a duplicated axis is almost always a mistake in a
    // hand-written spec, so parse_json_strict rejects it with the key path (and nesting past kMaxJsonDepth).
    json root = parse_json_strict(buffer.str(), path);
    if (!root.is_object())
        throw InputError(path, "", "must be a JSON object with the keys scenes and methods (and optionally description, "
                                   "frames, reference, truth, timing, report), not " + describe_json(root));
    check_keys(root, {"description", "scenes", "frames", "reference", "truth", "timing", "methods", "report"}, path, "");
    // "all" is expanded first, so that --axis, the checks below and the manifest's spec as run see every
    // method's axes as if they were written out.
    if (root.contains("methods") && !root["methods"].is_object()) {
        if (root["methods"] != "all")
            throw InputError(path, "methods", "must be \"all\" (every registered method at the sweep values its "
                                              "parameter table declares) or an object {method: {axis: values}}");
        root["methods"] = every_method_axes(path);
    }
    apply_axis_overrides(root, axis_overrides);

    SweepSpec spec;
    spec.path = path;
    spec.as_run = root;
    if (root.contains("report")) check_report(root["report"], path);
    if (root.contains("description")) {
        if (!root["description"].is_string()) throw InputError(path, "description", "must be a string");
        spec.description = root["description"].get<std::string>();
    }
    if (root.contains("truth")) spec.truth = require_truth(root["truth"], path, "truth");
    std::vector<int> default_frames{0};
    if (root.contains("frames")) default_frames = parse_frames(root["frames"], path, "frames");
    spec.scenes = parse_scenes(root, path, default_frames);
    if (root.contains("reference")) parse_reference(root["reference"], path, spec.reference);
    if (root.contains("timing")) parse_timing(root["timing"], path, spec);
    spec.methods = parse_methods(root, path, spec.scenes);
    return spec;
}

std::uint64_t count_runs(const SweepSpec& spec) {
    std::uint64_t scene_frames = 0, runs_per_frame = 0;
    for (const auto& scene : spec.scenes) scene_frames = saturating_add(scene_frames, scene.frames.size());
    for (const auto& m : spec.methods) {
        std::uint64_t product = 1;
        for (const auto& a : m.axes) product = saturating_mul(product, a.values.size());
        runs_per_frame = saturating_add(runs_per_frame, product);
    }
    return saturating_mul(scene_frames, runs_per_frame);
}

std::vector<PlannedRun> plan_runs(const SweepSpec& spec) {
    const std::uint64_t total = count_runs(spec);
    if (total > kMaxSweepRuns)
        throw InputError(spec.path, "methods", "the sweep has " + count_text(total) + " runs, more than " +
                                                   std::to_string(kMaxSweepRuns) + ", the most one sweep may have");
    std::vector<PlannedRun> runs;
    runs.reserve(static_cast<std::size_t>(total));
    std::unordered_set<std::string> ids;
    for (const auto& scene : spec.scenes) {
        const std::string& scene_path = scene.path;
        const std::string scene_name = fs::path(scene_path).stem().string();
        for (int frame : scene.frames) {
            for (const auto& m : spec.methods) {
                // Odometer over the axes, last axis fastest.
                std::vector<std::size_t> index(m.axes.size(), 0);
                while (true) {
                    PlannedRun run;
                    run.scene_path = scene_path;
                    run.scene_name = scene_name;
                    run.frame = frame;
                    run.noise_target = scene.noise_target >= 0.0 ? scene.noise_target : spec.reference.noise_target;
                    run.truth = scene.truth.empty() ? spec.truth : scene.truth;
                    run.method = m.method;
                    run.id = safe_token(scene_name) + "-f" + std::to_string(frame) + "-" + safe_token(m.method);
                    for (std::size_t a = 0; a < m.axes.size(); ++a) {
                        run.params[m.axes[a].name] = m.axes[a].values[index[a]];
                        run.id.append("-").append(safe_token(m.axes[a].name)).append("=");
                        run.id.append(safe_token(m.axes[a].values[index[a]]));
                    }
                    if (!ids.insert(run.id).second)
                        throw InputError(spec.path, "methods." + m.method,
                                         "two runs would share the run id " + run.id +
                                             " (values that differ only in characters a file name cannot hold); "
                                             "give values that differ in letters, digits, '.' or '-'");
                    runs.push_back(std::move(run));
                    std::size_t a = m.axes.size();
                    while (a > 0 && ++index[a - 1] == m.axes[a - 1].values.size()) index[--a] = 0;
                    if (a == 0) break;
                }
            }
        }
    }
    return runs;
}

std::string reference_key(const PlannedRun& run) { return run.scene_name + "-f" + std::to_string(run.frame); }

}  // namespace caustics
