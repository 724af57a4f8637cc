// Structural fuzzing of the input loaders (issue 38): where scripts/fuzz.sh mutates the bytes of shipped
// scenes, this builds shapes byte mutation never reaches: values nested tens of thousands deep, arrays and
// objects a million wide, keys and strings a megabyte long, placed anywhere in a scene file or a sweep spec,
// and glTF node graphs (chains past the depth limit, fans, shared children, cycles, out-of-range indices,
// deep `extras`). Every input is loaded in this process (so a stack overflow or a sanitizer report fails
// the test binary) and must either load or be refused with InputError and a message of bounded length.
//
// Independent oracles say which answer is right where the answer is decidable from the shape alone:
// - JSON nested deeper than kMaxJsonDepth anywhere must be refused as such;
// - a glTF node graph is loaded exactly when it is a set of trees (every index in range, no node reached
//   twice from the scene's roots, at most kMaxNodeDepth levels below a root) that reaches a mesh, and then
//   holds one triangle per reached mesh node.
// The draw is seeded: CAUSTICS_STRUCTURAL_FUZZ_SEED (default 20261205) and CAUSTICS_STRUCTURAL_FUZZ_CASES
// (default 120 per input kind); the seed is printed so that a failing draw can be replayed.
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "catalog_support.hpp"
#include "glb_writer.hpp"
#include <caustics/scene/scene.hpp>
#include <caustics/sweep/sweep_spec.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/json_reader.hpp>

namespace {

using nlohmann::json;
using caustics::test_support::CaseDir;

// Every message must stay this short whatever the input's size (it names a key path and a described value).
constexpr std::size_t kMaxMessageChars = 2048;
// The glTF loader's limit on levels below a scene root (harness/scene/gltf_mesh.cpp).
constexpr int kMaxNodeDepth = 256;

std::uint64_t env_or(const char* name, std::uint64_t fallback) {
    const char* v = std::getenv(name);
    return v && *v ? std::strtoull(v, nullptr, 10) : fallback;
}

std::uint64_t seed() { return env_or("CAUSTICS_STRUCTURAL_FUZZ_SEED", 20261205); }
int cases() { return static_cast<int>(env_or("CAUSTICS_STRUCTURAL_FUZZ_CASES", 120)); }
// CAUSTICS_STRUCTURAL_FUZZ_VERBOSE=1 prints each case before it is loaded (to find one that hangs).
bool verbose() { return env_or("CAUSTICS_STRUCTURAL_FUZZ_VERBOSE", 0) != 0; }

// ---- generated JSON values, written as text (building them as json values would itself recurse that deep)

struct Generated {
    std::string text;
    std::size_t depth = 0;  // arrays and objects nested, counting the value's own outermost one
    std::string kind;
};

class ValueGenerator {
public:
    explicit ValueGenerator(std::mt19937_64& rng) : rng_(rng) {}

    Generated draw() {
        switch (pick(8)) {
        case 0: return deep_arrays(draw_depth());
        case 1: return deep_objects(draw_depth());
        case 2: return alternating(draw_depth());
        case 3: return wide_array(draw_width());
        case 4: return wide_object(draw_width());
        case 5: return long_string(draw_width());
        case 6: return deep_and_wide(draw_depth(), 1 + pick(200));
        default: return small_scalar();
        }
    }

private:
    std::size_t pick(std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }

    // Depths around the limit, and far past it.
    std::size_t draw_depth() {
        static const std::size_t depths[] = {1, 2, 3, 8, 30, 60, 61, 62, 63, 64, 65, 66, 100, 1000, 100000, 1000000};
        return depths[pick(std::size(depths))];
    }
    std::size_t draw_width() {
        static const std::size_t widths[] = {0, 1, 2, 3, 4, 10, 1000, 100000, 1000000};
        return widths[pick(std::size(widths))];
    }
    std::string key(std::size_t length) { return "\"" + std::string(length, 'k') + "\""; }
    std::string scalar() {
        switch (pick(6)) {
        case 0: return "0";
        case 1: return "-1e308";
        case 2: return "1e999";
        case 3: return "\"x\"";
        case 4: return "null";
        default: return "true";
        }
    }

    Generated small_scalar() { return {scalar(), 0, "scalar"}; }
    Generated deep_arrays(std::size_t d) { return {std::string(d, '[') + scalar() + std::string(d, ']'), d, "arrays"}; }
    Generated deep_objects(std::size_t d) {
        // Long keys (a long key path) only where the file stays small: 5000 characters x 200 levels.
        const std::string k = key(pick(4) == 0 && d <= 200 ? 5000 : 1);
        std::string t;
        t.reserve(d * (k.size() + 3));
        for (std::size_t i = 0; i < d; ++i) t += "{" + k + ":";
        t += scalar();
        t += std::string(d, '}');
        return {t, d, "objects"};
    }
    Generated alternating(std::size_t d) {
        std::string open, close;
        for (std::size_t i = 0; i < d; ++i) {
            if (i % 2 == 0) open += "[", close += "]";
            else open += "{\"a\":", close += "}";
        }
        return {open + scalar() + std::string(close.rbegin(), close.rend()), d, "alternating"};
    }
    Generated wide_array(std::size_t w) {
        std::string t = "[";
        for (std::size_t i = 0; i < w; ++i) t += (i ? "," : "") + (i % 7 == 3 ? std::string("[1]") : scalar());
        return {t + "]", w > 3 ? 2u : 1u, "wide array"};
    }
    Generated wide_object(std::size_t w) {
        const bool repeat = pick(3) == 0;  // a repeated key must be refused, never silently dropped
        std::string t = "{";
        for (std::size_t i = 0; i < w; ++i)
            t.append(i ? "," : "").append("\"k").append(std::to_string(repeat ? i % 2 : i)).append("\":").append(scalar());
        return {t + "}", 1, "wide object"};
    }
    Generated long_string(std::size_t n) {
        std::string body;
        body.reserve(n * 2);
        for (std::size_t i = 0; i < n; ++i) body += (i % 97 == 5) ? "\\u00e9" : "s";
        return {"\"" + body + "\"", 0, "long string"};
    }
    Generated deep_and_wide(std::size_t d, std::size_t w) {
        const Generated one = deep_arrays(std::min<std::size_t>(d, 2000));
        std::string t = "[";
        for (std::size_t i = 0; i < w; ++i) t += (i ? "," : "") + one.text;
        return {t + "]", one.depth + 1, "deep and wide"};
    }

    std::mt19937_64& rng_;
};

// A place in a document: the JSON pointer of an existing value, or of a new member of an existing object;
// `containers` counts the arrays and objects around it (the root included).
struct Place {
    json::json_pointer pointer;
    std::size_t containers = 0;
};

void collect_places(const json& v, const json::json_pointer& at, std::size_t containers, std::vector<Place>& out) {
    if (v.is_object()) {
        out.push_back({at / "unknown_member", containers + 1});
        for (const auto& [k, child] : v.items()) {
            out.push_back({at / k, containers + 1});
            collect_places(child, at / k, containers + 1, out);
        }
    } else if (v.is_array()) {
        for (std::size_t i = 0; i < v.size(); ++i) {
            out.push_back({at / i, containers + 1});
            collect_places(v[i], at / i, containers + 1, out);
        }
    }
}

// The document's text with the generated value at `place`.
std::string with_value_at(json doc, const Place& place, const Generated& value) {
    const std::string marker = "\"STRUCTURAL_FUZZ_MARKER\"";
    doc[place.pointer] = "STRUCTURAL_FUZZ_MARKER";
    std::string text = doc.dump();
    text.replace(text.find(marker), marker.size(), value.text);
    return text;
}

// Loads through `load`; returns the InputError's message, or nullopt when the input loaded. Any other
// exception fails the test (a crash or a sanitizer report fails the whole binary).
template <class Load>
std::optional<std::string> outcome(Load&& load, const std::string& what) {
    try {
        load();
        return std::nullopt;
    } catch (const caustics::InputError& e) {
        const std::string message = e.what();
        EXPECT_LE(message.size(), kMaxMessageChars) << what << ": message of " << message.size() << " characters: "
                                                    << message.substr(0, 300) << "...";
        return message;
    } catch (const std::exception& e) {
        ADD_FAILURE() << what << ": not an InputError: " << std::string(e.what()).substr(0, 300);
        return std::string(e.what());
    }
}

json base_scene() {
    const json camera = {{"position", {0, -0.6, -0.03}}, {"look_at", {0, 0.05, -0.4}}, {"up", {0, 0, 1}},
                         {"fov_y", 55}, {"width", 8}, {"height", 6}};
    json s = caustics::test_support::small_sine_scene(1.0, 8, camera, 8);
    return s;
}

// A valid spec with a report block, so that generated values reach every level the loader checks.
json base_spec() {
    json s = caustics::test_support::small_sweep_spec();
    s["report"] = {{"time_budget_ms", 100}, {"image_settings", {{"caustic_triangles", {{"grid", 16}}}}}};
    return s;
}

// Runs `count` drawn cases of a generated value placed anywhere in `base`, loaded by `load(path)`.
template <class Load>
void fuzz_document(const json& base, const std::string& label, std::uint64_t salt, Load&& load) {
    std::mt19937_64 rng(seed() ^ salt);
    ValueGenerator values(rng);
    std::vector<Place> places;
    collect_places(base, json::json_pointer(), 0, places);
    const CaseDir dir("structural_" + label);
    int deep_cases = 0, refused = 0;
    for (int c = 0; c < cases(); ++c) {
        const Place& place = places[std::uniform_int_distribution<std::size_t>(0, places.size() - 1)(rng)];
        const Generated value = values.draw();
        const std::string path = dir.write(label + ".json", with_value_at(base, place, value));
        const std::string what = label + " case " + std::to_string(c) + ": " + value.kind + " of depth " +
                                 std::to_string(value.depth) + " at " + place.pointer.to_string();
        if (verbose()) std::cout << what << std::endl;
        const std::optional<std::string> message = outcome([&] { load(path); }, what);
        if (message) ++refused;
        if (place.containers + value.depth > caustics::kMaxJsonDepth) {
            ++deep_cases;
            ASSERT_TRUE(message.has_value()) << what << ": nested past the limit and loaded";
            EXPECT_NE(message->find("nested deeper than"), std::string::npos) << what << ": " << message->substr(0, 300);
        }
    }
    std::cout << label << ": " << cases() << " cases (seed " << seed() << "), " << deep_cases
              << " nested past the limit, " << refused << " refused\n";
}

TEST(StructuralFuzz, SceneFileValuesOfAnyShapeAreLoadedOrRefused) {
    fuzz_document(base_scene(), "scene", 0x5ce9e, [](const std::string& path) { (void)caustics::load_scene(path); });
}

TEST(StructuralFuzz, SweepSpecValuesOfAnyShapeAreLoadedOrRefused) {
    fuzz_document(base_spec(), "spec", 0x59ec, [](const std::string& path) { (void)caustics::load_sweep_spec(path); });
}

// ---- glTF node graphs

struct NodeGraph {
    json nodes = json::array();
    json roots = json::array();
    std::string shape;
    std::size_t extras_depth = 0;  // nesting of a node's `extras` (0: none)
};

class GraphGenerator {
public:
    explicit GraphGenerator(std::mt19937_64& rng) : rng_(rng) {}

    NodeGraph draw() {
        static const int sizes[] = {1, 2, 3, 10, 100, 255, 256, 257, 258, 1000, 20000};
        const int n = sizes[pick(std::size(sizes))];
        NodeGraph g;
        std::vector<std::vector<long long>> children(static_cast<std::size_t>(n));
        switch (pick(5)) {
        case 0:  // a chain, the longest possible tree
            g.shape = "chain";
            for (int k = 0; k + 1 < n; ++k) children[k].push_back(k + 1);
            break;
        case 1:  // one parent of all
            g.shape = "fan";
            for (int k = 1; k < n; ++k) children[0].push_back(k);
            break;
        case 2:  // a random tree: each node's parent comes before it
            g.shape = "tree";
            for (int k = 1; k < n; ++k) children[pick(static_cast<std::size_t>(k))].push_back(k);
            break;
        case 3:  // a random DAG: later children, some shared
            g.shape = "dag";
            for (int k = 0; k + 1 < n; ++k)
                for (std::size_t c = pick(3); c > 0; --c)
                    children[k].push_back(k + 1 + static_cast<long long>(pick(static_cast<std::size_t>(n - k - 1))));
            break;
        default:  // a random graph: any child, cycles and self loops included
            g.shape = "graph";
            for (int k = 0; k < n; ++k)
                for (std::size_t c = pick(3); c > 0; --c) children[k].push_back(static_cast<long long>(pick(static_cast<std::size_t>(n))));
            break;
        }
        // A few defects on top of any shape.
        if (pick(6) == 0) children[pick(static_cast<std::size_t>(n))].push_back(n + static_cast<long long>(pick(3)));
        if (pick(12) == 0) children[pick(static_cast<std::size_t>(n))].push_back(-1);
        if (pick(8) == 0 && n > 1) children[pick(static_cast<std::size_t>(n))].push_back(static_cast<long long>(pick(static_cast<std::size_t>(n))));

        for (int k = 0; k < n; ++k) {
            json node = json::object();
            if (!children[k].empty()) node["children"] = children[k];
            if (pick(3) == 0 || k == n - 1) node["mesh"] = pick(20) == 0 ? 1 : 0;  // mesh 1 does not exist
            g.nodes.push_back(node);
        }
        g.roots.push_back(0);
        if (pick(4) == 0) g.roots.push_back(static_cast<long long>(pick(static_cast<std::size_t>(n + 1))));
        if (pick(5) == 0) {
            static const std::size_t depths[] = {1, 10, 40, 60, 100, 100000};
            g.extras_depth = depths[pick(std::size(depths))];
        }
        return g;
    }

private:
    std::size_t pick(std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }
    std::mt19937_64& rng_;
};

// The oracle: how many mesh nodes the loader must find, or nullopt when it must refuse the graph.
std::optional<int> expected_mesh_nodes(const NodeGraph& g) {
    const long long n = static_cast<long long>(g.nodes.size());
    std::vector<char> reached(static_cast<std::size_t>(n), 0);
    std::vector<std::pair<long long, int>> stack;  // node, depth
    for (const json& r : g.roots) stack.emplace_back(r.get<long long>(), 0);
    int meshes = 0;
    while (!stack.empty()) {
        const auto [k, depth] = stack.back();
        stack.pop_back();
        if (k < 0 || k >= n || depth > kMaxNodeDepth || reached[static_cast<std::size_t>(k)]) return std::nullopt;
        reached[static_cast<std::size_t>(k)] = 1;
        const json& node = g.nodes[static_cast<std::size_t>(k)];
        if (node.contains("mesh")) {
            if (node["mesh"].get<int>() != 0) return std::nullopt;
            ++meshes;
        }
        if (node.contains("children"))
            for (const json& c : node["children"]) stack.emplace_back(c.get<long long>(), depth + 1);
    }
    if (meshes == 0) return std::nullopt;  // "contains no triangles"
    return meshes;
}

std::string glb_of(const NodeGraph& g) {
    const std::vector<float> positions = {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 0};
    const std::vector<float> normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    const std::string bin = caustics::test_support::glb_floats(positions) + caustics::test_support::glb_floats(normals);
    json doc = caustics::test_support::gltf_triangle_document("shard", bin.size(), g.nodes, g.roots);
    if (g.extras_depth == 0) return caustics::test_support::glb_container(doc.dump(), bin);
    doc["nodes"][0]["extras"] = "EXTRAS_MARKER";
    std::string text = doc.dump();
    const std::string marker = "\"EXTRAS_MARKER\"";
    text.replace(text.find(marker), marker.size(),
                 std::string(g.extras_depth, '[') + "1" + std::string(g.extras_depth, ']'));
    return caustics::test_support::glb_container(text, bin);
}

TEST(StructuralFuzz, GltfNodeGraphsLoadExactlyWhenTheyAreTrees) {
    std::mt19937_64 rng(seed() ^ 0x91fULL);
    GraphGenerator graphs(rng);
    const CaseDir dir("structural_gltf");
    json scene = base_scene();
    scene["objects"].push_back({{"name", "shard"}, {"shape", "mesh"}, {"file", "graph.glb"},
                                {"transform", {{"translate", {0, 0, -0.2}}}},
                                {"material", {{"type", "dielectric"}, {"ior", 1.5}}}});
    const std::string scene_path = dir.write("scene.json", scene.dump());
    int loaded = 0;
    for (int c = 0; c < cases(); ++c) {
        const NodeGraph g = graphs.draw();
        dir.write("graph.glb", glb_of(g));
        // The document nests: root, nodes[], node, extras (its own arrays).
        const bool extras_too_deep = g.extras_depth > 0 && 3 + g.extras_depth > caustics::kMaxJsonDepth;
        const std::optional<int> expected = extras_too_deep ? std::nullopt : expected_mesh_nodes(g);
        const std::string what = "glTF case " + std::to_string(c) + ": " + g.shape + " of " + std::to_string(g.nodes.size()) +
                                 " nodes, " + std::to_string(g.roots.size()) + " root(s), extras depth " +
                                 std::to_string(g.extras_depth);
        if (verbose()) std::cout << what << std::endl;
        std::optional<caustics::Scene> result;
        const std::optional<std::string> message = outcome([&] { result = caustics::load_scene(scene_path); }, what);
        if (expected) {
            ASSERT_FALSE(message.has_value()) << what << ": a valid tree was refused: " << message->substr(0, 300);
            ++loaded;
            EXPECT_EQ(result->objects.back().mesh.triangles.size(), static_cast<std::size_t>(*expected)) << what;
        } else {
            ASSERT_TRUE(message.has_value()) << what << ": not a valid set of trees, and loaded";
            EXPECT_NE(message->find("graph.glb"), std::string::npos) << what << ": " << message->substr(0, 300);
        }
    }
    std::cout << "glTF: " << cases() << " graphs (seed " << seed() << "), " << loaded << " valid and loaded\n";
}

}  // namespace
