#include "core/print_grain_fold.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/develop_rows.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "core/spectral.h"
#include "core/stages/filters.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

namespace {

// A film layer's grain as the print table reads it: unit white noise through the grain's 2D
// kernel G (its 1D kernel's outer product) and the paper's scatter K as applied, K * G, on lags
// -radius ... radius in x and y.
struct ScatteredGrain {
    int radius = 0;
    std::vector<double> taps;  // row-major
    // sum (K * G)_a (K * G)_b over their common lags: the covariance of two such fields of one
    // white noise (with itself: the field's variance).
    double dot(const ScatteredGrain& o) const {
        const int r = std::min(radius, o.radius);
        double sum = 0;
        for (int y = -r; y <= r; ++y)
            for (int x = -r; x <= r; ++x) sum += at(x, y) * o.at(x, y);
        return sum;
    }
    double at(int x, int y) const { return taps[size_t(y + radius) * (2 * radius + 1) + x + radius]; }
};

ScatteredGrain scattered_grain(const GrainModel& grain, const ScatterKernel& scatter) {
    const int rg = grain.radius, rs = scatter.radius, side_s = 2 * rs + 1;
    const std::vector<double> taps = scatter.applied_taps();
    ScatteredGrain k{rg + rs, {}};
    for (int y = -k.radius; y <= k.radius; ++y)
        for (int x = -k.radius; x <= k.radius; ++x) {
            double v = 0;
            for (int sy = -rs; sy <= rs; ++sy)
                for (int sx = -rs; sx <= rs; ++sx) {
                    const int gy = y - sy, gx = x - sx;
                    if (std::abs(gy) > rg || std::abs(gx) > rg) continue;
                    v += taps[size_t(sy + rs) * side_s + sx + rs] * grain.kernel[gy + rg] * grain.kernel[gx + rg];
                }
            k.taps.push_back(v);
        }
    return k;
}

// Gauss-Hermite quadrature for the standard normal: E[f(Z)] ~ sum_k weight_k f(node_k), exact
// for polynomials to degree 2n - 1 (Golub & Welsch 1969: the nodes are the eigenvalues of the
// probabilists' Hermite recurrence's Jacobi matrix, the weights the squared first components
// of its unit eigenvectors).
struct NormalQuadrature {
    explicit NormalQuadrature(int n) {
        std::vector<double> jacobi(size_t(n) * n, 0.0), values, vectors;
        for (int k = 1; k < n; ++k) jacobi[size_t(k - 1) * n + k] = jacobi[size_t(k) * n + k - 1] = std::sqrt(double(k));
        symmetric_eigen(jacobi, n, values, vectors);
        for (int k = 0; k < n; ++k) {
            node.push_back(values[k]);
            weight.push_back(vectors[k] * vectors[k]);
        }
    }
    std::vector<double> node, weight;
};

// The x in [lo, hi] where an increasing f reaches `aim` (within `tolerance`), and f there,
// given f_lo = f(lo); hi and f(hi) where f(hi) < aim. Regula falsi with the Illinois step
// (Dowell & Jarratt 1971), which keeps the bracket and converges superlinearly: a few
// evaluations of f.
template <typename F>
std::pair<double, double> solve_increasing(const F& f, double lo, double f_lo, double hi, double aim, double tolerance) {
    double below = f_lo - aim, above = f(hi) - aim;
    if (above <= 0) return {hi, above + aim};
    if (below >= 0) return {lo, below + aim};
    int kept = 0;  // the end kept by the last step: -1 lo, +1 hi
    for (int step = 0; step < 60; ++step) {
        const double x = hi - above * (hi - lo) / (above - below), v = f(x) - aim;
        if (std::abs(v) <= tolerance || !(x > lo && x < hi)) return {x, v + aim};
        if (v > 0) {
            hi = x, above = v;
            if (kept == +1) below /= 2;
            kept = +1;
        } else {
            lo = x, below = v;
            if (kept == -1) above /= 2;
            kept = -1;
        }
    }
    return {hi, above + aim};
}

// Printing through one table leaves no place for the paper's grain, so it is folded into the
// film's: each film layer's grain amplitude is raised so that each channel of the viewed print
// (log10 of its linear Rec.709, as a plate's grain is measured) has the grain variance of both,
// level by level along the grey scale. The extra variances are solved together (non-negative
// least squares over the three channels, through the print itself where it bends over the
// grain), and the layers' grains are correlated (a Cholesky mix of their white noises) as the
// print's channels need. The derivation: docs/model/print-grain-fold.md.
constexpr double kMaxFoldedGrainD = 0.5;

}  // namespace

// Minimisation along one coordinate at a time, projected onto x_i >= 0 (it converges for this
// convex problem; the sweeps are far more than three unknowns need). A sweep's x is a function
// of the x before it alone, so once x is one it was before, the sweeps repeat themselves from
// there, and the last sweep's x is known from one period's sweeps: the same bits as sweeping
// on. In floating point x mostly settles, or alternates among a few values in its last bits,
// within some 25 sweeps (ill-conditioned equations may change to the last); x is compared with
// the one marked at each power of two, which finds a period within twice its start and length.
// Each lane of D (L: as many int64) sweeps systems[first + l] (the last system again in the
// lanes past `count`, whose x is not stored) while it has sweeps to make, and keeps its x after.
namespace {
struct LeastSquaresLanes {
    template <int lanes>
    __attribute__((always_inline)) static void run(const LeastSquaresSystem* systems, int count, std::array<double, 3>* x) {
        for (int first = 0; first < count; first += lanes)
            solve<typename simd::Lanes<lanes>::D, typename simd::Lanes<lanes>::L>(systems, count, first, x);
    }
    template <typename D, typename L>
    __attribute__((always_inline)) static void solve(const LeastSquaresSystem* systems, int count, int first,
                                                     std::array<double, 3>* out) {
        constexpr int lanes = sizeof(D) / sizeof(double);
        constexpr int kSweeps = 300;
        double lane_a[3][3][lanes], lane_b[3][lanes];  // the lanes' systems, loaded below
        int64_t lane_free[3][lanes];
        for (int l = 0; l < lanes; ++l) {
            const LeastSquaresSystem& s = systems[std::min(first + l, count - 1)];
            for (int j = 0; j < 3; ++j) {
                lane_b[j][l] = s.b[j];
                for (int i = 0; i < 3; ++i) lane_a[j][i][l] = s.a[j][i];
            }
            for (int i = 0; i < 3; ++i) lane_free[i][l] = s.free[i] ? -1 : 0;
        }
        D a[3][3], b[3], column_norm[3]{};  // column_norm: of |A x - b|^2 / 2 along x_i
        L free[3];
        for (int j = 0; j < 3; ++j) {
            simd::load(b[j], lane_b[j]), simd::load(free[j], lane_free[j]);
            for (int i = 0; i < 3; ++i) simd::load(a[j][i], lane_a[j][i]);
        }
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) column_norm[i] += a[j][i] * a[j][i];
            free[i] &= column_norm[i] > 0;
        }
        D x[3]{}, marked[3]{};
        L repeated{}, left{};  // lanes whose x repeated the marked one; the sweeps they still make
        int marked_sweep = 0;
        for (int n = 1; n <= kSweeps; ++n) {
            const L sweeping = ~repeated | (left > 0);
            if (!simd::any_lane(sweeping)) break;
            for (int i = 0; i < 3; ++i) {
                D gradient{};
                for (int j = 0; j < 3; ++j) gradient += a[j][i] * (a[j][0] * x[0] + a[j][1] * x[1] + a[j][2] * x[2] - b[j]);
                const D next = x[i] - gradient / column_norm[i];
                x[i] = (free[i] & sweeping) ? (D{} < next ? next : D{}) : x[i];  // (std::max(0.0, next))
            }
            left += repeated & sweeping;  // (true lanes are -1)
            L same = ~repeated;  // (bits: x repeats exactly)
            for (int i = 0; i < 3; ++i) {
                L bits, marked_bits;
                std::memcpy(&bits, &x[i], sizeof bits), std::memcpy(&marked_bits, &marked[i], sizeof bits);
                same &= bits == marked_bits;
            }
            if (simd::any_lane(same)) {
                left = same ? L{} + int64_t((kSweeps - n) % (n - marked_sweep)) : left;
                repeated |= same;
            }
            if ((n & (n - 1)) == 0) {
                for (int i = 0; i < 3; ++i) marked[i] = x[i];
                marked_sweep = n;
            }
        }
        for (int l = 0; l < lanes && first + l < count; ++l)
            for (int i = 0; i < 3; ++i) out[first + l][size_t(i)] = x[i][l];
    }
};
}  // namespace

std::array<double, 3> nonnegative_least_squares(const double (&a)[3][3], const double (&b)[3], const bool (&free)[3]) {
    LeastSquaresSystem system;
    std::memcpy(system.a, a, sizeof system.a), std::memcpy(system.b, b, sizeof system.b);
    std::memcpy(system.free, free, sizeof system.free);
    std::array<double, 3> x;
    LeastSquaresLanes::run<1>(&system, 1, &x);
    return x;
}

void nonnegative_least_squares(const LeastSquaresSystem* systems, int count, std::array<double, 3>* x) {
    simd::dispatch_doubles<LeastSquaresLanes>(systems, count, x);
}

void fold_paper_grain(MaterialStages& film, const MaterialStages& paper, const PrintExposure& enlarger,
                      double exposure_scale, int curve_table_bits, int threads) {
    // (The tiers that print through one table tabulate curves; a colour film has three layers.)
    if (film.curve_tables.empty() || film.grain.size() != 3) return;
    bool grained[3], any = false;
    ScatteredGrain spread[3];
    double gain[3] = {0, 0, 0};  // the spread at the table's input per unit amplitude: kappa_i sqrt(rho_i)
    for (size_t i = 0; i < 3; ++i) {
        if (film.grain[i]) {
            spread[i] = scattered_grain(*film.grain[i], paper.scatter[i]);
            gain[i] = std::sqrt(spread[i].dot(spread[i]));
        }
        grained[i] = gain[i] > 0;
        any = any || (grained[i] && paper.grain[i]);
    }
    if (!any) return;
    // The grey scale's negative densities every quarter stop (beyond the film's curves, where
    // a step changes no density, once).
    std::vector<std::array<double, 3>> levels;
    std::vector<double> level_stops;
    for (double stops = -16; stops <= 16; stops += 0.25) {
        std::array<double, 3> d;
        for (size_t l = 0; l < 3; ++l) {
            const auto& w = film.rgb_weights[l];
            const double h = 0.18 * std::exp2(stops) * exposure_scale * (w[0] + w[1] + w[2]);
            d[l] = film.stock.layers[l].density_curve(std::log10(std::max(h, 1e-30)));
        }
        if (levels.empty() || d != levels.back()) levels.push_back(d), level_stops.push_back(stops);
    }
    const NormalQuadrature normal(8);
    const PrintView view(paper.stock, enlarger.view());
    auto log_view = [&](const double* paper_density, double* out) {
        double rgb[3];
        view.rgb(paper_density, rgb);
        for (int c = 0; c < 3; ++c) out[c] = std::log10(std::max(rgb[c], 1e-30));
    };
    auto log_print = [&](const double* negative, double* out) {
        double dp[3];
        print_densities(enlarger, paper.stock, negative, dp);
        log_view(dp, out);
    };
    // Grey: the film's mid-grey exposure, which the printer lights print at the paper's aim (with
    // the input in lux seconds the scale's 0 stops is 0.18 lux s, not grey).
    const double grey_stops = std::log2(mid_grey_exposure_lux_s(film.stock.iso_speed) / (0.18 * exposure_scale));
    const size_t grey = size_t(std::min_element(level_stops.begin(), level_stops.end(), [&](double a, double b) {
                                   return std::abs(a - grey_stops) < std::abs(b - grey_stops);
                               }) - level_stops.begin());
    // Each level's equations (3), and T (4) at grey (glm: column-major, [j][i] is T_ij; the
    // identity where M is singular there).
    struct Level {
        double a[3][3], b[3], m[3][3], film_variance[3];
    };
    std::vector<Level> equations(levels.size());
    glm::dmat3 at_grey(1.0);
    parallel_for(0, int(levels.size()), threads, [&](int begin, int end) {
        for (int level = begin; level < end; ++level) {
            const double* d = levels[size_t(level)].data();
            Level& e = equations[size_t(level)];
            double dp[3], seen[3], v[3][3];  // V_cj
            constexpr double kStep = 0.01;
            print_densities(enlarger, paper.stock, d, dp);
            log_view(dp, seen);
            for (int k = 0; k < 3; ++k) {
                double dp_up[3] = {dp[0], dp[1], dp[2]}, d_up[3] = {d[0], d[1], d[2]}, up[3];
                dp_up[k] += kStep, d_up[k] += kStep;
                log_view(dp_up, up);
                for (int c = 0; c < 3; ++c) v[c][k] = (up[c] - seen[c]) / kStep;
                log_print(d_up, up);
                for (int c = 0; c < 3; ++c) e.m[c][k] = (up[c] - seen[c]) / kStep;
            }
            double paper_variance[3];
            for (int j = 0; j < 3; ++j)
                paper_variance[j] = paper.grain[j] ? std::pow(grain_sigma_at(*paper.grain[j], dp[j]), 2) : 0.0;
            for (int i = 0; i < 3; ++i)
                e.film_variance[i] = grained[i] ? std::pow(film.grain[i]->amplitude_at(d[i]) * gain[i], 2) : 0.0;
            if (size_t(level) == grey) {
                glm::dmat3 m_inverse(0.0), paper_covariance(0.0);
                for (int c = 0; c < 3; ++c)
                    for (int i = 0; i < 3; ++i) {
                        m_inverse[i][c] = e.m[c][i];
                        for (int j = 0; j < 3; ++j) paper_covariance[i][c] += v[c][j] * v[i][j] * paper_variance[j];
                    }
                m_inverse = glm::inverse(m_inverse);
                glm::dmat3 t = m_inverse * paper_covariance * glm::transpose(m_inverse);
                for (int i = 0; i < 3; ++i) t[i][i] += e.film_variance[i];
                bool finite = true;
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) finite = finite && std::isfinite(t[j][i]);
                if (finite) at_grey = t;
            }
            for (int c = 0; c < 3; ++c) {
                e.b[c] = 0;
                for (int j = 0; j < 3; ++j) e.b[c] += v[c][j] * v[c][j] * paper_variance[j];
                for (int i = 0; i < 3; ++i) e.a[c][i] = e.m[c][i] * e.m[c][i];
                if (!grained[c] || e.b[c] == 0) continue;
                // Var v_c(D + s Z e_c), the other layers' densities held.
                auto print_variance = [&](double s) {
                    double mean = 0, square = 0;
                    for (size_t k = 0; k < normal.node.size(); ++k) {
                        double dk[3] = {d[0], d[1], d[2]}, vk[3];
                        dk[c] += s * normal.node[k];
                        log_print(dk, vk);
                        mean += normal.weight[k] * vk[c];
                        square += normal.weight[k] * vk[c] * vk[c];
                    }
                    return std::max(0.0, square - mean * mean);
                };
                const double s_film = std::sqrt(e.film_variance[c]);
                const double film_variance = print_variance(s_film);
                const double s_max = std::max(s_film, kMaxFoldedGrainD);
                const auto [s, variance] = solve_increasing(print_variance, s_film, film_variance, s_max,
                                                           film_variance + e.b[c], 1e-3 * e.b[c]);
                if (s > s_film) e.a[c][c] = (variance - film_variance) / (s * s - s_film * s_film);
            }
        }
    });
    // 4: T at grey, its correlation over the kernels' overlaps, factored.
    std::vector<double> wanted(9, 0.0), kernels(9, 1.0);  // the layers' grains' correlations, their kernels' overlaps
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const size_t ij = size_t(i) * 3 + j;
            if (i == j) wanted[ij] = 1.0;
            if (i == j || !grained[i] || !grained[j] || !(at_grey[i][i] > 0 && at_grey[j][j] > 0)) continue;
            kernels[ij] = spread[i].dot(spread[j]) / (gain[i] * gain[j]);
            wanted[ij] = at_grey[j][i] / std::sqrt(at_grey[i][i] * at_grey[j][j]);
        }
    const std::vector<double> factor = white_noise_mixing(wanted, kernels, 3);  // L, row-major
    double correlation[3][3];  // Q: the layers' grains' at the table's input
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            correlation[i][j] = 0;
            for (int k = 0; k < 3; ++k) correlation[i][j] += factor[size_t(i) * 3 + k] * factor[size_t(j) * 3 + k];
            correlation[i][j] *= kernels[size_t(i) * 3 + j];
        }
    // 3 with the cross terms, each level on its own: solved without them, then again with those
    // of the last solution until it settles (30 times at most), the levels still unsettled
    // solved together in vectors of systems.
    std::vector<std::array<double, 3>> extra(levels.size());  // e_i at each level
    parallel_for(0, int(levels.size()), threads, [&](int begin, int end) {
        std::vector<LeastSquaresSystem> systems;
        std::vector<int> unsettled;  // the levels' indices
        std::vector<std::array<double, 3>> t(size_t(end - begin)), next;
        for (int level = begin; level < end; ++level) {
            const Level& e = equations[size_t(level)];
            systems.push_back({});
            std::memcpy(systems.back().a, e.a, sizeof e.a), std::memcpy(systems.back().b, e.b, sizeof e.b);
            std::memcpy(systems.back().free, grained, sizeof grained);
            unsettled.push_back(level);
        }
        nonnegative_least_squares(systems.data(), int(systems.size()), t.data());
        for (int iteration = 0; iteration < 30 && !unsettled.empty(); ++iteration) {
            for (size_t u = 0; u < unsettled.size(); ++u) {
                const Level& e = equations[size_t(unsettled[u])];
                const std::array<double, 3>& t_level = t[size_t(unsettled[u] - begin)];
                double s[3];
                for (int i = 0; i < 3; ++i) s[i] = std::sqrt(e.film_variance[i] + t_level[i]);
                double* const b = systems[u].b;
                std::memcpy(systems[u].a, e.a, sizeof e.a);
                for (int c = 0; c < 3; ++c) {
                    b[c] = e.b[c];
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j)
                            if (i != j) b[c] -= e.m[c][i] * e.m[c][j] * s[i] * s[j] * correlation[i][j];
                }
            }
            next.resize(unsettled.size());
            nonnegative_least_squares(systems.data(), int(unsettled.size()), next.data());
            size_t still = 0;
            for (size_t u = 0; u < unsettled.size(); ++u) {
                std::array<double, 3>& t_level = t[size_t(unsettled[u] - begin)];
                if (next[u] == t_level) continue;  // (settled: every later sweep would repeat it)
                t_level = next[u];
                unsettled[still++] = unsettled[u];
            }
            unsettled.resize(still);
        }
        for (int level = begin; level < end; ++level)
            for (int i = 0; i < 3; ++i)
                extra[size_t(level)][size_t(i)] = grained[i] ? std::sqrt(t[size_t(level - begin)][size_t(i)]) / gain[i] : 0.0;
    });
    for (size_t i = 0; i < 3; ++i) {
        if (!grained[i]) continue;
        std::vector<double> density_i, extra_i;
        for (size_t level = 0; level < levels.size(); ++level)
            density_i.push_back(levels[level][i]), extra_i.push_back(extra[level][i]);
        GrainModel& film_grain = *film.grain[i];
        if (factor[i * 3 + i] != 1.0)
            for (size_t j = 0; j <= i; ++j)
                if (factor[i * 3 + j] != 0.0)
                    film_grain.mixed_noise.push_back({film.grain[j]->key, float(factor[i * 3 + j])});
        const Curve extra_at = make_curve(std::move(density_i), std::move(extra_i), "paper grain on the film's densities");
        film.curve_tables[i] = LogAxisTable(film.develop_curve(i), curve_table_bits,
                                            [film_grain, extra_at](double d) {
                                                return std::hypot(film_grain.amplitude_at(d), extra_at(d));
                                            });
    }
}

// Printing through one table (QualityTier::print_table_nodes) runs no grain or halation on
// the paper (nor its tabulated curves, which the table composes): its grain is in the film's
// where the film layer has grain (fold_paper_grain), and its MTF is applied to the negative's
// densities (Plan::print).
void leave_out_paper_grain(MaterialStages& paper, const MaterialStages& film, std::vector<std::string>& skipped) {
    for (size_t i = 0; i < paper.stock.layers.size(); ++i) {
        const std::string where = "paper layer " + paper.stock.layers[i].name;
        if (paper.grain[i] || paper.boolean_grain[i])
            skipped.push_back("grain (" + where + "): " +
                              (film.grain[i] ? "folded into the film layer's" : "left out (the film layer has none)") +
                              ", the print being one table");
        if (paper.halation[i]) skipped.push_back("halation (" + where + "): left out, the print being one table");
        paper.grain[i].reset();
        paper.boolean_grain[i].reset();
        paper.halation[i].reset();
    }
    paper.curve_tables.clear();
}


}  // namespace darkroom
