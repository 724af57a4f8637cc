// The entry point of a method plugin, compiled into every plugin library by caustics_add_method()
// (api/plugin.hpp). CAUSTICS_SDK_VERSION is the version of the installed caustics package,
// CAUSTICS_PLUGIN_BUILD_TYPE the plugin's own build type.
#include <vector>

#ifndef CAUSTICS_PLUGIN_BUILD_TYPE
#define CAUSTICS_PLUGIN_BUILD_TYPE "unknown"
#endif

#include <caustics/api/plugin.hpp>

namespace caustics::plugin {
namespace {

// Function-local static: the methods' registrars run during the library's static initialisation, in an
// unspecified order relative to this file.
std::vector<Method>& methods() {
    static std::vector<Method> list;
    return list;
}

}  // namespace

void record(MethodInfo (*make)(), const char* where) { methods().push_back({make, where}); }

}  // namespace caustics::plugin

extern "C" [[gnu::visibility("default")]] void caustics_plugin_register_v2(caustics::plugin::Manifest* manifest) {
    manifest->sdk_version = CAUSTICS_SDK_VERSION;
    manifest->methods = caustics::plugin::methods().data();
    manifest->count = caustics::plugin::methods().size();
    manifest->build_type = CAUSTICS_PLUGIN_BUILD_TYPE;
}
