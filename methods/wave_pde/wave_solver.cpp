// Leapfrog wave propagation with a damping band and a layer-granular narrow band (Mercier 2013, Sec. 4).
#include "wave_solver.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <tbb/parallel_for.h>

namespace caustics::wave {
namespace {

constexpr float kBandThreshold = 1e-7f;

std::vector<float> ramp(int n, int sponge) {
    std::vector<float> r(static_cast<std::size_t>(n), 0.0f);
    if (sponge <= 0) return r;
    for (int i = 0; i < n; ++i) {
        const int d = std::max(sponge - i, i - (n - 1 - sponge));  // cells into the band, 1..sponge
        if (d > 0) r[static_cast<std::size_t>(i)] = static_cast<float>(std::min(d, sponge)) / sponge;
    }
    return r;
}

}  // namespace

Simulation::Simulation(const VolumeShape& shape, const Settings& settings)
    : shape_(shape), settings_(settings), cur_(shape.size(), 0.0f), prev_(shape.size(), 0.0f),
      ramp_x_(ramp(shape.nx, settings.sponge)), ramp_y_(ramp(shape.ny, settings.sponge)),
      ramp_z_(ramp(shape.nz, settings.sponge)), active_(static_cast<std::size_t>(shape.nz), 0),
      zero_row_(static_cast<std::size_t>(shape.nx), 0.0f) {}

void Simulation::set_initial(const std::vector<float>& initial) {
    cur_ = initial;
    prev_ = initial;
    const std::size_t layer = static_cast<std::size_t>(shape_.nx) * shape_.ny;
    for (int k = 0; k < shape_.nz; ++k) {
        float m = 0.0f;
        for (std::size_t c = k * layer; c < (k + 1) * layer; ++c) m = std::max(m, std::fabs(cur_[c]));
        active_[static_cast<std::size_t>(k)] = m > kBandThreshold;
    }
}

double Simulation::step(std::vector<float>* accumulate) {
    const VolumeShape& s = shape_;
    const std::size_t layer = static_cast<std::size_t>(s.nx) * s.ny;
    const float lam = static_cast<float>(settings_.courant * settings_.courant);
    const float sig_scale = static_cast<float>(settings_.sponge_strength * settings_.courant);  // sigma dt at d = 1
    const bool clamp = settings_.clamp_negative;
    std::vector<float> layer_max(static_cast<std::size_t>(s.nz), 0.0f);
    std::vector<std::uint8_t> update(static_cast<std::size_t>(s.nz), 0);
    for (int k = 0; k < s.nz; ++k) {
        bool u = !settings_.narrow_band || active_[static_cast<std::size_t>(k)];
        if (k > 0) u = u || active_[static_cast<std::size_t>(k - 1)];
        if (k + 1 < s.nz) u = u || active_[static_cast<std::size_t>(k + 1)];
        update[static_cast<std::size_t>(k)] = u;
    }
    std::atomic<std::int64_t> clamped{0}, updated{0};
    tbb::parallel_for(0, s.nz, [&](int k) {
        if (!update[static_cast<std::size_t>(k)]) return;
        std::int64_t local_clamped = 0;
        float local_max = 0.0f;
        const float rz = ramp_z_[static_cast<std::size_t>(k)];
        for (int j = 0; j < s.ny; ++j) {
            const std::size_t row = s.index(0, j, k);
            const float* c = cur_.data() + row;
            const float* ym = j > 0 ? c - s.nx : zero_row_.data();
            const float* yp = j + 1 < s.ny ? c + s.nx : zero_row_.data();
            const float* zm = k > 0 ? c - layer : zero_row_.data();
            const float* zp = k + 1 < s.nz ? c + layer : zero_row_.data();
            float* p = prev_.data() + row;
            float* acc = accumulate ? accumulate->data() + row : nullptr;
            const float ryz = std::max(ramp_y_[static_cast<std::size_t>(j)], rz);
            const float* rx = ramp_x_.data();
            const int n = s.nx;
            for (int i = 0; i < n; ++i) {
                const float left = i > 0 ? c[i - 1] : 0.0f, right = i + 1 < n ? c[i + 1] : 0.0f;
                const float lap = left + right + ym[i] + yp[i] + zm[i] + zp[i] - 6.0f * c[i];
                const float m = std::max(rx[i], ryz);
                const float sig = sig_scale * m * m;
                float next = (2.0f * c[i] - (1.0f - 0.5f * sig) * p[i] + lam * lap) / (1.0f + 0.5f * sig);
                if (clamp && next < 0.0f) {
                    next = 0.0f;
                    ++local_clamped;
                }
                if (acc) acc[i] += c[i];
                p[i] = next;
                local_max = std::max(local_max, std::fabs(next));
            }
        }
        layer_max[static_cast<std::size_t>(k)] = local_max;
        clamped += local_clamped;
        updated += static_cast<std::int64_t>(layer);
    });
    clamped_ += clamped.load();
    cells_updated_ += updated.load();
    std::swap(cur_, prev_);
    double max_abs = 0.0;
    for (int k = 0; k < s.nz; ++k) {
        const std::size_t kk = static_cast<std::size_t>(k);
        if (!update[kk]) continue;
        max_abs = std::max(max_abs, static_cast<double>(layer_max[kk]));
        if (std::isnan(layer_max[kk])) max_abs = layer_max[kk];
        // The layer's previous values (now prev_) were checked when it was last updated; it stays in
        // the band while either time level is above the threshold.
        const bool was = active_[kk];
        const bool now = layer_max[kk] > kBandThreshold;
        if (settings_.narrow_band && was && !now) {
            // Leaving the band: values below the threshold become exact zeros.
            bool prev_small = true;
            for (std::size_t c = kk * layer; c < (kk + 1) * layer && prev_small; ++c)
                prev_small = std::fabs(prev_[c]) <= kBandThreshold;
            if (prev_small) {
                std::fill(cur_.begin() + static_cast<std::ptrdiff_t>(kk * layer), cur_.begin() + static_cast<std::ptrdiff_t>((kk + 1) * layer), 0.0f);
                std::fill(prev_.begin() + static_cast<std::ptrdiff_t>(kk * layer), prev_.begin() + static_cast<std::ptrdiff_t>((kk + 1) * layer), 0.0f);
                active_[kk] = 0;
                continue;
            }
        }
        active_[kk] = now || was;
        if (!now && !was) active_[kk] = 0;
        if (now) active_[kk] = 1;
    }
    return max_abs;
}

namespace {

double energy_box(const std::vector<float>& a_cur, const std::vector<float>& a_prev, const VolumeShape& sa,
                  const std::vector<float>* b_cur, const std::vector<float>* b_prev, const VolumeShape* sb,
                  glm::ivec3 lo, glm::ivec3 hi, glm::ivec3 offset, double lam) {
    // Field value (difference with b when given); cells outside the grid of a are zero.
    auto value = [&](const std::vector<float>& av, const std::vector<float>* bv, int i, int j, int k) -> double {
        double v = 0.0;
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
                    const bool low_face = (e[0] && i == lo.x) || (e[1] && j == lo.y) || (e[2] && k == lo.z);
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
    return energy_box(cur_, prev_, shape_, nullptr, nullptr, nullptr, glm::ivec3(0),
                      glm::ivec3(shape_.nx, shape_.ny, shape_.nz), glm::ivec3(0), lam);
}

double Simulation::difference_energy(const Simulation& other, glm::ivec3 lo, glm::ivec3 hi, glm::ivec3 offset) const {
    const double lam = settings_.courant * settings_.courant;
    return energy_box(cur_, prev_, shape_, &other.cur_, &other.prev_, &other.shape_, lo, hi, offset, lam);
}

}  // namespace caustics::wave
