#include <caustics/util/hash.hpp>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

namespace caustics {

namespace {
constexpr std::uint64_t kFnvPrime = 0x100000001B3ull;
}

void Hash128::bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::uint64_t a = a_, b = b_;
    for (std::size_t i = 0; i < size; ++i) {
        a = (a ^ p[i]) * kFnvPrime;
        b = (b ^ static_cast<unsigned char>(p[i] + 0x5Bu)) * kFnvPrime;
    }
    a_ = a;
    b_ = b;
}

void Hash128::text(std::string_view s) {
    u64(s.size());
    bytes(s.data(), s.size());
}

void Hash128::u64(std::uint64_t v) {
    unsigned char buf[8];
    for (int i = 0; i < 8; ++i) buf[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(buf, 8);
}

void Hash128::f64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
}

std::string Hash128::hex() const {
    char buf[33];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(high()),
                  static_cast<unsigned long long>(low()));
    return buf;
}

std::uint64_t checksum64(const void* data, std::size_t size) {
    Hash128 h;
    h.bytes(data, size);
    return h.low() ^ mix64(h.high());
}

bool read_file_bytes(const std::string& path, std::string& out) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) return false;
    out = std::move(ss).str();
    return true;
}

}  // namespace caustics
