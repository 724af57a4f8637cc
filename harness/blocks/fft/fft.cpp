// FFTW wrapper: see fft.hpp for the threading and alignment scheme.
#include <caustics/blocks/fft/fft.hpp>

#include <caustics/util/fftw_lock.hpp>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>

#include <fftw3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics {

namespace {

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
// remainder batch; each batch has its own forward and inverse plan. Row plans run in place on the array;
// column plans run on a contiguous block of `batch` interleaved columns (stride batch, distance 1).
struct BatchPass {
    int count = 0;        // transforms in this pass (ny rows or nx columns)
    int batch = 0;        // transforms per batch
    fftwf_plan full[2] = {nullptr, nullptr};   // [0] forward, [1] inverse
    fftwf_plan tail[2] = {nullptr, nullptr};
    int batches() const { return (count + batch - 1) / batch; }
    int width(int b) const { return std::min(batch, count - b * batch); }
    fftwf_plan plan(int b, int s) const { return width(b) == batch ? full[s] : tail[s]; }
};

struct Fft2D::Plans {
    fftwf_plan whole[2] = {nullptr, nullptr};   // small sizes: one serial 2-D plan
    BatchPass rows, cols;
};

namespace {

constexpr int kColumnBatch = 16;   // 128 bytes of each row per column block

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

// Copies `count` pieces of `width` values between strides; full-width pieces are a fixed-size copy the
// compiler inlines (a library call per 128-byte piece costs as much as the copy).
void copy_pieces(const ComplexF* src, std::size_t src_stride, ComplexF* dst, std::size_t dst_stride, int count,
                 int width) {
    if (width == kColumnBatch) {
        for (int y = 0; y < count; ++y)
            std::memcpy(dst + y * dst_stride, src + y * src_stride, kColumnBatch * sizeof(ComplexF));
        return;
    }
    for (int y = 0; y < count; ++y) std::copy_n(src + y * src_stride, width, dst + y * dst_stride);
}

}  // namespace

Fft2D::Fft2D(int nx, int ny, FftRigor rigor) : nx_(nx), ny_(ny), plans_(std::make_unique<Plans>()) {
    if (nx < 1 || ny < 1) throw std::invalid_argument("Fft2D: sizes must be positive");
    const unsigned flags = (rigor == FftRigor::Measure ? FFTW_MEASURE : FFTW_ESTIMATE);
    const std::size_t total = static_cast<std::size_t>(nx) * ny;
    ComplexBuffer scratch(total);
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
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
        for (int s = 0; s < 2; ++s) {
            const int sign = s == 0 ? FFTW_FORWARD : FFTW_BACKWARD;
            p.full[s] = plan_batch(nx, p.batch, 1, nx, scratch.data(), sign, flags);
            if (ny % p.batch != 0) p.tail[s] = plan_batch(nx, ny % p.batch, 1, nx, scratch.data(), sign, flags);
        }
    }
    // Columns: blocks of up to kColumnBatch interleaved columns.
    {
        BatchPass& p = plans_->cols;
        p.count = nx;
        p.batch = std::min(nx, kColumnBatch);
        const int rest = nx % p.batch;
        for (int s = 0; s < 2; ++s) {
            const int sign = s == 0 ? FFTW_FORWARD : FFTW_BACKWARD;
            p.full[s] = plan_batch(ny, p.batch, p.batch, 1, scratch.data(), sign, flags);
            if (rest != 0) p.tail[s] = plan_batch(ny, rest, rest, 1, scratch.data(), sign, flags);
        }
    }
}

Fft2D::~Fft2D() {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    for (int s = 0; s < 2; ++s) {
        destroy(plans_->whole[s]);
        destroy(plans_->rows.full[s]);
        destroy(plans_->rows.tail[s]);
        destroy(plans_->cols.full[s]);
        destroy(plans_->cols.tail[s]);
    }
}

void Fft2D::forward(ComplexF* data) const { forward_fused(data, {}); }
void Fft2D::inverse(ComplexF* data) const { inverse_fused(data, {}, {}); }

void Fft2D::check_aligned(const ComplexF* data) const {
    if (fftwf_alignment_of(reinterpret_cast<float*>(const_cast<ComplexF*>(data))) != 0)
        throw std::invalid_argument("Fft2D: data must be allocated by ComplexBuffer (SIMD-aligned)");
}

void Fft2D::forward_fused(ComplexF* data, const RowHook& fill_rows) const {
    check_aligned(data);
    if (plans_->whole[0] != nullptr) {
        if (fill_rows) fill_rows(0, ny_, data);
        fftwf_execute_dft(plans_->whole[0], as_fftw(data), as_fftw(data));
        return;
    }
    row_pass(data, 0, fill_rows);
    column_pass(data, 0, {});
}

void Fft2D::inverse_fused(ComplexF* data, const RowHook& fill_rows, const ColumnHook& consume_columns) const {
    check_aligned(data);
    if (plans_->whole[1] != nullptr) {
        if (fill_rows) fill_rows(0, ny_, data);
        fftwf_execute_dft(plans_->whole[1], as_fftw(data), as_fftw(data));
        if (consume_columns) {
            ComplexBuffer block(static_cast<std::size_t>(ny_) * kColumnBatch);
            for (int x0 = 0; x0 < nx_; x0 += kColumnBatch) {
                const int width = std::min(kColumnBatch, nx_ - x0);
                copy_pieces(data + x0, nx_, block.data(), width, ny_, width);
                consume_columns(x0, width, block.data());
            }
        }
        return;
    }
    row_pass(data, 1, fill_rows);
    column_pass(data, 1, consume_columns);
}

void Fft2D::row_pass(ComplexF* data, int s, const RowHook& fill) const {
    const BatchPass& p = plans_->rows;
    tbb::parallel_for(tbb::blocked_range<int>(0, p.batches(), 1), [&](const tbb::blocked_range<int>& r) {
        for (int b = r.begin(); b < r.end(); ++b) {
            const int y0 = b * p.batch, y1 = y0 + p.width(b);
            ComplexF* start = data + static_cast<std::size_t>(y0) * nx_;
            if (fill) fill(y0, y1, start);
            fftwf_execute_dft(p.plan(b, s), as_fftw(start), as_fftw(start));
        }
    });
}

void Fft2D::column_pass(ComplexF* data, int s, const ColumnHook& consume) const {
    const BatchPass& p = plans_->cols;
    tbb::parallel_for(tbb::blocked_range<int>(0, p.batches(), 1), [&](const tbb::blocked_range<int>& r) {
        ComplexBuffer block(static_cast<std::size_t>(ny_) * p.batch);   // one per task: ~128 KB at 1024
        for (int b = r.begin(); b < r.end(); ++b) {
            const int x0 = b * p.batch, width = p.width(b);
            copy_pieces(data + x0, nx_, block.data(), width, ny_, width);
            fftwf_execute_dft(p.plan(b, s), as_fftw(block.data()), as_fftw(block.data()));
            if (consume)
                consume(x0, width, block.data());
            else
                copy_pieces(block.data(), width, data + x0, nx_, ny_, width);
        }
    });
}

}  // namespace caustics
