#pragma once
// The method registry. A method registers itself from its own source file:
//
//   CAUSTICS_REGISTER_METHOD(my_method_info);   // my_method_info: a function returning MethodInfo
//
// Built into the program (methods/CMakeLists.txt), methods are object libraries so the linker keeps their
// registration objects and no shared file names a method. Built as a plugin (caustics_add_method() in a
// project outside this repository, which defines CAUSTICS_PLUGIN), the same line records the method in
// the plugin's own list instead, which the program takes when it loads the library (api/plugin.hpp).
//
// Every method remembers where it came from (a source file and line, or a plugin library), so that a
// second method of a taken name is refused with a message naming both, never silently replacing one.
#include <string>
#include <vector>

#include <caustics/api/method.hpp>

namespace caustics {

using MethodFactory = MethodInfo (*)();

// Sorted by name.
std::vector<const MethodInfo*> registered_methods();
// nullptr if unknown.
const MethodInfo* find_method(const std::string& name);
// Throws InputError (listing the known names) if unknown.
const MethodInfo& require_method(const std::string& name, const std::string& option = "--method");
// Where the method of that name was registered ("" if unknown): "methods/x/x.cpp:40", or a plugin
// library with the source line inside it.
std::string method_origin(const std::string& name);

// The build type a plugin method was compiled with ("Release", "Debug", "none" when the plugin's build
// set none); "" for a method compiled into the program (it has the program's build type).
std::string method_build_type(const std::string& name);

// Adds the method `make` describes, registered at `origin` (for a plugin, with its build type). A name
// already taken is refused with an InputError naming `origin` (the file at fault), the name and where the
// first registration came from; the first method stays.
void add_method(MethodFactory make, const std::string& origin, const std::string& build_type = "");

// The registrations refused while static initialisation ran (when nothing can report them), one message
// each as add_method words it. The program refuses to start while there is any.
std::vector<std::string> registration_conflicts();

struct MethodRegistrar {
    MethodRegistrar(MethodFactory make, const char* origin);
};

}  // namespace caustics

#define CAUSTICS_CONCAT_INNER(a, b) a##b
#define CAUSTICS_CONCAT(a, b) CAUSTICS_CONCAT_INNER(a, b)
#define CAUSTICS_STRINGIFY_INNER(a) #a
#define CAUSTICS_STRINGIFY(a) CAUSTICS_STRINGIFY_INNER(a)

// The registration's origin: the method's folder in its project (caustics_add_method() defines
// CAUSTICS_METHOD_DIR, "methods/NAME/") and the file name and line. Not __FILE__, whose path depends on
// how the compiler was started (and a compiler cache may hand back an object built elsewhere).
#ifndef CAUSTICS_METHOD_DIR
#define CAUSTICS_METHOD_DIR ""
#endif
#define CAUSTICS_REGISTRATION_SITE CAUSTICS_METHOD_DIR __FILE_NAME__ ":" CAUSTICS_STRINGIFY(__LINE__)

#ifdef CAUSTICS_PLUGIN
#include <caustics/api/plugin.hpp>
#define CAUSTICS_REGISTER_METHOD(make_info)                                                             \
    static const ::caustics::plugin::LocalRegistrar CAUSTICS_CONCAT(caustics_registrar_, __LINE__){   \
        make_info, CAUSTICS_REGISTRATION_SITE}
#else
#define CAUSTICS_REGISTER_METHOD(make_info)                                                             \
    static const ::caustics::MethodRegistrar CAUSTICS_CONCAT(caustics_registrar_, __LINE__){           \
        make_info, CAUSTICS_REGISTRATION_SITE}
#endif
