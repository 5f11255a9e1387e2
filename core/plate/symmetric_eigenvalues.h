// The eigenvalues of a symmetric matrix, without its eigenvectors.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace darkroom {

// The eigenvalues of the symmetric n x n matrix a (row-major), ascending: Householder
// reduction to tridiagonal form, then the implicit QL method with Wilkinson shifts (Golub and
// Van Loan, 8.3). Without the eigenvectors this takes an eighth of the time of Jacobi's
// rotations (symmetric_eigen) on a 25 x 25 matrix; the grain analysis's patch-space
// calibration solves thousands of these.
inline std::vector<double> symmetric_eigenvalues(std::vector<double> a, int n) {
    auto at = [&](int i, int j) -> double& { return a[(size_t)i * n + j]; };
    std::vector<double> v(n), p(n);
    for (int k = 0; k + 2 < n; ++k) {
        // The reflection I - beta v v^T that zeroes column k below its subdiagonal.
        double below = 0;
        for (int i = k + 2; i < n; ++i) below += at(i, k) * at(i, k);
        if (below == 0) continue;
        const double x0 = at(k + 1, k), alpha = -std::copysign(std::sqrt(below + x0 * x0), x0);
        for (int i = k + 1; i < n; ++i) v[i] = at(i, k);
        v[k + 1] -= alpha;
        const double beta = 2.0 / (below + v[k + 1] * v[k + 1]);
        // A <- H A H on the trailing block: A - v w^T - w v^T with w = p - (beta/2)(v.p) v, p = beta A v.
        double vp = 0;
        for (int i = k + 1; i < n; ++i) {
            double sum = 0;
            for (int j = k + 1; j < n; ++j) sum += at(i, j) * v[j];
            p[i] = beta * sum;
            vp += v[i] * p[i];
        }
        for (int i = k + 1; i < n; ++i) p[i] -= 0.5 * beta * vp * v[i];
        for (int i = k + 1; i < n; ++i)
            for (int j = k + 1; j < n; ++j) at(i, j) -= v[i] * p[j] + p[i] * v[j];
        at(k + 1, k) = alpha;
    }
    std::vector<double> d(n), e(n, 0.0);  // the diagonal and e[i] = a(i + 1, i)
    for (int i = 0; i < n; ++i) d[i] = at(i, i);
    for (int i = 0; i + 1 < n; ++i) e[i] = at(i + 1, i);
    for (int l = 0; l < n; ++l)
        for (int iteration = 0; iteration < 60; ++iteration) {
            int m = l;  // the first negligible subdiagonal from l on: d[l..m] is unreduced
            while (m + 1 < n && std::abs(e[m]) > 1e-15 * (std::abs(d[m]) + std::abs(d[m + 1]))) ++m;
            if (m == l) break;
            // A QL step shifted by the eigenvalue of the 2 x 2 block at l nearer d[l] (Wilkinson).
            double g = (d[l + 1] - d[l]) / (2 * e[l]), r = std::hypot(g, 1.0);
            g = d[m] - d[l] + e[l] / (g + std::copysign(r, g));
            double s = 1, c = 1, shift = 0;
            int i = m - 1;
            for (; i >= l; --i) {
                const double f = s * e[i], b = c * e[i];
                e[i + 1] = r = std::sqrt(f * f + g * g);  // no overflow at pixel values' scale
                if (r == 0) break;  // deflated: d[i + 1..m] split off
                s = f / r, c = g / r;
                g = d[i + 1] - shift;
                r = (d[i] - g) * s + 2 * c * b;
                shift = s * r;
                d[i + 1] = g + shift;
                g = c * r - b;
            }
            if (r == 0 && i >= l) {
                d[i + 1] -= shift;
                e[m] = 0;
                continue;
            }
            d[l] -= shift, e[l] = g, e[m] = 0;
        }
    std::sort(d.begin(), d.end());
    return d;
}

}  // namespace darkroom
