// The `waves` height-field generator: a damped 2-D wave equation
//     h_tt = c^2 (h_xx + h_yy) - damping h_t
// on the height-field grid, explicit leapfrog, reflecting (Neumann) borders, started from rest and fed
// with Gaussian drops (height `amplitude`, profile exp(-r^2 / drop_radius^2)) at seeded positions and
// seeded frames in the first half of the animation (drop 0 falls at frame 0, so no frame is flat).
//
// Frame N is the same bits on every machine: one thread, a fixed operation order, IEEE double
// arithmetic with no contraction into fused multiply-adds, no C library calls (the drops' profile uses
// our own exp), and our own splitmix64 for the seeds.
//
// The animation length comes in `desc.animation_length` (load_scene sets it to frames / fps).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#include <caustics/util/rng.hpp>
#include "detail/heightfield_generators.hpp"

// No fused multiply-adds in this file (compilers contract by default on some targets, which would
// change the bits between machines).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("fp-contract=off")
#elif defined(__clang__)
#pragma clang fp contract(off)
#endif

namespace caustics::detail {

namespace {

// exp(-x) for x >= 0 with basic IEEE operations only, so that it does not depend on the C library's
// exp(): x = n ln 2 + r, exp(-r) by its Taylor series (|r| < ln 2: 24 terms are well below 1 ulp).
double exp_neg(double x) {
    constexpr double kLn2 = 0.69314718055994530942;
    const int n = static_cast<int>(x / kLn2);
    const double r = x - n * kLn2;
    double term = 1.0, sum = 1.0;
    for (int k = 1; k <= 24; ++k) {
        term = term * (-r) / k;
        sum = sum + term;
    }
    for (int k = 0; k < n; ++k) sum = sum * 0.5;
    return sum;
}

struct Drop {
    double x = 0.0, y = 0.0;
    int frame = 0;
};

std::vector<Drop> seeded_drops(const HeightFieldDesc& d, double fps) {
    SplitMix64 rng{d.seed};
    const int half = std::max(1, static_cast<int>(std::floor(0.5 * d.animation_length * fps)));
    // Scalar arithmetic (not glm's templates, compiled outside the pragma above).
    const double lo_x = d.center.x - 0.5 * d.size.x, lo_y = d.center.y - 0.5 * d.size.y;
    std::vector<Drop> drops(static_cast<std::size_t>(std::max(0, d.drops)));
    for (std::size_t k = 0; k < drops.size(); ++k) {
        const double margin_x = std::min(d.drop_radius, 0.25 * d.size.x), margin_y = std::min(d.drop_radius, 0.25 * d.size.y);
        drops[k].x = lo_x + margin_x + rng.uniform() * (d.size.x - 2.0 * margin_x);
        drops[k].y = lo_y + margin_y + rng.uniform() * (d.size.y - 2.0 * margin_y);
        const int f = std::min(half - 1, static_cast<int>(rng.uniform() * half));
        drops[k].frame = k == 0 ? 0 : f;
    }
    return drops;
}

struct WaveState {
    int nx = 0, ny = 0;
    int frame = -1;
    std::vector<double> h, h_prev;
};

class WaveSimulation {
public:
    WaveSimulation(const HeightFieldDesc& d, double fps) : desc_(d), fps_(fps), drops_(seeded_drops(d, fps)) {
        nx_ = d.resolution.x + 1;
        ny_ = d.resolution.y + 1;
        dx_ = d.size.x / d.resolution.x;
        dy_ = d.size.y / d.resolution.y;
        // CFL: c dt sqrt(1/dx^2 + 1/dy^2) <= 1 for this stencil; keep a margin of 0.5.
        const double dt_frame = 1.0 / fps;
        const double courant = d.wave_speed * dt_frame * std::sqrt(1.0 / (dx_ * dx_) + 1.0 / (dy_ * dy_));
        substeps_ = std::max(1, static_cast<int>(std::ceil(courant / 0.5)));
        dt_ = dt_frame / substeps_;
    }

    // Advances `s` (a state of this simulation at frame s.frame, or empty) to `frame`.
    void advance(WaveState& s, int frame) const {
        if (s.frame < 0 || s.frame > frame) {
            s.nx = nx_;
            s.ny = ny_;
            s.h.assign(static_cast<std::size_t>(nx_) * ny_, 0.0);
            s.h_prev = s.h;
            s.frame = 0;
            add_drops(s, 0);
        }
        std::vector<double> next(s.h.size());
        while (s.frame < frame) {
            for (int k = 0; k < substeps_; ++k) {
                step(s.h, s.h_prev, next);
                std::swap(s.h_prev, s.h);  // h_prev <- h
                std::swap(s.h, next);      // h <- next
            }
            ++s.frame;
            add_drops(s, s.frame);
        }
    }

private:
    void add_drops(WaveState& s, int frame) const {
        const double r2 = desc_.drop_radius * desc_.drop_radius;
        const double lo_x = desc_.center.x - 0.5 * desc_.size.x, lo_y = desc_.center.y - 0.5 * desc_.size.y;
        for (const Drop& drop : drops_) {
            if (drop.frame != frame) continue;
            for (int j = 0; j < ny_; ++j) {
                const double y = lo_y + j * dy_ - drop.y;
                for (int i = 0; i < nx_; ++i) {
                    const double x = lo_x + i * dx_ - drop.x;
                    const double d2 = (x * x + y * y) / r2;
                    if (d2 > 36.0) continue;  // exp(-36) ~ 2e-16 of the drop height
                    const double bump = desc_.amplitude * exp_neg(d2);
                    const std::size_t k = static_cast<std::size_t>(j) * nx_ + i;
                    s.h[k] += bump;       // added to both levels: the drop starts at rest
                    s.h_prev[k] += bump;
                }
            }
        }
    }

    // One leapfrog step with damping (central difference for h_t):
    //   (1 + g dt/2) h+ = 2 h - (1 - g dt/2) h- + (c dt)^2 lap h
    // Reflecting borders: the ghost node mirrors the first interior node.
    void step(const std::vector<double>& h, const std::vector<double>& hp, std::vector<double>& out) const {
        const double cx = (desc_.wave_speed * dt_ / dx_) * (desc_.wave_speed * dt_ / dx_);
        const double cy = (desc_.wave_speed * dt_ / dy_) * (desc_.wave_speed * dt_ / dy_);
        const double gd = 0.5 * desc_.damping * dt_;
        const double inv = 1.0 / (1.0 + gd);
        const double keep = 1.0 - gd;
        for (int j = 0; j < ny_; ++j) {
            const int jd = j > 0 ? j - 1 : (ny_ > 1 ? 1 : 0);
            const int ju = j + 1 < ny_ ? j + 1 : (ny_ > 1 ? ny_ - 2 : 0);
            for (int i = 0; i < nx_; ++i) {
                const int il = i > 0 ? i - 1 : (nx_ > 1 ? 1 : 0);
                const int ir = i + 1 < nx_ ? i + 1 : (nx_ > 1 ? nx_ - 2 : 0);
                const std::size_t k = static_cast<std::size_t>(j) * nx_ + i;
                const double c = h[k];
                const double lap = cx * ((h[static_cast<std::size_t>(j) * nx_ + il] - c) + (h[static_cast<std::size_t>(j) * nx_ + ir] - c)) +
                                   cy * ((h[static_cast<std::size_t>(jd) * nx_ + i] - c) + (h[static_cast<std::size_t>(ju) * nx_ + i] - c));
                out[k] = (2.0 * c - keep * hp[k] + lap) * inv;
            }
        }
    }

    HeightFieldDesc desc_;
    double fps_;
    std::vector<Drop> drops_;
    int nx_ = 0, ny_ = 0, substeps_ = 1;
    double dx_ = 1.0, dy_ = 1.0, dt_ = 0.0;
};

bool same_simulation(const HeightFieldDesc& a, const HeightFieldDesc& b) {
    return a.center == b.center && a.size == b.size && a.resolution == b.resolution && a.amplitude == b.amplitude &&
           a.drops == b.drops && a.drop_radius == b.drop_radius && a.wave_speed == b.wave_speed &&
           a.damping == b.damping && a.seed == b.seed && a.animation_length == b.animation_length;
}

}  // namespace

void generate_waves(const HeightFieldDesc& desc, int frame, double fps, HeightField& hf) {
    // The last state computed, so that frames rendered in order step one frame at a time.
    static std::mutex mutex;
    static HeightFieldDesc cached_desc;
    static double cached_fps = 0.0;
    static WaveState cached;

    const WaveSimulation sim(desc, fps);
    WaveState state;
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (cached.frame >= 0 && cached.frame <= frame && cached_fps == fps && same_simulation(cached_desc, desc)) state = cached;
    }
    sim.advance(state, std::max(0, frame));
    {
        std::lock_guard<std::mutex> lock(mutex);
        cached_desc = desc;
        cached_fps = fps;
        cached = state;
    }
    for (std::size_t k = 0; k < hf.height.size(); ++k)
        hf.height[k] = static_cast<float>(desc.base_height + state.h[k]);
    gradients_by_central_differences(hf);
}

}  // namespace caustics::detail
