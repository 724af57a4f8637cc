#include <caustics/scene/scene_catalog.hpp>

#include <algorithm>

#include <caustics/util/errors.hpp>
#include <caustics/util/resources.hpp>

namespace caustics {

namespace fs = std::filesystem;

fs::path scenes_directory() { return data_directory() / "scenes"; }

std::vector<std::string> scene_names() {
    std::vector<std::string> names;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(scenes_directory(), ec))
        if (entry.path().extension() == ".json" && entry.is_regular_file(ec)) names.push_back(entry.path().stem().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::optional<fs::path> find_named_scene(const std::string& name) {
    if (name.empty() || fs::path(name).has_parent_path()) return std::nullopt;
    const fs::path dir = scenes_directory();
    std::error_code ec;
    for (const fs::path& candidate : {dir / (name + ".json"), dir / name})
        if (candidate.extension() == ".json" && fs::is_regular_file(candidate, ec)) return candidate;
    return std::nullopt;
}

std::string scene_argument_valid_text() {
    std::string names;
    for (const std::string& n : scene_names()) names += (names.empty() ? "" : ", ") + n;
    return "a scene file, or a scene name in " + scenes_directory().string() + ": " + names;
}

std::string resolve_scene_path(const std::string& arg) {
    if (arg.empty()) throw invalid_value("SCENE", "empty", scene_argument_valid_text());
    std::error_code ec;
    const fs::file_status st = fs::status(arg, ec);
    if (ec == std::errc::too_many_symbolic_link_levels)
        throw invalid_value(arg, "symbolic link loop", scene_argument_valid_text());
    if (fs::exists(st)) return arg;   // load_scene checks what it is
    if (fs::is_symlink(fs::symlink_status(arg, ec)))
        throw invalid_value(arg, "a symbolic link to a file that does not exist", scene_argument_valid_text());
    if (!fs::path(arg).has_parent_path()) {
        if (auto named = find_named_scene(arg)) return named->string();
        throw invalid_value(arg, "no such scene file, nor a scene of that name", scene_argument_valid_text());
    }
    throw invalid_value(arg, "no such scene file", scene_argument_valid_text());
}

}  // namespace caustics
