// The method registry refuses a second method of a taken name: the first stays, and the refusal names
// both origins (this file registers two methods named "registry_test_twin"; the `caustics` program
// refuses to start on such a conflict, see harness/cli/main.cpp).
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include <caustics/api/registry.hpp>
#include <caustics/util/errors.hpp>

namespace caustics {
namespace {

MethodInfo twin(const std::string& doc) {
    MethodInfo info;
    info.name = "registry_test_twin";
    info.doc = doc;
    info.params = {{"grid", ParamType::Int, "1", 1, 1, {}, "no grid"},
                   {"iterations", ParamType::Int, "1", 1, 1, {}, "no iterations"}};
    info.create = [](const ParamSet&) -> std::unique_ptr<Method> { return nullptr; };
    return info;
}
MethodInfo first_twin() { return twin("the first"); }
MethodInfo second_twin() { return twin("the second"); }

constexpr int kFirstLine = __LINE__ + 1;
CAUSTICS_REGISTER_METHOD(first_twin);
constexpr int kSecondLine = __LINE__ + 1;
CAUSTICS_REGISTER_METHOD(second_twin);

std::string origin_at(int line) { return "test_registry.cpp:" + std::to_string(line); }

TEST(Registry, SecondRegistrationOfANameIsRefusedNamingBoth) {
    const auto conflicts = registration_conflicts();
    ASSERT_EQ(conflicts.size(), 1u);
    EXPECT_NE(conflicts[0].find("registry_test_twin"), std::string::npos) << conflicts[0];
    EXPECT_EQ(conflicts[0].rfind(origin_at(kSecondLine), 0), 0u) << "names the refused one first: " << conflicts[0];
    EXPECT_NE(conflicts[0].find("already registered by " + origin_at(kFirstLine)), std::string::npos) << conflicts[0];
}

TEST(Registry, FirstRegistrationStays) {
    const MethodInfo* info = find_method("registry_test_twin");
    ASSERT_NE(info, nullptr);
    EXPECT_EQ(info->doc, "the first");
    EXPECT_EQ(method_origin("registry_test_twin"), origin_at(kFirstLine));
    int named = 0;
    for (const MethodInfo* m : registered_methods()) named += m->name == "registry_test_twin";
    EXPECT_EQ(named, 1);
}

TEST(Registry, AddingATakenNameThrowsInputErrorNamingBothOrigins) {
    try {
        add_method(second_twin, "/plugins/libtwin.so (twin.cpp:7)");
        FAIL() << "a taken name was accepted";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.file(), "/plugins/libtwin.so (twin.cpp:7)");
        EXPECT_EQ(e.key(), "registry_test_twin");
        EXPECT_NE(what.find("already registered by " + origin_at(kFirstLine)), std::string::npos) << what;
    }
    EXPECT_EQ(find_method("registry_test_twin")->doc, "the first");
}

TEST(Registry, BuiltInMethodsRecordTheirSourceFile) {
    ASSERT_FALSE(registered_methods().empty());
    for (const MethodInfo* m : registered_methods()) {
        if (m->name == "registry_test_twin") continue;
        const std::string origin = method_origin(m->name);
        EXPECT_EQ(origin.rfind("methods/", 0), 0u) << m->name << ": " << origin;
        EXPECT_NE(origin.find(".cpp:"), std::string::npos) << m->name << ": " << origin;
    }
    EXPECT_EQ(method_origin("no_such_method"), "");
}

}  // namespace
}  // namespace caustics
