// The zeroed buffers of images and of the reference's per-run sums (util/huge_pages.hpp) and the
// per-batch sampler seeds (photon_sampler.hpp): speed work that must not change what is computed.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/reference/photon_sampler.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/util/huge_pages.hpp>
#include <caustics/util/image.hpp>

using namespace caustics;

TEST(ReferenceBuffers, AllocationsAreZeroedBelowAndAboveTheHugePageThreshold) {
    for (const std::size_t bytes : {std::size_t{1}, std::size_t{4096}, kHugeThreshold - 8, kHugeThreshold,
                                    std::size_t{5} << 20, (std::size_t{9} << 20) + 24}) {
        // Dirty memory of the same size first, so that a reused block would show.
        {
            auto* p = static_cast<unsigned char*>(allocate_zeroed(bytes));
            std::memset(p, 0xA5, bytes);
            free_zeroed(p, bytes);
        }
        auto* p = static_cast<unsigned char*>(allocate_zeroed(bytes));
        ASSERT_NE(p, nullptr);
        EXPECT_TRUE(std::all_of(p, p + bytes, [](unsigned char c) { return c == 0; })) << bytes << " bytes";
        if (bytes >= kHugeThreshold && !kHeapOnly) {
            EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % (std::size_t{2} << 20), 0u);
        }
        std::memset(p, 0x5A, bytes);   // writable to the last byte
        EXPECT_EQ(p[bytes - 1], 0x5A);
        free_zeroed(p, bytes);
    }
}

// Freed large blocks are kept for reuse up to a cap, the oldest given back first: more than the cap's
// worth of dirtied blocks, freed, must come back zeroed and aligned, and no larger than asked.
TEST(ReferenceBuffers, KeptBlocksComeBackZeroedPastTheCap) {
    const std::size_t bytes = (std::size_t{100} << 20) + 12;   // three of them exceed the 256 MiB cap
    std::vector<unsigned char*> blocks;
    for (int i = 0; i < 3; ++i) {
        blocks.push_back(static_cast<unsigned char*>(allocate_zeroed(bytes)));
        std::memset(blocks.back(), 0xC3, bytes);
    }
    for (unsigned char* p : blocks) free_zeroed(p, bytes);
    for (unsigned char*& p : blocks) {
        p = static_cast<unsigned char*>(allocate_zeroed(bytes));
        EXPECT_TRUE(std::all_of(p, p + bytes, [](unsigned char c) { return c == 0; }));
        if (!kHeapOnly) {
            EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % (std::size_t{2} << 20), 0u);
        }
    }
    for (unsigned char* p : blocks) free_zeroed(p, bytes);
}

// SumVector's value-initialisation writes nothing: the zeros must come from the allocation itself.
TEST(ReferenceBuffers, SumVectorsStartAtZero) {
    for (int round = 0; round < 3; ++round) {
        SumVector v(3'000'000 + round);
        EXPECT_TRUE(std::all_of(v.begin(), v.end(), [](std::int64_t x) { return x == 0; }));
        std::fill(v.begin(), v.end(), -1);
        SumVector copy = v;
        EXPECT_EQ(copy, v);
    }
    SumVector small(10);
    EXPECT_TRUE(std::all_of(small.begin(), small.end(), [](std::int64_t x) { return x == 0; }));
}

// An Image's zeros come from its allocation too (no pass over the pixels); other fills are written.
TEST(ReferenceBuffers, ImagesStartAtTheirFill) {
    for (const auto& [w, h] : {std::pair{3, 2}, std::pair{1024, 768}, std::pair{1500, 1001}}) {
        for (int round = 0; round < 2; ++round) {
            {   // a dirtied image of the same size first, so that reused memory would show
                Image dirty(w, h, 1, 7.0f);
                EXPECT_EQ(dirty.pixels.back(), 7.0f);
            }
            const Image zero(w, h);
            ASSERT_EQ(zero.pixels.size(), static_cast<std::size_t>(w) * h);
            EXPECT_TRUE(std::all_of(zero.pixels.begin(), zero.pixels.end(), [](float x) { return x == 0.0f && !std::signbit(x); }));
        }
        const Image negative_zero(w, h, 3, -0.0f);
        EXPECT_TRUE(std::all_of(negative_zero.pixels.begin(), negative_zero.pixels.end(), [](float x) { return std::signbit(x); }));
        Image copy = negative_zero;
        EXPECT_EQ(copy.pixels, negative_zero.pixels);
        copy.pixels.resize(copy.pixels.size() + 5, 0.0f);   // an explicit value is always written
        EXPECT_EQ(copy.pixels.back(), 0.0f);
    }
}

TEST(ReferenceBuffers, PreparingFreshMemoryKeepsItsContents) {
    std::vector<float> v;
    const std::size_t n = 786432;   // one 1024 x 768 image
    v.reserve(n);
    prepare_fresh_memory(v.data(), n * sizeof(float));
    v.resize(n, 0.0f);
    EXPECT_TRUE(std::all_of(v.begin(), v.end(), [](float x) { return x == 0.0f; }));
    for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<float>(i);
    prepare_fresh_memory(v.data(), n * sizeof(float));
    for (std::size_t i = 0; i < n; i += 997) ASSERT_EQ(v[i], static_cast<float>(i));
}

// The seeds hashed once per light and replica give every photon the sampler it had before.
TEST(ReferenceBuffers, SeededSamplersAreThePhotonsOwn) {
    for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent})
        for (const std::uint64_t seed : {std::uint64_t{1}, std::uint64_t{0x51ED270B27D5A3C2ull}})
            for (const std::uint32_t replica : {0u, 7u})
                for (const std::uint64_t index : {std::uint64_t{0}, std::uint64_t{1}, std::uint64_t{65537},
                                                  std::uint64_t{0xFFFFFFFFull}, std::uint64_t{0x100000003ull}}) {
                    const PhotonSampler direct(kind, seed, replica, index);
                    const SamplerSeeds seeds = PhotonSampler::seeds(kind, seed, replica);
                    const PhotonSampler seeded(seeds, index);
                    double a1, a2, b1, b2;
                    direct.get2(0, a1, a2);
                    PhotonSampler::emission(seeds, index, b1, b2);
                    EXPECT_EQ(std::memcmp(&a1, &b1, sizeof a1), 0);
                    EXPECT_EQ(std::memcmp(&a2, &b2, sizeof a2), 0);
                    for (int dim = 0; dim < 20; ++dim) {
                        const double x = direct.get(dim), y = seeded.get(dim);
                        EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0) << "dimension " << dim;
                    }
                }
}
