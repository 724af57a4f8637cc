#pragma once
// One heap policy for every process that times methods, so that a run's frame time does not depend on
// what the process did before it (docs/design.md section 6).
//
// glibc's malloc adapts on its own: blocks from 128 KiB on are mapped fresh and unmapped on free, and
// freed memory at the heap's top is returned to the system, until the first large block is freed, which
// raises both limits for the rest of the process. A method that allocates large temporaries every frame
// then pays a page fault per 4 KiB of them on every frame (about 15 us each on a virtual machine: some 80 ms
// of one method's 120 ms frame stage on `sine`) in a fresh process, and nothing in a sweep worker whose
// earlier runs raised the limits: the same run took 138 ms in `caustics render` and 46 ms inside the quick
// sweep. Fixing the limits at start-up gives every run the warm heap a long-running renderer has
// after its first frames (the warm-up frames then warm it for the timed ones).
#include <cstddef>

namespace caustics {

// Blocks below this are served from the heap (glibc's largest allowed value, 32 MiB on 64-bit).
inline constexpr std::size_t kHeapMapThreshold = std::size_t{32} << 20;
// Freed memory kept at the top of each heap before it is returned to the system.
inline constexpr std::size_t kHeapTrimThreshold = std::size_t{256} << 20;

// Sets both limits (and so turns glibc's adaptation off). Returns false where the C library does not
// take them (not glibc, or under a sanitizer's allocator): nothing changes then.
bool apply_heap_policy();

}  // namespace caustics
