#pragma once
// Small helpers shared by the tests that drive the `caustics` program through a shell.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace caustics::test_support {

// The whole file as bytes ("" if it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Single-quoted for /bin/sh, embedded quotes escaped.
inline std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

}  // namespace caustics::test_support
