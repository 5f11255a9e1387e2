#include "core/fft.h"

#include <cmath>
#include <stdexcept>

#include "core/parallel.h"

namespace darkroom {

bool is_power_of_two(int n) { return n > 0 && (n & (n - 1)) == 0; }

Fft::Fft(int n) : n_(n) {
    if (!is_power_of_two(n)) throw std::invalid_argument("FFT size " + std::to_string(n) + " is not a power of two");
    for (int k = 0; k < n / 2; ++k) {
        const double angle = -2.0 * M_PI * k / n;
        twiddles_.emplace_back(std::cos(angle), std::sin(angle));
    }
    int bits = 0;
    while ((1 << bits) < n) ++bits;
    reversed_.resize(size_t(n));
    for (int i = 0; i < n; ++i) {
        int r = 0;
        for (int b = 0; b < bits; ++b) r |= ((i >> b) & 1) << (bits - 1 - b);
        reversed_[size_t(i)] = r;
    }
}

void Fft::transform(std::complex<double>* data, bool inverse) const {
    for (int i = 0; i < n_; ++i)
        if (i < reversed_[size_t(i)]) std::swap(data[i], data[reversed_[size_t(i)]]);
    const double sign = inverse ? -1.0 : 1.0;  // the inverse's twiddles are the conjugates
    for (int half = 1; half < n_; half *= 2) {
        const int step = n_ / (2 * half);  // twiddle index step at this level
        for (int start = 0; start < n_; start += 2 * half)
            for (int k = 0; k < half; ++k) {
                const std::complex<double> w = twiddles_[size_t(k * step)];
                const double wr = w.real(), wi = sign * w.imag();
                std::complex<double>& a = data[start + k];
                std::complex<double>& b = data[start + k + half];
                // (std::complex's product checks for infinities and NaN in a library call.)
                const double tr = wr * b.real() - wi * b.imag(), ti = wr * b.imag() + wi * b.real();
                b = {a.real() - tr, a.imag() - ti};
                a = {a.real() + tr, a.imag() + ti};
            }
    }
}

void fft_2d(const Fft& fft, std::vector<std::complex<double>>& grid, bool inverse, int threads) {
    const int n = fft.size();
    auto pass = [&](bool rows) {
        parallel_for(0, n, threads, [&](int begin, int end) {
            std::vector<std::complex<double>> line(static_cast<size_t>(n));
            for (int i = begin; i < end; ++i) {
                // A column is copied out and back: contiguous, it stays in the cache.
                std::complex<double>* first = grid.data() + (rows ? size_t(i) * n : size_t(i));
                const size_t stride = rows ? 1 : size_t(n);
                for (int j = 0; j < n; ++j) line[size_t(j)] = first[j * stride];
                inverse ? fft.inverse(line.data()) : fft.forward(line.data());
                for (int j = 0; j < n; ++j) first[j * stride] = line[size_t(j)];
            }
        });
    };
    pass(true);
    pass(false);
}

}  // namespace darkroom
