#pragma once
// Deterministic binning of items into horizontal bands of rows, shared by the rasterizers (triangles,
// G-buffers, splats): a first parallel pass counts, per fixed chunk of items, how many entries each band
// gets (counts[chunk * bands + band]); band_offsets() turns the counts into write cursors; a second pass
// writes the entries. Offsets are band-major, then chunk order, so every band lists its items in input
// order whatever the thread count.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace caustics {

// Fills cursors[chunk * bands + band] (where chunk c writes its first entry of band b) and band_start
// (bands + 1 entries: band b's entries are [band_start[b], band_start[b + 1])). Returns the total.
inline std::uint32_t band_offsets(const std::vector<std::uint32_t>& counts, std::size_t chunks, std::size_t bands,
                                  std::vector<std::uint32_t>& cursors, std::vector<std::uint32_t>& band_start) {
    cursors.resize(chunks * bands);
    band_start.resize(bands + 1);
    std::uint32_t running = 0;
    for (std::size_t b = 0; b < bands; ++b) {
        band_start[b] = running;
        for (std::size_t c = 0; c < chunks; ++c) {
            cursors[c * bands + b] = running;
            running += counts[c * bands + b];
        }
    }
    band_start[bands] = running;
    return running;
}

}  // namespace caustics
