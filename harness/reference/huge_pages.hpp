#pragma once
// Large buffers backed by 2 MiB pages. A reference's per-run memory (the camera sums: 50 MB for a
// 1024 x 768 view and 8 replicas; its per-pixel tables and result images) is touched for the first
// time on every run. With 4 KiB pages each first touch is a page fault, and on a virtual machine a
// fault costs ~15 us: 190 ms for the camera sums alone, several times the photons' own tracing at 1e6
// photons (bench/bench_reference.cpp). Huge pages take 512 times fewer faults.
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

namespace caustics {

// Zeroed memory of at least `bytes`: mapped fresh and advised to use huge pages from kHugeThreshold on
// (aligned to 2 MiB so that every page of it can be one), from calloc below. Throws std::bad_alloc.
void* allocate_zeroed(std::size_t bytes);
void free_zeroed(void* p, std::size_t bytes);

// Asks for huge pages on the 2 MiB-aligned part of [p, p + bytes) before it is first touched (memory
// whose allocation the caller does not control, such as an Image's pixels after reserve()).
void advise_huge_pages(void* p, std::size_t bytes);

inline constexpr std::size_t kHugeThreshold = std::size_t{1} << 20;

// A std::allocator replacement for large arrays of trivially constructible values.
template <class T>
struct HugePageAllocator {
    using value_type = T;
    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
    T* allocate(std::size_t n) {
        if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
        return static_cast<T*>(allocate_zeroed(n * sizeof(T)));
    }
    void deallocate(T* p, std::size_t n) noexcept { free_zeroed(p, n * sizeof(T)); }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
};

// The reference's fixed-point sums (ReferenceSums).
using SumVector = std::vector<std::int64_t, HugePageAllocator<std::int64_t>>;

}  // namespace caustics
