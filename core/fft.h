// A radix-2 complex FFT in double precision: the reference tier's exact convolutions
// (stages/scatter.h) sum their kernels through it. Exact up to rounding: the twiddle
// factors are each evaluated by std::cos and std::sin, not by recurrence, so the error
// grows as log2(n) roundings of a value's magnitude (tested against the direct DFT).
#pragma once

#include <complex>
#include <vector>

namespace darkroom {

class Fft {
public:
    // n: a power of two, at least 1.
    explicit Fft(int n);
    int size() const { return n_; }
    // In place: forward, X_k = sum x_j e^(-2 pi i jk/n); inverse without the 1/n.
    void forward(std::complex<double>* data) const { transform(data, false); }
    void inverse(std::complex<double>* data) const { transform(data, true); }

private:
    int n_;
    std::vector<std::complex<double>> twiddles_;  // e^(-2 pi i k/n), k < n/2
    std::vector<int> reversed_;                   // bit-reversed index
    void transform(std::complex<double>* data, bool inverse) const;
};

// The 2D transform of an n x n row-major grid (rows, then columns), on `threads` threads:
// each row and column is transformed alone, so the result is the same on any number.
void fft_2d(const Fft& fft, std::vector<std::complex<double>>& grid, bool inverse, int threads);

bool is_power_of_two(int n);

}  // namespace darkroom
