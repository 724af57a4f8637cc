// See huge_pages.hpp.
#include <caustics/util/huge_pages.hpp>

#include <cstdlib>
#include <cstring>
#include <mutex>
#include <utility>
#include <vector>

#include <sys/mman.h>

namespace caustics {
namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;

std::size_t round_up(std::size_t bytes, std::size_t to) { return (bytes + to - 1) / to * to; }

// MADV_POPULATE_WRITE (Linux 5.14); older kernels refuse it and the pages fault in one by one as before.
#ifdef MADV_POPULATE_WRITE
constexpr int kPopulateWrite = MADV_POPULATE_WRITE;
#else
constexpr int kPopulateWrite = 23;
#endif

// Freed large blocks kept mapped for reuse, up to kCachedBytes in all, the oldest unmapped first to make
// room: a reused block costs one memset where a fresh one costs its page faults and the kernel's
// clearing. Renderers allocate and free their output images every frame (a 1024 x 768 camera view is
// 3 MB); with fresh mappings each time, an image-space method's camera lookup took 0.7-1 ms longer per
// frame.
constexpr std::size_t kCachedBytes = std::size_t{256} << 20;

struct BlockCache {
    std::mutex mutex;
    std::vector<std::pair<std::size_t, void*>> blocks;   // (mapped size, address), oldest first
    std::size_t bytes = 0;
    // Room for every block the cap allows (each is at least one huge page): keeping a block never
    // allocates, so freeing never throws.
    BlockCache() { blocks.reserve(kCachedBytes / kHugePage); }
};

BlockCache& block_cache() {
    static BlockCache* cache = new BlockCache;   // never destroyed: buffers may be freed during exit
    return *cache;
}

bool on_heap(std::size_t bytes) { return kHeapOnly || bytes < kHugeThreshold; }

void* take_cached(std::size_t size) {
    BlockCache& c = block_cache();
    std::lock_guard<std::mutex> lock(c.mutex);
    for (std::size_t i = c.blocks.size(); i-- > 0;)
        if (c.blocks[i].first == size) {
            void* p = c.blocks[i].second;
            c.blocks.erase(c.blocks.begin() + static_cast<std::ptrdiff_t>(i));
            c.bytes -= size;
            return p;
        }
    return nullptr;
}

// Keeps block p (mapped size `size`), unmapping the oldest blocks when the cap needs room, and p itself
// when it alone exceeds the cap.
void keep_cached(void* p, std::size_t size) noexcept {
    if (size > kCachedBytes) {
        munmap(p, size);
        return;
    }
    BlockCache& c = block_cache();
    {
        std::lock_guard<std::mutex> lock(c.mutex);
        std::size_t drop = 0;
        while (c.bytes + size > kCachedBytes) c.bytes -= c.blocks[drop++].first;
        for (std::size_t i = 0; i < drop; ++i) munmap(c.blocks[i].second, c.blocks[i].first);
        c.blocks.erase(c.blocks.begin(), c.blocks.begin() + static_cast<std::ptrdiff_t>(drop));
        c.blocks.emplace_back(size, p);   // within the reserved capacity
        c.bytes += size;
    }
}

}  // namespace

void* allocate_zeroed(std::size_t bytes) {
    if (on_heap(bytes)) {
        // calloc would map a fresh block page fault by page fault (~15 us each on a virtual machine).
        void* p = std::malloc(bytes > 0 ? bytes : 1);
        if (!p) throw std::bad_alloc();
        prepare_fresh_memory(p, bytes);
        std::memset(p, 0, bytes);
        return p;
    }
    const std::size_t size = round_up(bytes, kHugePage);
    if (void* reused = take_cached(size)) {
        std::memset(reused, 0, bytes);   // the caller sees `bytes` of it
        return reused;
    }
    // Map one huge page more than needed, then unmap the unaligned head and the tail: the kernel backs
    // a region with huge pages only where they fit whole and aligned.
    void* raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const auto start = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t aligned = round_up(start, kHugePage);
    if (aligned > start) munmap(raw, aligned - start);
    const std::size_t tail = start + size + kHugePage - (aligned + size);
    if (tail > 0) munmap(reinterpret_cast<void*>(aligned + size), tail);
    // Advice only: without transparent huge pages the memory is still valid (and zero), in 4 KiB pages.
    madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);
    return reinterpret_cast<void*>(aligned);
}

void free_zeroed(void* p, std::size_t bytes) {
    if (!p) return;
    if (on_heap(bytes)) return std::free(p);
    keep_cached(p, round_up(bytes, kHugePage));
}

void prepare_fresh_memory(void* p, std::size_t bytes) {
    if (bytes < (std::size_t{64} << 10)) return;   // a few pages: not worth the calls
    const auto start = reinterpret_cast<std::uintptr_t>(p);
    const std::uintptr_t first = round_up(start, kHugePage);
    const std::uintptr_t last = (start + bytes) / kHugePage * kHugePage;
    if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
    // Then the whole range in one call rather than one fault per 4 KiB page (about 1.7x faster for an
    // Image of 3 MB here). The range is rounded out to whole pages: populating a page writes nothing.
    const std::uintptr_t page = 4096, from = start / page * page, to = round_up(start + bytes, page);
    madvise(reinterpret_cast<void*>(from), to - from, kPopulateWrite);
}

}  // namespace caustics
