#pragma once
// A thin RAII wrapper over FFTW (single precision) for the Fourier-domain methods (wave optics, periodic
// texture synthesis), plus the list of sizes FFTW plans quickly.
//
// Plans are made once per size (FFTW_MEASURE by default) and reused; planning is serialised behind one
// process-wide lock because the FFTW planner is not thread-safe, while execution is (FFTW's new-array
// execute functions). The harness links plain fftw3f (no fftw3f_threads), so a 2-D transform is split
// into batches of 1-D transforms, rows and columns, run in parallel with TBB; each row batch starts on a
// 64-byte boundary so one plan serves every batch. Thread count follows the active TBB arena (the
// harness's ThreadLimit).
//
// Columns are not transformed in place: a column stride of a power-of-two number of bytes (grid 512,
// 1024) maps every element of a column onto the same few cache sets, so a strided batch thrashes the
// cache (measured: 4x slower than the row pass at 1024^2). Each batch of adjacent columns is copied into
// a small contiguous block ([row][column], 128-byte pieces of each row), transformed there and copied
// back. The fused entry points let the caller fill or consume the data batch by batch while it is still
// in cache, saving whole passes over the array (see forward_fused / inverse_fused). Both directions run
// rows first, then columns.
#include <complex>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

namespace caustics {

using ComplexF = std::complex<float>;

// Sizes whose only prime factors are 2, 3, 5 and 7: FFTW's codelets plan and run them quickly.
bool is_fast_fft_size(int n);
// The smallest fast size >= n (n >= 1).
int next_fast_fft_size(int n);
// Every fast size in [lo, hi], ascending.
std::vector<int> fast_fft_sizes(int lo, int hi);

// A buffer of complex floats allocated with fftwf_malloc (SIMD-aligned, as the plans expect).
class ComplexBuffer {
public:
    ComplexBuffer() = default;
    explicit ComplexBuffer(std::size_t count);
    ~ComplexBuffer();
    ComplexBuffer(ComplexBuffer&& other) noexcept;
    ComplexBuffer& operator=(ComplexBuffer&& other) noexcept;
    ComplexBuffer(const ComplexBuffer&) = delete;
    ComplexBuffer& operator=(const ComplexBuffer&) = delete;

    ComplexF* data() { return data_; }
    const ComplexF* data() const { return data_; }
    std::size_t size() const { return size_; }
    ComplexF& operator[](std::size_t i) { return data_[i]; }
    const ComplexF& operator[](std::size_t i) const { return data_[i]; }

private:
    ComplexF* data_ = nullptr;
    std::size_t size_ = 0;
};

enum class FftRigor { Estimate, Measure };

// In-place 2-D complex DFT of an nx x ny row-major array (x fastest). Unnormalised in both directions:
// inverse(forward(a)) = nx * ny * a. Forward uses exp(-2 pi i k x / n).
class Fft2D {
public:
    // Rows [y0, y1) of the array, which start at `rows` (= data + y0 * nx).
    using RowHook = std::function<void(int y0, int y1, ComplexF* rows)>;
    // Columns [x0, x0 + width) of the array as a block: block[y * width + i] = a(x0 + i, y).
    using ColumnHook = std::function<void(int x0, int width, const ComplexF* block)>;

    Fft2D(int nx, int ny, FftRigor rigor = FftRigor::Measure);
    ~Fft2D();
    Fft2D(const Fft2D&) = delete;
    Fft2D& operator=(const Fft2D&) = delete;

    int nx() const { return nx_; }
    int ny() const { return ny_; }
    // `data` must come from a ComplexBuffer (or fftwf_malloc) and hold nx * ny values.
    void forward(ComplexF* data) const;
    void inverse(ComplexF* data) const;
    // forward(data), where `fill_rows` (if set) writes each batch of rows of the input just before the
    // batch is transformed: the input need not be in `data` beforehand.
    void forward_fused(ComplexF* data, const RowHook& fill_rows) const;
    // inverse(data), where `fill_rows` (if set) writes each batch of rows of the input just before the
    // batch is transformed (a batch may read the rows of `data` it replaces), and `consume_columns` (if
    // set) sees each batch of columns of the result as soon as it is final; the result is then not
    // written back, and `data` is left holding an intermediate.
    void inverse_fused(ComplexF* data, const RowHook& fill_rows, const ColumnHook& consume_columns) const;

private:
    struct Plans;
    void check_aligned(const ComplexF* data) const;
    void row_pass(ComplexF* data, int sign_index, const RowHook& fill) const;
    void column_pass(ComplexF* data, int sign_index, const ColumnHook& consume) const;
    int nx_ = 0, ny_ = 0;
    std::unique_ptr<Plans> plans_;
};

}  // namespace caustics
