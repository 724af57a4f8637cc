#pragma once
// Where the program's data lives at run time: the scenes (scenes/), the report scripts (scripts/report/)
// and the sweep specs (scripts/sweeps/), with build.json describing the build. No path is compiled in;
// the folder is found from the running program:
//   1. $CAUSTICS_DATA_DIR, when set;
//   2. else share/caustics in the program's folder's parent, or in one of its next two ancestors: an
//      installation's PREFIX/bin/caustics finds PREFIX/share/caustics, and in a build tree (which CMake
//      lays out the same way, its share/caustics linking to the source tree's folders) the programs one
//      or two folders further down (tests/, methods/NAME/) find the same folder.
#include <filesystem>

#include <nlohmann/json.hpp>

namespace caustics {

// The data folder; throws InputError (exit 2) when $CAUSTICS_DATA_DIR is not a folder with scenes/, or
// when it is unset and no share/caustics with scenes/ is found, naming where it looked.
std::filesystem::path data_directory();

// data_directory()/build.json: {"version", and "source_dir" in a build tree or "git_commit" (at the
// last build) in an installation}. An empty object when the file or the data folder is missing.
nlohmann::json build_description();

}  // namespace caustics
