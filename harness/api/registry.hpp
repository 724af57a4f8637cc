#pragma once
// The method registry. A method registers itself from its own source file:
//
//   CAUSTICS_REGISTER_METHOD(my_method_info);   // my_method_info: a function returning MethodInfo
//
// Methods are compiled as object libraries (methods/CMakeLists.txt) so the linker keeps their
// registration objects; no shared file names a method.
#include <string>
#include <vector>

#include <caustics/api/method.hpp>

namespace caustics {

// Sorted by name.
std::vector<const MethodInfo*> registered_methods();
// nullptr if unknown.
const MethodInfo* find_method(const std::string& name);
// Throws InputError (listing the known names) if unknown.
const MethodInfo& require_method(const std::string& name, const std::string& option = "--method");

struct MethodRegistrar {
    explicit MethodRegistrar(MethodInfo (*make)());
};

}  // namespace caustics

#define CAUSTICS_CONCAT_INNER(a, b) a##b
#define CAUSTICS_CONCAT(a, b) CAUSTICS_CONCAT_INNER(a, b)
#define CAUSTICS_REGISTER_METHOD(make_info)                                                    \
    static const ::caustics::MethodRegistrar CAUSTICS_CONCAT(caustics_registrar_, __LINE__){make_info}
