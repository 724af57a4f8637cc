// The heap policy of timing processes (see heap_policy.hpp).
#include <caustics/util/heap_policy.hpp>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace caustics {

bool apply_heap_policy() {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
    // mallopt returns 1 on success. The mapping threshold first: setting either limit ends the adaptation.
    const bool mapped = mallopt(M_MMAP_THRESHOLD, static_cast<int>(kHeapMapThreshold)) == 1;
    const bool trimmed = mallopt(M_TRIM_THRESHOLD, static_cast<int>(kHeapTrimThreshold)) == 1;
    return mapped && trimmed;
#else
    return false;
#endif
}

}  // namespace caustics
