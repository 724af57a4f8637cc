#pragma once
// Loading method plugins at start-up (api/plugin.hpp).
#include <string>

namespace caustics::cli {

// Loads every shared library (a file named *.so) in the folders of `path_list`, colon-separated like
// PATH (empty entries are skipped): folders in the order given, libraries in a folder by name. Each must
// export caustics_plugin_register_v2, be built against this version of caustics, and register only names
// not taken yet. Throws InputError (exit 2) naming the library (or the folder) and what is wrong; the
// libraries loaded before it stay registered.
void load_plugins(const std::string& path_list);

}  // namespace caustics::cli
