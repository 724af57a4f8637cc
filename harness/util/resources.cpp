#include <caustics/util/resources.hpp>

#include <cstdlib>
#include <fstream>
#include <string>

#include <caustics/util/errors.hpp>

namespace caustics {
namespace {

namespace fs = std::filesystem;

constexpr const char* kVariable = "CAUSTICS_DATA_DIR";
constexpr int kAncestors = 3;   // bin/ in an installation; bin/, tests/, methods/NAME/ in a build tree

bool holds_scenes(const fs::path& dir) {
    std::error_code ec;
    return fs::is_directory(dir / "scenes", ec);
}

}  // namespace

fs::path data_directory() {
    if (const char* env = std::getenv(kVariable); env && *env) {
        if (!holds_scenes(env))
            throw invalid_value(kVariable, "'" + std::string(env) + "' has no scenes/ folder",
                                "an installation's share/caustics (or a build tree's), or unset");
        return env;
    }
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (ec) throw invalid_value(kVariable, "unset, and the program cannot find itself (/proc/self/exe: " +
                                               ec.message() + ")",
                                "the folder of scenes/ and scripts/ (an installation's share/caustics)");
    std::string looked;
    fs::path dir = exe.parent_path();
    for (int i = 0; i < kAncestors && dir.has_parent_path() && dir != dir.root_path(); ++i) {
        dir = dir.parent_path();
        const fs::path candidate = dir / "share" / "caustics";
        if (holds_scenes(candidate)) return candidate;
        looked += (looked.empty() ? "" : ", ") + candidate.string();
    }
    throw invalid_value(kVariable, "unset, and no data folder with scenes/ near the program " + exe.string() +
                                       " (looked in " + looked + ")",
                        "set it to an installation's share/caustics, or run the program from an installation "
                        "(PREFIX/bin) or a build tree");
}

nlohmann::json build_description() {
    fs::path dir;
    try {
        dir = data_directory();
    } catch (const InputError&) {
        return nlohmann::json::object();   // describing the build never stops a run
    }
    std::ifstream in(dir / "build.json");
    nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    return j.is_object() ? j : nlohmann::json::object();
}

}  // namespace caustics
