// The eigenvalues of a symmetric matrix, without its eigenvectors.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace darkroom {

// The eigenvalues of the symmetric n x n matrix a (row-major), ascending: Householder
// reduction to tridiagonal form, then implicit QR steps with Wilkinson shifts (Golub and
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
    std::vector<double> d(n), e(std::max(n - 1, 0));  // the diagonal and e[i] = a(i + 1, i)
    for (int i = 0; i < n; ++i) d[i] = at(i, i);
    for (int i = 0; i + 1 < n; ++i) e[i] = at(i + 1, i);
    // Implicit symmetric QR steps with Wilkinson's shift on the last unreduced block (Golub and
    // Van Loan, algorithm 8.3.2), each step a chase of one bulge by Givens rotations, until every
    // subdiagonal element is negligible. Wilkinson's shift converges for every tridiagonal
    // matrix, almost always cubically: the cap on steps is only a guard.
    auto negligible = [&](int i) { return std::abs(e[i]) <= std::numeric_limits<double>::epsilon() * (std::abs(d[i]) + std::abs(d[i + 1])); };
    for (int last = n - 1, steps = 0; last > 0 && steps < 30 * n;) {
        if (negligible(last - 1)) {
            --last;
            continue;
        }
        int first = last - 1;  // the unreduced block is first..last
        while (first > 0 && !negligible(first - 1)) --first;
        const double half_gap = 0.5 * (d[last - 1] - d[last]), coupling = e[last - 1] * e[last - 1];
        const double shift = d[last] - coupling / (half_gap + std::copysign(std::sqrt(half_gap * half_gap + coupling), half_gap));
        double x = d[first] - shift, z = e[first];
        for (int k = first; k < last; ++k) {
            // (No overflow at the scale of pixel values' moments.) The rotation G = [c s; -s c] on k, k + 1 with G^T (x, z) = (r, 0); T <- G^T T G.
            const double r = std::sqrt(x * x + z * z), c = r > 0 ? x / r : 1, s = r > 0 ? -z / r : 0;
            if (k > first) e[k - 1] = r;
            const double a = d[k], b = e[k], f = d[k + 1];
            d[k] = c * c * a - 2 * c * s * b + s * s * f;
            d[k + 1] = s * s * a + 2 * c * s * b + c * c * f;
            e[k] = c * s * (a - f) + (c * c - s * s) * b;
            if (k + 1 < last) {
                z = -s * e[k + 1];  // the bulge at (k + 2, k), which the next rotation removes
                e[k + 1] *= c;
                x = e[k];
            }
        }
        ++steps;
    }
    std::sort(d.begin(), d.end());
    return d;
}

}  // namespace darkroom
