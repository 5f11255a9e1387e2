#include "core/plate/block_surface.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace darkroom {

std::vector<double> cross_correlation(const double* f, const double* g, int size, const LagGrid& lags) {
    std::vector<double> out(lags.size(), 0.0);
    for (int dy = -lags.radius; dy <= lags.radius; ++dy)
        for (int dx = -lags.radius; dx <= lags.radius; ++dx) {
            double sum = 0;
            for (int y = std::max(0, -dy); y < std::min(size, size - dy); ++y) {
                const double* fr = f + (size_t)y * size;
                const double* gr = g + (size_t)(y + dy) * size + dx;
                for (int x = std::max(0, -dx); x < std::min(size, size - dx); ++x) sum += fr[x] * gr[x];
            }
            out[lags.index(dx, dy)] = sum;
        }
    return out;
}

std::vector<double> autocorrelation(const double* f, int size, const LagGrid& lags) {
    std::vector<double> out(lags.size(), 0.0);
    for (int dy = 0; dy <= lags.radius; ++dy)
        for (int dx = dy == 0 ? 0 : -lags.radius; dx <= lags.radius; ++dx) {
            double sum = 0;
            for (int y = 0; y < size - dy; ++y) {
                const double* fr = f + (size_t)y * size;
                const double* gr = f + (size_t)(y + dy) * size + dx;
                for (int x = std::max(0, -dx); x < std::min(size, size - dx); ++x) sum += fr[x] * gr[x];
            }
            out[lags.index(dx, dy)] = out[lags.index(-dx, -dy)] = sum;
        }
    return out;
}

double pair_count(int size, int dx, int dy) { return double(size - std::abs(dx)) * (size - std::abs(dy)); }

double sum_rho2(const std::vector<double>& rho, const LagGrid& lags, int size) {
    double sum = 0;
    for (int dy = -lags.radius; dy <= lags.radius; ++dy)
        for (int dx = -lags.radius; dx <= lags.radius; ++dx)
            if (std::abs(dx) < size && std::abs(dy) < size)
                sum += pair_count(size, dx, dy) * rho[lags.index(dx, dy)] * rho[lags.index(dx, dy)];
    return sum;
}

std::vector<double> apply_autocorrelation(const std::vector<double>& rho, const LagGrid& lags, int n,
                                          const std::vector<double>& v) {
    std::vector<double> out((size_t)n * n, 0.0);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            double sum = 0;
            for (int dy = std::max(-lags.radius, -y); dy <= std::min(lags.radius, n - 1 - y); ++dy)
                for (int dx = std::max(-lags.radius, -x); dx <= std::min(lags.radius, n - 1 - x); ++dx)
                    sum += rho[lags.index(dx, dy)] * v[(size_t)(y + dy) * n + x + dx];
            out[(size_t)y * n + x] = sum;
        }
    return out;
}

SurfaceFit::SurfaceFit(int block, const LagGrid& lags) : size(block) {
    const double centre = (block - 1) / 2.0;
    for (int y = 0; y < block; ++y)
        for (int x = 0; x < block; ++x) {
            const double u = (x - centre) / block, v = (y - centre) / block;
            const double monomial[kTerms] = {1, u, v, u * u, u * v, v * v};
            for (int k = 0; k < kTerms; ++k) basis[k].push_back(monomial[k]);
        }
    // Gram-Schmidt, twice for accuracy.
    for (int k = 0; k < kTerms; ++k)
        for (int pass = 0; pass < 2; ++pass) {
            for (int l = 0; l < k; ++l) {
                double dot = 0;
                for (size_t p = 0; p < basis[k].size(); ++p) dot += basis[k][p] * basis[l][p];
                for (size_t p = 0; p < basis[k].size(); ++p) basis[k][p] -= dot * basis[l][p];
            }
            double norm = 0;
            for (double b : basis[k]) norm += b * b;
            for (double& b : basis[k]) b /= std::sqrt(norm);
        }
    for (int k = 0; k < kTerms; ++k)
        for (int l = 0; l < kTerms; ++l)
            basis_xcorr[k][l] = cross_correlation(basis[k].data(), basis[l].data(), block, lags);
}


void SurfaceFit::subtract_from(double* v) const {
    const int npx = size * size;
    double coef[kTerms] = {};
    for (int k = 0; k < kTerms; ++k)
        for (int p = 0; p < npx; ++p) coef[k] += basis[k][p] * v[p];
    for (int p = 0; p < npx; ++p)
        for (int k = 0; k < kTerms; ++k) v[p] -= coef[k] * basis[k][p];
}

SurfaceFit::Bias SurfaceFit::bias(const std::vector<double>& rho, const LagGrid& lags) const {
    const int n = size;
    std::vector<double> applied[kTerms];  // R b_k
    for (int k = 0; k < kTerms; ++k) applied[k] = apply_autocorrelation(rho, lags, n, basis[k]);
    double m[kTerms][kTerms];
    for (int k = 0; k < kTerms; ++k)
        for (int l = 0; l < kTerms; ++l) {
            m[k][l] = 0;
            for (size_t p = 0; p < applied[l].size(); ++p) m[k][l] += basis[k][p] * applied[l][p];
        }
    Bias out;
    for (int k = 0; k < kTerms; ++k) out.trace += m[k][k];
    // The residual r = (I - P) g is Gaussian with covariance (I - P) R (I - P), so r.r has
    // variance 2 tr(((I - P) R)^2) = 2 (tr(R^2) - 2 tr(P R^2) + tr((P R)^2)). The fit takes
    // out the low frequencies, where correlated grain's sum of squares varies most.
    double trace_prr = 0, trace_prpr = 0;
    for (int k = 0; k < kTerms; ++k) {
        for (double v : applied[k]) trace_prr += v * v;
        for (int l = 0; l < kTerms; ++l) trace_prpr += m[k][l] * m[k][l];
    }
    out.squares_variance = 2 * (sum_rho2(rho, lags, n) - 2 * trace_prr + trace_prpr);
    out.lag_bias.assign(lags.size(), 0.0);
    for (int k = 0; k < kTerms; ++k) {
        std::vector<double> bv = cross_correlation(basis[k].data(), applied[k].data(), n, lags);
        // cross_correlation(v, b) at d is cross_correlation(b, v) at -d.
        for (size_t i = 0; i < lags.size(); ++i) out.lag_bias[i] += bv[i] + bv[lags.size() - 1 - i];
        for (int l = 0; l < kTerms; ++l)
            for (size_t i = 0; i < lags.size(); ++i) out.lag_bias[i] -= m[k][l] * basis_xcorr[k][l][i];
    }
    for (int dy = -lags.radius; dy <= lags.radius; ++dy)
        for (int dx = -lags.radius; dx <= lags.radius; ++dx) out.lag_bias[lags.index(dx, dy)] /= pair_count(n, dx, dy);
    return out;
}

}  // namespace darkroom
