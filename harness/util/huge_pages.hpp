#pragma once
// Zeroed memory for large arrays, backed by 2 MiB pages. Images (util/image.hpp) and a reference's
// per-run sums and tables (the camera sums: 50 MB for a 1024 x 768 view and 8 replicas) are fresh
// memory on every run. With 4 KiB pages each first touch is a page fault, and on a virtual machine a
// fault costs ~15 us: 190 ms for the camera sums alone, several times the photons' own tracing at 1e6
// photons (bench/bench_reference.cpp). Huge pages take 512 times fewer faults, and memory that comes
// zeroed needs no pass to clear it.
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace caustics {

// Zeroed memory of at least `bytes`. From kHugeThreshold on: a block freed earlier, cleared (up to
// 256 MiB of freed blocks stay mapped for reuse, the oldest unmapped first), or a fresh mapping advised
// to use huge pages (aligned to 2 MiB so that every page of it can be one, the size rounded up to 2 MiB),
// which comes zeroed. Below: heap memory, mapped in one call where it is fresh, then cleared. Throws
// std::bad_alloc.
void* allocate_zeroed(std::size_t bytes);
void free_zeroed(void* p, std::size_t bytes);

// Memory whose allocation the caller does not control (a std::vector's after reserve()), before it
// is first touched: huge pages on its 2 MiB-aligned part, the rest mapped in one call (from 64 KiB on).
// Advice only (the contents do not change); a kernel without either just faults as before.
void prepare_fresh_memory(void* p, std::size_t bytes);

// Below 1 MiB a block comes from the heap: a 2 MiB page per allocation would waste up to 8 times the
// memory of a 256 x 256 receiver map, and freed heap blocks are reused already mapped (ten such maps,
// a reference's 2 + R, cost about 0.6 ms from the heap and 4-5 ms on fresh huge pages here).
inline constexpr std::size_t kHugeThreshold = std::size_t{1} << 20;

// AddressSanitizer tracks heap blocks, not mappings: under it every size takes the heap's path (no
// huge pages, no kept blocks), so that overflows and uses after free stay visible.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kHeapOnly = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kHeapOnly = true;
#else
inline constexpr bool kHeapOnly = false;
#endif
#else
inline constexpr bool kHeapOnly = false;
#endif

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
    // Value-initialisation (resize(n), SumVector(n)) writes nothing: allocate() returns zeroed memory,
    // whose pages, when freshly mapped, are then mapped only where the run touches them (a 50 MB memset
    // less per reference; a reused block was cleared by allocate()). The element is default-initialised
    // over those zeros, which for the trivial types stored here (integers, floats, PixelInfo) reads as
    // zero with every compiler this project supports. So an element is zero only when it is new memory:
    // shrinking such a vector and growing it again within its capacity with resize(n) keeps the old
    // values (resize(n, 0) writes zeros).
    template <class U>
    void construct(U* p) {
        if constexpr (std::is_trivially_default_constructible_v<U>) ::new (static_cast<void*>(p)) U;
        else ::new (static_cast<void*>(p)) U();
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
};

}  // namespace caustics
