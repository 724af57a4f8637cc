// Leapfrog wave propagation with a damping band and a row-granular narrow band (Mercier 2013, Sec. 4).
#include "wave_solver.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include <tbb/parallel_for.h>

namespace caustics::wave {
namespace {

// A row whose |phi| never exceeds this is set to exact zeros and leaves the narrow band.
constexpr float kBandThreshold = 1e-7f;
// Layers updated above the accumulating window: the zeroed layers' disturbance moves at most at the
// wave speed (courant layers per step, as fast as the window), so past these it no longer reaches the
// accumulating layers but for the scheme's exponentially small numerical precursor.
constexpr int kGuardLayers = 4;

std::uint32_t abs_bits(float v) { return std::bit_cast<std::uint32_t>(v) & 0x7fffffffu; }

// Cells into the damping band per index along one axis (1..sponge in the band, 0 inside).
std::vector<int> band_depth(int n, int sponge) {
    std::vector<int> d(static_cast<std::size_t>(n), 0);
    if (sponge <= 0) return d;
    for (int i = 0; i < n; ++i) d[static_cast<std::size_t>(i)] = std::clamp(std::max(sponge - i, i - (n - 1 - sponge)), 0, sponge);
    return d;
}

// One x row of the leapfrog update: p (phi^{n-1} in, phi^{n+1} out) from c (phi^n) and its four y/z
// neighbour rows; a, b, l: the factors of phi^n, phi^{n-1} and the Laplacian. Acc: what is added to
// acc (Accumulate in the header): 0 nothing, 1 phi^n + phi^{n-1} (every other step: half the
// accumulator traffic), 2 the flux term (phi^{n+1} - phi^{n-1}) (phi^n_{k+1} - phi^n_{k-1}). Returns
// the largest |phi^{n+1}| as its IEEE bits without the sign (a NaN compares above inf): an integer
// maximum, which vectorises where a float one would not (NaN ordering).
// Kept out of line: inlined into the tile loop, GCC no longer vectorises it.
template <bool Clamp, int Acc>
[[gnu::noinline]] std::uint32_t update_row(int n, Sides sides, const float* __restrict c, const float* __restrict ym, const float* __restrict yp,
                         const float* __restrict zm, const float* __restrict zp, float* __restrict p,
                         float* __restrict acc, const float* __restrict a, const float* __restrict b,
                         const float* __restrict l, int open_lo, int open_hi, std::int64_t& clamped) {
    std::uint32_t top = 0;
    std::int64_t negative = 0;
    // One cell, with its x neighbours `left` and `right` (at the x faces: zero, the cell itself for
    // mirror, the opposite end of the row for periodic).
    auto cell = [&](int i, float left, float right) {
        const float lap = left + right + ym[i] + yp[i] + zm[i] + zp[i] - 6.0f * c[i];
        float next = a[i] * c[i] - b[i] * p[i] + l[i] * lap;
        if constexpr (Acc == 1) acc[i] += c[i] + p[i];
        if constexpr (Clamp) {
            negative += next < 0.0f;
            next = next < 0.0f ? 0.0f : next;
        }
        if constexpr (Acc == 2) {  // only cells open_lo <= i < open_hi (CellWindow): an integer mask
            const float open = static_cast<float>(static_cast<int>(i >= open_lo) & static_cast<int>(i < open_hi));
            acc[i] += open * ((next - p[i]) * (zp[i] - zm[i]));
        }
        p[i] = next;
        const std::uint32_t bits = abs_bits(next);
        top = top > bits ? top : bits;
    };
    const float outside_left = sides == Sides::Zero ? 0.0f : sides == Sides::Mirror ? c[0] : c[n - 1];
    const float outside_right = sides == Sides::Zero ? 0.0f : sides == Sides::Mirror ? c[n - 1] : c[0];
    if (n == 1) {
        cell(0, outside_left, outside_right);
        clamped += negative;
        return top;
    }
    cell(0, outside_left, c[1]);
    for (int i = 1; i + 1 < n; ++i) cell(i, c[i - 1], c[i + 1]);   // branch-free: vectorised
    cell(n - 1, c[n - 2], outside_right);
    clamped += negative;
    return top;
}

// Normal CDF.
double gauss_cdf(double x) { return 0.5 * std::erfc(-x * 0.7071067811865476); }
constexpr double kSourceWidths = 4.0;  // a cell's pulse starts and ends this many widths from its time
constexpr double kSourceBucket = 1.0;  // time span of the injection's buckets

}  // namespace

Simulation::Simulation(const VolumeShape& shape, const Settings& settings)
    : shape_(shape), settings_(settings), cur_(shape.size(), 0.0f), prev_(shape.size(), 0.0f),
      depth_x_(band_depth(shape.nx, settings.side_x() == Sides::Zero ? settings.sponge : 0)),
      depth_y_(band_depth(shape.ny, settings.side_y() == Sides::Zero ? settings.sponge : 0)),
      depth_z_(band_depth(shape.nz, settings.sponge)),
      row_cur_(static_cast<std::size_t>(shape.ny) * shape.nz, 0), row_prev_(row_cur_),
      zero_row_(static_cast<std::size_t>(shape.nx), 0.0f) {
    // (1 + s/2) phi^{n+1} = 2 phi^n - (1 - s/2) phi^{n-1} + courant^2 L(phi^n), s = sigma dt.
    const int levels = std::max(settings.sponge, 0) + 1;
    const std::size_t nx = static_cast<std::size_t>(shape.nx);
    coef_.assign(3 * nx * static_cast<std::size_t>(levels), 0.0f);
    const double lam = settings.courant * settings.courant;
    for (int dyz = 0; dyz < levels; ++dyz)
        for (std::size_t i = 0; i < nx; ++i) {
            const int d = std::max(dyz, depth_x_[i]);
            const double m = settings.sponge > 0 ? static_cast<double>(d) / settings.sponge : 0.0;
            const double half_s = 0.5 * settings.sponge_strength * settings.courant * m * m;
            float* row = coef_.data() + 3 * nx * static_cast<std::size_t>(dyz);
            row[i] = static_cast<float>(2.0 / (1.0 + half_s));
            row[nx + i] = static_cast<float>((1.0 - half_s) / (1.0 + half_s));
            row[2 * nx + i] = static_cast<float>(lam / (1.0 + half_s));
        }
}

void Simulation::set_initial(const std::vector<float>& initial) {
    cur_ = initial;
    const std::size_t nx = static_cast<std::size_t>(shape_.nx);
    for (std::size_t r = 0; r < row_cur_.size(); ++r) {
        std::uint32_t top = 0;
        for (std::size_t c = r * nx; c < (r + 1) * nx; ++c) top = std::max(top, abs_bits(cur_[c]));
        const bool keep = !settings_.narrow_band || top > std::bit_cast<std::uint32_t>(kBandThreshold);
        if (!keep) std::fill_n(cur_.begin() + static_cast<std::ptrdiff_t>(r * nx), nx, 0.0f);
        row_cur_[r] = keep;
    }
    prev_ = cur_;
    row_prev_ = row_cur_;
}

void Simulation::set_source(Source source) {
    source_ = std::move(source);
    // Ordered by time bucket, then cell: the injection walks memory in order within a bucket (sorted by
    // time alone, its writes scatter over the sheet and miss the cache), and the order (so the result)
    // is fixed.
    std::sort(source_.cells.begin(), source_.cells.end(), [](const SourceCell& x, const SourceCell& y) {
        const double bx = std::floor(x.time / kSourceBucket), by = std::floor(y.time / kSourceBucket);
        return bx != by ? bx < by : x.cell < y.cell;
    });
    source_done_ = 0;
}

double Simulation::source_end() const {
    double last = -std::numeric_limits<double>::infinity();
    for (const SourceCell& c : source_.cells) last = std::max(last, static_cast<double>(c.time));
    return last + kSourceWidths * source_.width;
}

// Brings every source cell's displacement up to the time of level n (phi^n = cur_), raising phi^n and
// phi^{n-1} alike (the velocity is unchanged). Buckets whose pulses have not started end the scan,
// those whose pulses have ended leave it. Serial: the order of
// the additions, and so the result, does not depend on the thread count.
void Simulation::inject(int update_top) {
    if (source_.cells.empty()) return;
    const double t = steps_ * settings_.courant, t_prev = t - settings_.courant, w = source_.width;
    const std::size_t layer = static_cast<std::size_t>(shape_.nx) * shape_.ny;
    const std::size_t end_cell = static_cast<std::size_t>(update_top + 1) * layer;
    auto bucket_start = [](const SourceCell& c) { return std::floor(c.time / kSourceBucket) * kSourceBucket; };
    while (source_done_ < source_.cells.size() && bucket_start(source_.cells[source_done_]) + kSourceBucket + kSourceWidths * w < t_prev)
        ++source_done_;
    for (std::size_t q = source_done_; q < source_.cells.size(); ++q) {
        SourceCell& sc = source_.cells[q];
        if (bucket_start(sc) - kSourceWidths * w > t) break;
        if (sc.time - kSourceWidths * w > t || sc.time + kSourceWidths * w < t_prev) continue;
        if (sc.cell >= end_cell) continue;  // above the updated layers (the caller's window keeps them)
        // The displacement due by time t, less what is in: one CDF per cell and step.
        const double target = sc.weight * gauss_cdf((t - sc.time) / w);
        const float d = static_cast<float>(target - sc.injected);
        sc.injected = target;
        if (d == 0.0f) continue;
        cur_[sc.cell] += d;
        prev_[sc.cell] += d;
        const std::size_t r = sc.cell / static_cast<std::size_t>(shape_.nx);
        row_cur_[r] = 1;
        row_prev_[r] = 1;
    }
}

double Simulation::step(std::vector<float>* accumulate, int accumulate_top) {
    const VolumeShape& s = shape_;
    const int nx = s.nx, ny = s.ny, nz = s.nz;
    const std::size_t layer = static_cast<std::size_t>(nx) * ny;
    const std::uint32_t threshold_bits = std::bit_cast<std::uint32_t>(kBandThreshold);
    const bool band = settings_.narrow_band, clamp = settings_.clamp_negative;
    const Sides sides = settings_.side_x(), sides_y = settings_.side_y();
    const bool flux = settings_.accumulate == Accumulate::Flux;
    // Sum: levels are accumulated in pairs: the odd steps add phi^n + phi^{n-1}; flush() adds a last
    // odd one. Flux: every step.
    const bool pair = flux || steps_ % 2 == 1;
    if (accumulate) pending_ = !pair;
    // The window: layers above accumulate_top no longer accumulate (a layer leaving on an odd step
    // still owes its phi^{n-1}); layers above it + kGuardLayers are set to zero and no longer updated.
    accumulate_top = std::clamp(accumulate_top, -1, nz - 1);
    const int update_top = std::min(nz - 1, accumulate_top + kGuardLayers);
    if (accumulate && pair && !flux)
        for (int k = accumulate_top + 1; k <= std::min(accumulate_top_, nz - 1); ++k)
            for (std::size_t c = static_cast<std::size_t>(k) * layer; c < static_cast<std::size_t>(k + 1) * layer; ++c)
                (*accumulate)[c] += prev_[c];
    for (int k = update_top + 1; k <= std::min(update_top_, nz - 1); ++k) {
        const auto first = static_cast<std::ptrdiff_t>(static_cast<std::size_t>(k) * layer);
        std::fill_n(cur_.begin() + first, layer, 0.0f);
        std::fill_n(prev_.begin() + first, layer, 0.0f);
        std::fill_n(row_cur_.begin() + k * ny, ny, 0);
        std::fill_n(row_prev_.begin() + k * ny, ny, 0);
    }
    accumulate_top_ = accumulate_top;
    update_top_ = update_top;
    inject(update_top);
    const double time = steps_ * settings_.courant;  // of level n
    // Tiles of kTileRows y rows, each swept along z: the three z layers of a tile stay in cache, so phi^n
    // is read from memory once per step (a z slab's neighbour layers would not fit at 256^3).
    constexpr int kTileRows = 8;
    const int tiles = (ny + kTileRows - 1) / kTileRows;
    std::vector<std::uint32_t> tile_top(static_cast<std::size_t>(tiles), 0);
    std::vector<std::int64_t> tile_clamped(static_cast<std::size_t>(tiles), 0), tile_rows(static_cast<std::size_t>(tiles), 0);
    // row_prev_ becomes the flags of phi^{n+1}: each row reads its own flag before writing it, and
    // only row_cur_ (not written here) is read across rows, so tiles are independent.
    tbb::parallel_for(0, tiles, [&](int t) {
        std::uint32_t top = 0;
        std::int64_t clamped = 0, rows = 0;
        std::vector<float> saved;
        const int j0 = t * kTileRows, j1 = std::min(ny, j0 + kTileRows);
        for (int k = 0; k <= update_top; ++k)
        for (int j = j0; j < j1; ++j) {
            const std::size_t kk = static_cast<std::size_t>(k);
            const std::size_t r = kk * ny + j;
            // The y neighbour rows across the y faces: none (zero), the row itself (mirror) or the
            // opposite face's row (periodic).
            const bool wrap = sides_y == Sides::Periodic;
            const std::ptrdiff_t dym = j > 0 ? -1 : wrap ? ny - 1 : 0, dyp = j + 1 < ny ? 1 : wrap ? 1 - ny : 0;
            if (band) {
                const bool near = row_cur_[r] || row_prev_[r] || row_cur_[r + dym] || row_cur_[r + dyp] ||
                                  (k > 0 && row_cur_[r - ny]) || (k + 1 < nz && row_cur_[r + ny]);
                if (!near) continue;  // phi^n and phi^{n-1} are exact zeros here and around: so is phi^{n+1}
            }
            const std::size_t row = r * nx;
            const float* c = cur_.data() + row;
            const bool zero_y = sides_y == Sides::Zero;
            const float* ym = j > 0 || !zero_y ? c + dym * nx : zero_row_.data();
            const float* yp = j + 1 < ny || !zero_y ? c + dyp * nx : zero_row_.data();
            const float* zm = k > 0 ? c - layer : zero_row_.data();
            const float* zp = k + 1 < nz ? c + layer : zero_row_.data();
            float* p = prev_.data() + row;
            float* acc = accumulate && pair && k <= accumulate_top ? accumulate->data() + row : nullptr;
            const std::size_t dyz = static_cast<std::size_t>(std::max(depth_y_[static_cast<std::size_t>(j)], depth_z_[kk]));
            const float* a = coef_.data() + 3 * static_cast<std::size_t>(nx) * dyz;
            const float* b = a + nx;
            const float* l = b + nx;
            const int mode = acc ? (flux ? 2 : 1) : 0;
            // The row's cells still accumulating (CellWindow): level n stands for the times within half
            // a step of its own, so a cell whose stop S falls inside that interval takes the fraction
            // (S - time + dt/2) / dt of its flux (the sub-step interpolation of the stop: a stop
            // rounded to whole steps would modulate the captured tail with the stop's phase, a ripple
            // of a few tenths of a percent along a tilted front). [open_lo, open_hi): S > time - dt/2;
            // among them [part_lo, part_hi): S < time + dt/2.
            int open_lo = 0, open_hi = nx, part_lo = 0, part_hi = 0;
            const CellWindow& win = settings_.window;
            const double half = 0.5 * settings_.courant;
            const double c0 = std::isfinite(win.s0) ? win.s0 + win.sy * j + win.sz * static_cast<double>(k) - time : 0.0;
            if (flux && std::isfinite(win.s0)) {
                auto first_above = [&](double level) {  // the range of i with c0 + sx i > level
                    if (win.sx > 0.0) return std::pair<int, int>(static_cast<int>(std::clamp(std::floor((level - c0) / win.sx) + 1.0, 0.0, double(nx))), nx);
                    if (win.sx < 0.0) return std::pair<int, int>(0, static_cast<int>(std::clamp(std::ceil((c0 - level) / -win.sx), 0.0, double(nx))));
                    return c0 > level ? std::pair<int, int>(0, nx) : std::pair<int, int>(0, 0);
                };
                std::tie(open_lo, open_hi) = first_above(-half);
                const auto [full_lo, full_hi] = first_above(half);
                // Partial: open but not full (one end of the open range; the whole of it when sx = 0).
                if (full_lo >= full_hi) part_lo = open_lo, part_hi = open_hi;
                else if (win.sx > 0.0) part_lo = open_lo, part_hi = std::max(open_lo, full_lo);
                else part_lo = std::min(open_hi, full_hi), part_hi = open_hi;
            }
            saved.clear();
            if (acc && flux)
                for (int i = part_lo; i < part_hi; ++i) saved.push_back(p[i]);
            std::uint32_t row_top;
            if (clamp)
                row_top = mode == 2   ? update_row<true, 2>(nx, sides, c, ym, yp, zm, zp, p, acc, a, b, l, open_lo, open_hi, clamped)
                          : mode == 1 ? update_row<true, 1>(nx, sides, c, ym, yp, zm, zp, p, acc, a, b, l, open_lo, open_hi, clamped)
                                      : update_row<true, 0>(nx, sides, c, ym, yp, zm, zp, p, acc, a, b, l, open_lo, open_hi, clamped);
            else
                row_top = mode == 2   ? update_row<false, 2>(nx, sides, c, ym, yp, zm, zp, p, acc, a, b, l, open_lo, open_hi, clamped)
                          : mode == 1 ? update_row<false, 1>(nx, sides, c, ym, yp, zm, zp, p, acc, a, b, l, open_lo, open_hi, clamped)
                                      : update_row<false, 0>(nx, sides, c, ym, yp, zm, zp, p, acc, a, b, l, open_lo, open_hi, clamped);
            if (acc && flux)
                for (int i = part_lo; i < part_hi; ++i) {
                    const float part_flux = (p[i] - saved[static_cast<std::size_t>(i - part_lo)]) * (zp[i] - zm[i]);
                    const double w = std::clamp((c0 + win.sx * i + half) / settings_.courant, 0.0, 1.0);
                    acc[i] -= static_cast<float>(1.0 - w) * part_flux;
                }
            ++rows;
            top = std::max(top, row_top);
            const bool nonzero = !band || row_top > threshold_bits;
            if (!nonzero) std::fill_n(p, nx, 0.0f);  // leaves the band: exact zeros
            row_prev_[r] = nonzero;
        }
        tile_top[static_cast<std::size_t>(t)] = top;
        tile_clamped[static_cast<std::size_t>(t)] = clamped;
        tile_rows[static_cast<std::size_t>(t)] = rows;
    });
    std::uint32_t top = 0;
    for (std::size_t t = 0; t < tile_top.size(); ++t) {
        top = std::max(top, tile_top[t]);
        clamped_ += tile_clamped[t];
        cells_updated_ += tile_rows[t] * nx;
    }
    std::swap(cur_, prev_);
    std::swap(row_cur_, row_prev_);
    ++steps_;
    // Bits above +inf's are NaN: report them as NaN so the caller stops.
    if (top > 0x7f800000u) return std::numeric_limits<double>::quiet_NaN();
    return static_cast<double>(std::bit_cast<float>(top));
}

void Simulation::flush(std::vector<float>* accumulate) {
    if (!accumulate || !pending_) return;
    // The last step was even: its phi^n (now prev_) has not been added in the accumulating layers.
    const std::size_t end = static_cast<std::size_t>(accumulate_top_ + 1) * shape_.nx * shape_.ny;
    for (std::size_t c = 0; c < end; ++c) (*accumulate)[c] += prev_[c];
    pending_ = false;
}

namespace {

double energy_box(const std::vector<float>& a_cur, const std::vector<float>& a_prev, const VolumeShape& sa, Sides sides, Sides sides_y,
                  const std::vector<float>* b_cur, const std::vector<float>* b_prev, const VolumeShape* sb,
                  glm::ivec3 lo, glm::ivec3 hi, glm::ivec3 offset, double lam) {
    // Across a's x and y faces: the mirrored cell (mirror) or the wrapped one (periodic).
    auto side = [](Sides kind, int i, int n) {
        if (kind == Sides::Mirror) return std::clamp(i, 0, n - 1);
        if (kind == Sides::Periodic) return (i % n + n) % n;
        return i;
    };
    // Field value (difference with b when given); other cells outside the grid of a are zero.
    auto value = [&](const std::vector<float>& av, const std::vector<float>* bv, int i, int j, int k) -> double {
        double v = 0.0;
        if (!bv) {
            i = side(sides, i, sa.nx);
            j = side(sides_y, j, sa.ny);
        }
        if (i >= 0 && j >= 0 && k >= 0 && i < sa.nx && j < sa.ny && k < sa.nz) v = av[sa.index(i, j, k)];
        if (bv) {
            const int bi = i + offset.x, bj = j + offset.y, bk = k + offset.z;
            if (bi >= 0 && bj >= 0 && bk >= 0 && bi < sb->nx && bj < sb->ny && bk < sb->nz) v -= (*bv)[sb->index(bi, bj, bk)];
        }
        return v;
    };
    double kinetic = 0.0, potential = 0.0;
    for (int k = lo.z; k < hi.z; ++k)
        for (int j = lo.y; j < hi.y; ++j)
            for (int i = lo.x; i < hi.x; ++i) {
                const double u = value(a_cur, b_cur, i, j, k), p = value(a_prev, b_prev, i, j, k);
                kinetic += (u - p) * (u - p) / lam;
                // Edges to the +x, +y, +z neighbours, and to the -x, -y, -z ones on the box's low faces.
                const int d[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
                for (const auto& e : d) {
                    const double un = value(a_cur, b_cur, i + e[0], j + e[1], k + e[2]);
                    const double pn = value(a_prev, b_prev, i + e[0], j + e[1], k + e[2]);
                    potential += (u - un) * (p - pn);
                    // Across periodic x and y faces the low face's edge is the high face's, counted there.
                    const bool wrapped = (e[0] && sides == Sides::Periodic) || (e[1] && sides_y == Sides::Periodic);
                    const bool low_face = !wrapped && ((e[0] && i == lo.x) || (e[1] && j == lo.y) || (e[2] && k == lo.z));
                    if (low_face) {
                        const double um = value(a_cur, b_cur, i - e[0], j - e[1], k - e[2]);
                        const double pm = value(a_prev, b_prev, i - e[0], j - e[1], k - e[2]);
                        potential += (u - um) * (p - pm);
                    }
                }
            }
    return kinetic + potential;
}

}  // namespace

double Simulation::energy() const {
    const double lam = settings_.courant * settings_.courant;
    return energy_box(cur_, prev_, shape_, settings_.side_x(), settings_.side_y(), nullptr, nullptr, nullptr, glm::ivec3(0),
                      glm::ivec3(shape_.nx, shape_.ny, shape_.nz), glm::ivec3(0), lam);
}

double Simulation::difference_energy(const Simulation& other, glm::ivec3 lo, glm::ivec3 hi, glm::ivec3 offset) const {
    const double lam = settings_.courant * settings_.courant;
    return energy_box(cur_, prev_, shape_, Sides::Zero, Sides::Zero, &other.cur_, &other.prev_, &other.shape_, lo, hi, offset, lam);
}

}  // namespace caustics::wave
