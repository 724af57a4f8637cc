#pragma once
// The scenes shipped with the program, by name: NAME is the file NAME.json in the data folder's scenes/
// (util/resources.hpp), wherever the program was installed or built. The one place that turns a scene
// argument or a sweep spec's scene entry into a file.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace caustics {

// data_directory()/scenes.
std::filesystem::path scenes_directory();
// The names of the scene files there ("pool" for scenes/pool.json), sorted.
std::vector<std::string> scene_names();
// The shipped scene `name` ("pool" or "pool.json"), or nothing for a name with a folder part or no such file.
std::optional<std::filesystem::path> find_named_scene(const std::string& name);
// What a scene argument may be, for messages: "a scene file, or a scene name in DIR: a, b, c".
std::string scene_argument_valid_text();

// A scene argument: an existing path as is, else a shipped scene's name. Throws InputError (exit 2) for
// an empty argument, a symbolic link loop, and a path or name that is neither, listing the scene names.
std::string resolve_scene_path(const std::string& arg);

}  // namespace caustics
