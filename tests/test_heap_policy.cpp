// The heap policy of timing processes (util/heap_policy.hpp): after it, a block of several MiB comes from
// the heap rather than a fresh mapping, and freeing it keeps its memory for the next one, so that a
// method allocating such blocks every frame pays its page faults once, in the warm-up, in any process.
#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <caustics/util/heap_policy.hpp>

namespace caustics {
namespace {

// The blocks escape through it, so that the compiler cannot drop an allocation whose memory no one reads.
char* volatile g_sink = nullptr;

TEST(HeapPolicy, LargeBlocksComeFromTheHeapAndStayMapped) {
#if !defined(__GLIBC__) || defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "glibc's malloc only (a sanitizer's allocator ignores the limits)";
#else
    ASSERT_TRUE(apply_heap_policy());
    constexpr std::size_t kBlock = std::size_t{8} << 20;   // above glibc's default 128 KiB mapping threshold
    const struct mallinfo2 before = mallinfo2();
    char* first = static_cast<char*>(std::malloc(kBlock));
    ASSERT_NE(first, nullptr);
    std::memset(first, 1, kBlock);
    g_sink = first;
    const struct mallinfo2 during = mallinfo2();
    EXPECT_EQ(during.hblks, before.hblks) << "the block was mapped on its own";
    EXPECT_EQ(during.hblkhd, before.hblkhd);
    std::free(first);
    const struct mallinfo2 after = mallinfo2();
    EXPECT_GE(after.fordblks, kBlock) << "the freed block was returned to the system";
    // The next frame's block reuses that memory: the heaps do not grow.
    char* second = static_cast<char*>(std::malloc(kBlock));
    ASSERT_NE(second, nullptr);
    g_sink = second;
    EXPECT_EQ(mallinfo2().arena, after.arena);
    std::free(second);
#endif
}

}  // namespace
}  // namespace caustics
