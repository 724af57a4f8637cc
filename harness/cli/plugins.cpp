#include "plugins.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <filesystem>
#include <vector>

#include <caustics/api/plugin.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/util/build_info.hpp>
#include <caustics/util/errors.hpp>

namespace caustics::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kVariable = "CAUSTICS_PLUGIN_PATH";

std::vector<fs::path> libraries_in(const fs::path& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        throw invalid_value(kVariable, "'" + folder.string() + "' is not a folder",
                            "folders of plugin libraries (*.so), separated by ':'");
    std::vector<fs::path> out;
    for (const auto& entry : fs::directory_iterator(folder, ec))
        if (entry.path().extension() == ".so" && entry.is_regular_file(ec)) out.push_back(entry.path());
    std::sort(out.begin(), out.end());
    return out;
}

void load_plugin(const fs::path& library) {
    const std::string path = library.string();
    // RTLD_NOW: a symbol the program lacks (a plugin built against another harness) fails here, with the
    // loader's message, instead of at its first call. RTLD_LOCAL: plugins do not see each other.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        const char* why = dlerror();
        throw InputError(path, "", std::string("cannot load the library: ") + (why ? why : "unknown reason") +
                                       "; valid: a shared library built with caustics_add_method() against this "
                                       "installation (CAUSTICS_PLUGIN_PATH lists such files or folders of them)");
    }
    // Never closed: the methods' code and their MethodInfo functions live in it.
    auto entry = reinterpret_cast<plugin::EntryFunction>(dlsym(handle, plugin::kEntryPoint));
    if (!entry)
        throw InputError(path, "", std::string("not a caustics plugin: it exports no ") + plugin::kEntryPoint +
                                       " (build methods with caustics_add_method() from the installed package)");
    plugin::Manifest manifest;
    entry(&manifest);
    const std::string built_for = manifest.sdk_version ? manifest.sdk_version : "an unknown version";
    if (built_for != project_version())
        throw InputError(path, "", "built against caustics " + built_for + ", this program is caustics " +
                                       project_version() + "; rebuild the plugin against this installation");
    for (std::size_t i = 0; i < manifest.count; ++i)
        add_method(manifest.methods[i].make, path + " (" + manifest.methods[i].where + ")",
                   manifest.build_type ? manifest.build_type : "unknown");
}

}  // namespace

void load_plugins(const std::string& path_list) {
    std::size_t start = 0;
    while (start <= path_list.size()) {
        const std::size_t end = std::min(path_list.find(':', start), path_list.size());
        if (end > start)
            for (const fs::path& library : libraries_in(path_list.substr(start, end - start))) load_plugin(library);
        start = end + 1;
    }
}

}  // namespace caustics::cli
