#pragma once
// The analytic cases of the conformance suite (tests/test_conformance.cpp): scenes whose receiver map has
// an exact closed form (harness/reference/analytic_truth.hpp), chosen to contain what a method's model may miss:
// oblique light, a floor past the first focus (folds), ior = 1, Fresnel and absorption on a slanted path,
// a 2-D (radial) caustic, a solid refractor whose map folds into a ring. Each is a shipped scene file
// (scenes/README.md), so that sweeps and reports can run the same cases.
#include <functional>
#include <string>
#include <vector>

#include <caustics/scene/scene.hpp>

namespace caustics::test_support {

struct ConformanceCase {
    std::string name;
    std::string what;            // one line: what the case exercises
    std::function<Scene()> scene;
    bool flat_truth = false;     // the truth is constant over the bins it lights: the map must be flat
};

inline Scene shipped_scene(const std::string& name) {
    return load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json");
}

inline std::vector<ConformanceCase> conformance_cases() {
    std::vector<ConformanceCase> cases;
    cases.push_back({"sine", "1-D sine, normal incidence, floor above the first focus",
                     [] { return shipped_scene("sine"); }});
    cases.push_back({"sine_oblique", "the same sine lit 30 deg off the vertical",
                     [] { return shipped_scene("sine_oblique"); }});
    cases.push_back({"sine_deep", "floor 1.2 m down, past the first focus (folds), absorption 0.5 /m",
                     [] { return shipped_scene("sine_deep"); }});
    cases.push_back({"sine_ior1", "ior = 1: the interface does not refract, the truth is flat",
                     [] { return shipped_scene("sine_ior1"); }, true});
    cases.push_back({"flat_oblique", "flat water lit 30 deg off the vertical, Fresnel, absorption 0.5 /m",
                     [] { return shipped_scene("flat_oblique"); }, true});
    cases.push_back({"gaussian", "radial Gaussian bump, normal incidence, before its focus",
                     [] { return shipped_scene("gaussian"); }});
    cases.push_back({"ball_lens", "glass sphere (n 1.5) lit along its axis, floor past the paraxial focus (ring fold)",
                     [] { return shipped_scene("ball_lens"); }});
    return cases;
}

}  // namespace caustics::test_support
