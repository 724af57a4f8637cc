#pragma once
// Content hashing for cache keys and checksums. Not cryptographic: it detects changed inputs and
// damaged files, it does not resist an adversary.
//
// Hash128 runs two 64-bit FNV-1a streams from different offset bases, each folded through a
// splitmix64 finaliser at the end, and prints them as 32 hex digits.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace caustics {

// splitmix64 finaliser (Steele, Lea and Flood 2014): a bijective 64-bit mixer.
constexpr std::uint64_t mix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

class Hash128 {
public:
    void bytes(const void* data, std::size_t size);
    // Length-prefixed, so ("ab", "c") and ("a", "bc") differ.
    void text(std::string_view s);
    void u64(std::uint64_t v);
    void f64(double v);
    std::string hex() const;
    std::uint64_t low() const { return mix64(a_); }
    std::uint64_t high() const { return mix64(b_ ^ 0xA5A5A5A5A5A5A5A5ull); }

private:
    std::uint64_t a_ = 0xCBF29CE484222325ull;  // FNV-1a 64 offset basis
    std::uint64_t b_ = 0x84222325CBF29CE4ull;  // a second, different basis
};

// One 64-bit checksum of a byte range (used for cache payloads).
std::uint64_t checksum64(const void* data, std::size_t size);

// Reads a whole file into a string; false if it cannot be read.
bool read_file_bytes(const std::string& path, std::string& out);

}  // namespace caustics
