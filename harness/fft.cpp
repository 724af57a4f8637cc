// FFTW wrapper: see fft.hpp for the threading and alignment scheme.
#include "fft.hpp"

#include <algorithm>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>

#include <fftw3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics {

namespace {

// The FFTW planner (plan creation and destruction) is not thread-safe; execution is.
std::mutex& planner_mutex() {
    static std::mutex m;
    return m;
}

fftwf_complex* as_fftw(ComplexF* p) { return reinterpret_cast<fftwf_complex*>(p); }

int gcd(int a, int b) {
    while (b != 0) {
        const int t = a % b;
        a = b;
        b = t;
    }
    return a;
}

constexpr int kAlignComplex = 8;   // 64 bytes / sizeof(ComplexF): batch starts keep the buffer's alignment

}  // namespace

bool is_fast_fft_size(int n) {
    if (n < 1) return false;
    for (int p : {2, 3, 5, 7})
        while (n % p == 0) n /= p;
    return n == 1;
}

int next_fast_fft_size(int n) {
    n = std::max(n, 1);
    while (!is_fast_fft_size(n)) ++n;
    return n;
}

std::vector<int> fast_fft_sizes(int lo, int hi) {
    std::vector<int> sizes;
    for (int n = std::max(lo, 1); n <= hi; ++n)
        if (is_fast_fft_size(n)) sizes.push_back(n);
    return sizes;
}

ComplexBuffer::ComplexBuffer(std::size_t count) : size_(count) {
    if (count == 0) return;
    data_ = reinterpret_cast<ComplexF*>(fftwf_malloc(count * sizeof(ComplexF)));
    if (data_ == nullptr) throw std::bad_alloc();
    std::fill(data_, data_ + count, ComplexF(0.0f, 0.0f));
}

ComplexBuffer::~ComplexBuffer() {
    if (data_ != nullptr) fftwf_free(data_);
}

ComplexBuffer::ComplexBuffer(ComplexBuffer&& other) noexcept : data_(other.data_), size_(other.size_) {
    other.data_ = nullptr;
    other.size_ = 0;
}

ComplexBuffer& ComplexBuffer::operator=(ComplexBuffer&& other) noexcept {
    if (this != &other) {
        if (data_ != nullptr) fftwf_free(data_);
        data_ = other.data_;
        size_ = other.size_;
        other.data_ = nullptr;
        other.size_ = 0;
    }
    return *this;
}

// One pass (rows or columns) is a set of equal batches of 1-D transforms plus at most one shorter
// remainder batch; each batch has its own forward and inverse plan.
struct BatchPass {
    int count = 0;        // transforms in this pass (ny rows or nx columns)
    int batch = 0;        // transforms per batch
    std::ptrdiff_t batch_offset = 0;   // elements between the starts of consecutive batches
    fftwf_plan full[2] = {nullptr, nullptr};   // [0] forward, [1] inverse
    fftwf_plan tail[2] = {nullptr, nullptr};
};

struct Fft2D::Plans {
    fftwf_plan whole[2] = {nullptr, nullptr};   // small sizes: one serial 2-D plan
    BatchPass rows, cols;
};

namespace {

// Plans `howmany` 1-D transforms of length n with the given stride/distance on `scratch`.
fftwf_plan plan_batch(int n, int howmany, int stride, int dist, ComplexF* scratch, int sign, unsigned flags) {
    int dims[1] = {n};
    fftwf_plan p = fftwf_plan_many_dft(1, dims, howmany, as_fftw(scratch), nullptr, stride, dist,
                                       as_fftw(scratch), nullptr, stride, dist, sign, flags);
    if (p == nullptr) throw std::runtime_error("FFTW could not plan a transform of size " + std::to_string(n));
    return p;
}

void destroy(fftwf_plan& p) {
    if (p != nullptr) fftwf_destroy_plan(p);
    p = nullptr;
}

}  // namespace

Fft2D::Fft2D(int nx, int ny, FftRigor rigor) : nx_(nx), ny_(ny), plans_(std::make_unique<Plans>()) {
    if (nx < 1 || ny < 1) throw std::invalid_argument("Fft2D: sizes must be positive");
    const unsigned flags = (rigor == FftRigor::Measure ? FFTW_MEASURE : FFTW_ESTIMATE);
    const std::size_t total = static_cast<std::size_t>(nx) * ny;
    ComplexBuffer scratch(total);
    std::lock_guard<std::mutex> lock(planner_mutex());
    if (total < 16384) {
        plans_->whole[0] = fftwf_plan_dft_2d(ny, nx, as_fftw(scratch.data()), as_fftw(scratch.data()),
                                             FFTW_FORWARD, flags);
        plans_->whole[1] = fftwf_plan_dft_2d(ny, nx, as_fftw(scratch.data()), as_fftw(scratch.data()),
                                             FFTW_BACKWARD, flags);
        if (plans_->whole[0] == nullptr || plans_->whole[1] == nullptr)
            throw std::runtime_error("FFTW could not plan a 2-D transform");
        return;
    }
    // Rows: batches of contiguous rows; a batch start r0 * nx must be a multiple of kAlignComplex.
    {
        BatchPass& p = plans_->rows;
        const int unit = kAlignComplex / gcd(nx, kAlignComplex);
        p.count = ny;
        p.batch = std::max(unit, (ny / 32 + unit - 1) / unit * unit);
        p.batch = std::min(p.batch, ny);
        p.batch_offset = static_cast<std::ptrdiff_t>(p.batch) * nx;
        for (int s = 0; s < 2; ++s) {
            const int sign = s == 0 ? FFTW_FORWARD : FFTW_BACKWARD;
            p.full[s] = plan_batch(nx, p.batch, 1, nx, scratch.data(), sign, flags);
            if (ny % p.batch != 0) p.tail[s] = plan_batch(nx, ny % p.batch, 1, nx, scratch.data(), sign, flags);
        }
    }
    // Columns: batches of adjacent columns (stride nx); batch starts are multiples of kAlignComplex.
    {
        BatchPass& p = plans_->cols;
        p.count = nx;
        p.batch = std::min(nx, 16);
        p.batch_offset = p.batch;
        for (int s = 0; s < 2; ++s) {
            const int sign = s == 0 ? FFTW_FORWARD : FFTW_BACKWARD;
            p.full[s] = plan_batch(ny, p.batch, nx, 1, scratch.data(), sign, flags);
            if (nx % p.batch != 0) p.tail[s] = plan_batch(ny, nx % p.batch, nx, 1, scratch.data(), sign, flags);
        }
    }
}

Fft2D::~Fft2D() {
    std::lock_guard<std::mutex> lock(planner_mutex());
    for (int s = 0; s < 2; ++s) {
        destroy(plans_->whole[s]);
        destroy(plans_->rows.full[s]);
        destroy(plans_->rows.tail[s]);
        destroy(plans_->cols.full[s]);
        destroy(plans_->cols.tail[s]);
    }
}

void Fft2D::forward(ComplexF* data) const { execute(data, true); }
void Fft2D::inverse(ComplexF* data) const { execute(data, false); }

void Fft2D::execute(ComplexF* data, bool forward) const {
    if (fftwf_alignment_of(reinterpret_cast<float*>(data)) != 0)
        throw std::invalid_argument("Fft2D: data must be allocated by ComplexBuffer (SIMD-aligned)");
    const int s = forward ? 0 : 1;
    if (plans_->whole[s] != nullptr) {
        fftwf_execute_dft(plans_->whole[s], as_fftw(data), as_fftw(data));
        return;
    }
    auto run_pass = [&](const BatchPass& p) {
        const int batches = (p.count + p.batch - 1) / p.batch;
        tbb::parallel_for(tbb::blocked_range<int>(0, batches, 1), [&](const tbb::blocked_range<int>& r) {
            for (int b = r.begin(); b < r.end(); ++b) {
                ComplexF* start = data + static_cast<std::ptrdiff_t>(b) * p.batch_offset;
                const bool tail = (b + 1) * p.batch > p.count;
                fftwf_execute_dft(tail ? p.tail[s] : p.full[s], as_fftw(start), as_fftw(start));
            }
        });
    };
    run_pass(plans_->rows);
    run_pass(plans_->cols);
}

}  // namespace caustics
