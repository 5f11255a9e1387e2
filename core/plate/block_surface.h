// A grain analysis block's least-squares surface, and what it does to grain.
//
// The grain analysis (grain_analysis.h) takes a quadratic surface off each block to stand in
// for the picture. The surface also takes some of the grain: its residual's sum of squares,
// the spread of that sum and its products at each lag are not the grain's. SurfaceFit gives
// each exactly, for Gaussian grain of a given autocorrelation, so that the analysis can undo
// them.
#pragma once

#include <cstddef>
#include <vector>

namespace darkroom {

// Lags |dx|, |dy| <= radius, row-major from (-radius, -radius).
struct LagGrid {
    int radius = 0;
    int side() const { return 2 * radius + 1; }
    size_t size() const { return (size_t)side() * side(); }
    size_t index(int dx, int dy) const { return (size_t)(dy + radius) * side() + dx + radius; }
};

// Sum over pixel pairs (p, p + d) inside a size x size block of f(p) g(p + d), for each lag d.
std::vector<double> cross_correlation(const double* f, const double* g, int size, const LagGrid& lags);

// cross_correlation(f, f): symmetric, so only half the lags are summed.
std::vector<double> autocorrelation(const double* f, int size, const LagGrid& lags);

// The pixel pairs a lag of (dx, dy) has inside a size x size block.
double pair_count(int size, int dx, int dy);

// Sum over lags of pair_count(size) * rho^2: tr(R^2) for grain of autocorrelation rho in a
// size x size block.
double sum_rho2(const std::vector<double>& rho, const LagGrid& lags, int size);

// R v: the covariance (in units of sigma^2) of grain of autocorrelation rho applied to v, an
// n x n block.
std::vector<double> apply_autocorrelation(const std::vector<double>& rho, const LagGrid& lags, int n,
                                          const std::vector<double>& v);

// The least-squares quadratic surface on a block (1, x, y, x^2, xy, y^2), as an
// orthonormal basis: it follows shading and gentle gradients, not edges or texture.
struct SurfaceFit {
    static constexpr int kTerms = 6;
    int size = 0;
    std::vector<double> basis[kTerms];
    std::vector<double> basis_xcorr[kTerms][kTerms];  // cross_correlation(basis k, basis l)

    SurfaceFit(int block, const LagGrid& lags);

    // v less its least-squares surface (v: a block, row-major).
    void subtract_from(double* v) const;

    // What the fit does to Gaussian grain of unit variance and autocorrelation rho: the
    // residual's expected sum of squares is N - trace, that sum's variance squares_variance,
    // and its mean product at lag d is rho(d) - lag_bias[d].
    struct Bias {
        double trace = 0, squares_variance = 0;
        std::vector<double> lag_bias;
    };
    Bias bias(const std::vector<double>& rho, const LagGrid& lags) const;
};

}  // namespace darkroom
