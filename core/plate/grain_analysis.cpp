#include "core/plate/grain_analysis.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>

#include <glm/glm.hpp>

#include "core/parallel.h"
#include "core/plate/block_surface.h"
#include "core/plate/grain_synthesis.h"
#include "core/plate/symmetric_eigenvalues.h"
#include "core/stages/filters.h"

namespace darkroom {

namespace {

constexpr double kRejectionSigmas = 3.5;   // a block further from the curve than this is not grain only
// Blocks the autocorrelation is measured on: enough for a stable estimate at bounded cost
// (fewer in the early passes, which only steer the block selection).
constexpr int kMaxAutocorrelationBlocks = 256, kEarlyAutocorrelationBlocks = 48;
// The last pass reads the autocorrelation (which whitens the response and is reported) from
// this share of the accepted blocks, those whose neighbourhoods (the 8 blocks around) are
// quietest: picture content faint enough to pass the block tests adds its own, smoother
// correlation, which the whitening would take for grain. Such content is spatially coherent,
// and a block's neighbours hold other grain than its own, so choosing by them does not bias
// the grain's correlation as choosing by the block's own variance would (a block quiet by
// chance is quiet in its low frequencies). The earlier passes, which steer the selection,
// read all the accepted blocks: on a plate textured throughout, choosing by neighbourhoods
// there drifted the selection into the texture.
constexpr double kQuietNeighbourhoodShare = 0.5;
// Minimal-residual steps of the fit-bias correction of the autocorrelation per pass.
constexpr int kEarlySolverSteps = 3, kFinalSolverSteps = 10;
// The default block size follows the grain: the analysis starts at the smallest block and
// grows it (in steps of 8 px, up to the largest) while the measured grain's correlation
// reaches past a quarter of the block (its lag grid), as long as the plate holds enough blocks.
constexpr int kSmallestBlockPx = 16, kLargestBlockPx = 64, kBlockStepPx = 8, kMinAutoBlockCount = 400;
constexpr int kMinBlockCount = 16;  // fewer blocks of the smallest size: the plate is too small
// Block size / grain size (the std of a Gaussian autocorrelation exp(-d^2 / (4 s^2)) with the
// measured lag-1 value) that keeps the correlation down to 7 % (at 3.25 s) inside the lag grid.
// No larger: the larger the block, the more of a picture its surface leaves in the residual
// (known 1 px grain on the Kodak plates reads up to 10.8 % high in 24 px blocks, 7.7 % in 16 px).
constexpr double kBlockPerGrainSize = 13.0;
// The response is the low quantile of the candidate blocks' variance at each level, divided
// by the same quantile of grain alone: picture content only adds variance, so it is read from
// the quietest blocks, and a level stays unbiased while most of its blocks hold content.
constexpr double kResponseQuantile = 0.4;
// Grain is stationary within a block, edges and local detail are not: the dispersion of the
// log variances of a block's four quadrants, in units of its grain-only variance, is about
// chi-square with 3 degrees of freedom; this is its 0.999 quantile.
constexpr double kStationarityLimit = 16.27;
// Texture and edges differ from grain in their short-range correlation as well as in
// their variance: each block's own autocorrelation at these lags must be typical.
constexpr int kShapeLags[][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}, {2, 0}, {0, 2}, {4, 0}, {0, 4}};
constexpr int kShapeLagCount = sizeof(kShapeLags) / sizeof(kShapeLags[0]);
constexpr double kShapeOutlierMads = 5.0;
// Weak texture (Liu, Tanaka and Okutomi, IEEE TIP 2013): a block of grain alone has a
// gradient covariance whose largest eigenvalue is about Gamma distributed around that of the
// grain's expected gradient covariance (from sigma at its level and the autocorrelation at
// lags 1); a block above its 0.99 quantile holds texture.
constexpr double kWeakTextureZ = 2.3263478740408408;  // standard normal quantile of 0.99
// The curve and the weak-texture selection are iterated until the curve's variances settle.
constexpr int kWeakTextureIterations = 8;
constexpr double kWeakTextureSettled = 1e-3;
// The low-band test's cells: a grid of this many a side over the block.
constexpr int kLowBandCellsPerSide = 8;

// The quantile at standard normal quantile z of a Gamma variable of this shape, over its mean
// (Wilson-Hilferty).
double gamma_quantile_over_mean(double shape, double z) {
    const double h = 1.0 / (9 * shape);
    return std::pow(1 - h + z * std::sqrt(h), 3.0);
}

// A block's low frequencies: the means of its residual over a grid of square cells. Picture
// content a few pixels across (gradients, soft texture, a defocused background) that the
// surface cannot follow keeps its power there, while grain's averages out: a block whose
// cell means hold more power than grain of the curve's sigma and the measured
// autocorrelation gives (a chi-square test, as libaom's noise model compares each block's
// spectrum with the noise's) holds content. A residual's cell mean is u_c . g for grain g,
// with u_c = (I - P) 1_c / m^2 (P the surface fit, m the cell's side), so its covariance is
// exactly u_c . R u_c'.
struct LowBand {
    const SurfaceFit& fit;
    int cells_per_side = 0, cell_px = 0;
    std::vector<std::array<double, SurfaceFit::kTerms>> basis_weight;  // per cell c, b_k . 1_c / m^2

    LowBand(const SurfaceFit& surface, int cells) : fit(surface), cells_per_side(cells), cell_px(surface.size / cells) {
        for (int c = 0; c < cell_count(); ++c) {
            std::array<double, SurfaceFit::kTerms> dots{};
            for (int k = 0; k < SurfaceFit::kTerms; ++k) dots[k] = cell_mean(fit.basis[k].data(), c);
            basis_weight.push_back(dots);
        }
    }

    int cell_count() const { return cells_per_side * cells_per_side; }

    // The mean of v (a block, row-major) over cell c.
    double cell_mean(const double* v, int c) const {
        const int x0 = c % cells_per_side * cell_px, y0 = c / cells_per_side * cell_px;
        double sum = 0;
        for (int y = y0; y < y0 + cell_px; ++y)
            for (int x = x0; x < x0 + cell_px; ++x) sum += v[(size_t)y * fit.size + x];
        return sum / (cell_px * cell_px);
    }

    // The sum of squares of a residual's cell means.
    double power(const double* residual) const {
        double sum = 0;
        for (int c = 0; c < cell_count(); ++c) sum += cell_mean(residual, c) * cell_mean(residual, c);
        return sum;
    }

    // For grain of unit variance and autocorrelation rho: the power's mean (the trace of the
    // cell means' covariance C) and its degrees of freedom as a scaled chi-square
    // (Satterthwaite: tr(C)^2 / tr(C^2)). R u_c is R 1_c / m^2 (a sum of rho over a
    // rectangle of lags, from its summed-area table) less the projection's R b_k.
    struct Expectation {
        double mean = 0, dof = 0;
    };
    Expectation expectation(const std::vector<double>& rho, const LagGrid& lags) const {
        const int n = fit.size, side = lags.side(), r = lags.radius;
        std::vector<double> area((size_t)(side + 1) * (side + 1), 0.0);  // sums of rho over lags below and left
        for (int j = 0; j < side; ++j)
            for (int i = 0; i < side; ++i)
                area[(size_t)(j + 1) * (side + 1) + i + 1] = rho[(size_t)j * side + i] + area[(size_t)j * (side + 1) + i + 1] +
                                                             area[(size_t)(j + 1) * (side + 1) + i] - area[(size_t)j * (side + 1) + i];
        std::vector<double> applied_basis[SurfaceFit::kTerms];
        for (int k = 0; k < SurfaceFit::kTerms; ++k) applied_basis[k] = apply_autocorrelation(rho, lags, n, fit.basis[k]);
        std::vector<std::vector<double>> applied(cell_count(), std::vector<double>((size_t)n * n));  // R u_c
        for (int c = 0; c < cell_count(); ++c) {
            const int x0 = c % cells_per_side * cell_px, y0 = c / cells_per_side * cell_px;
            for (int y = 0; y < n; ++y) {
                const int dy0 = std::max(-r, y0 - y), dy1 = std::min(r, y0 + cell_px - 1 - y);
                for (int x = 0; x < n; ++x) {
                    const int dx0 = std::max(-r, x0 - x), dx1 = std::min(r, x0 + cell_px - 1 - x);
                    double sum = 0;
                    if (dy0 <= dy1 && dx0 <= dx1)
                        sum = area[(size_t)(dy1 + r + 1) * (side + 1) + dx1 + r + 1] - area[(size_t)(dy0 + r) * (side + 1) + dx1 + r + 1] -
                              area[(size_t)(dy1 + r + 1) * (side + 1) + dx0 + r] + area[(size_t)(dy0 + r) * (side + 1) + dx0 + r];
                    sum /= cell_px * cell_px;
                    for (int k = 0; k < SurfaceFit::kTerms; ++k) sum -= basis_weight[c][k] * applied_basis[k][(size_t)y * n + x];
                    applied[c][(size_t)y * n + x] = sum;
                }
            }
        }
        // C_ab = u_a . R u_b = (R u_b summed over cell a) / m^2 - sum_k (b_k . 1_a / m^2) (b_k . R u_b).
        double trace = 0, trace_squared = 0;
        for (int b = 0; b < cell_count(); ++b) {
            double projection[SurfaceFit::kTerms] = {};
            for (int k = 0; k < SurfaceFit::kTerms; ++k)
                for (size_t p = 0; p < applied[b].size(); ++p) projection[k] += fit.basis[k][p] * applied[b][p];
            for (int a = 0; a < cell_count(); ++a) {
                double c = cell_mean(applied[b].data(), a);
                for (int k = 0; k < SurfaceFit::kTerms; ++k) c -= basis_weight[a][k] * projection[k];
                trace += a == b ? c : 0.0;
                trace_squared += c * c;
            }
        }
        return {trace, trace_squared > 0 ? trace * trace / trace_squared : 0.0};
    }
};

struct Block {
    std::vector<double> residual;  // channel-planar: [c][y][x]
    std::vector<double> level;     // mean per channel
    std::vector<double> squares;   // residual sum of squares per channel
    std::vector<double> quadrant_squares;  // per channel, that of each quadrant
    std::vector<double> shape;     // per channel, the block's autocorrelation at kShapeLags
    std::vector<double> gradient;  // per channel, mean gh^2, gv^2, gh gv (forward differences)
    std::vector<double> low_band;  // per channel, LowBand::power of the residual
    std::vector<float> extremes;   // per channel, its lowest and highest pixel
};

// The largest eigenvalue of the symmetric 2x2 matrix [[a, b], [b, c]].
double largest_eigenvalue(double a, double b, double c) { return 0.5 * (a + c) + std::hypot(0.5 * (a - c), b); }

double median_of(std::vector<double> v) {
    if (v.empty()) return 0;
    auto mid = v.begin() + v.size() / 2;
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

// The q-quantile, interpolated between order statistics.
double quantile_of(std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    const double at = q * (v.size() - 1);
    const size_t i = std::min(v.size() - 1, (size_t)at);
    return i + 1 < v.size() ? v[i] + (at - i) * (v[i + 1] - v[i]) : v[i];
}

constexpr double kResponseQuantileZ = -0.2533471031357997;  // standard normal quantile of kResponseQuantile

// A grain-only block's variance estimate / sigma^2 is about chi-square / nu with
// nu = 2 / relative_sd^2: its kResponseQuantile quantile (Wilson-Hilferty).
double grain_quantile(double relative_sd) {
    const double h = relative_sd * relative_sd / 9.0;  // 2 / (9 nu)
    return std::pow(1.0 - h + kResponseQuantileZ * std::sqrt(h), 3.0);
}

// The relative standard error of sigma read from that quantile of n blocks.
double quantile_sigma_error(double relative_sd, int n) {
    const double density = std::exp(-0.5 * kResponseQuantileZ * kResponseQuantileZ) / std::sqrt(2 * M_PI);
    const double variance_error = relative_sd * std::sqrt(kResponseQuantile * (1 - kResponseQuantile) / n) / density;
    return 0.5 * variance_error / grain_quantile(relative_sd);
}

// Variance against level: piecewise linear through the bins' (mean level, variance).
struct LevelCurve {
    std::vector<double> level, variance;
    std::vector<double> error;  // relative standard error of sigma
    std::vector<int> bin, blocks;
    double at(double x) const {
        if (level.empty()) return 0;
        if (x <= level.front()) return variance.front();
        if (x >= level.back()) return variance.back();
        size_t i = std::upper_bound(level.begin(), level.end(), x) - level.begin();
        double t = (x - level[i - 1]) / (level[i] - level[i - 1]);
        return variance[i - 1] + t * (variance[i] - variance[i - 1]);
    }
    void erase(size_t k) {
        for (auto* v : {&level, &variance, &error}) v->erase(v->begin() + k);
        for (auto* v : {&bin, &blocks}) v->erase(v->begin() + k);
    }
};

// Picture content only adds variance, and grain's varies smoothly with the level: a bin more
// than this many times the variance its neighbours give at its level holds edges or texture
// (a level the picture reaches only in its content, which the block tests cannot tell from
// grain there, having no grain-only blocks to compare with).
constexpr double kContentVarianceRatio = 2.0;

// The curve without such bins, the worst first (each judged against the bins left), while
// three or more remain: their blocks are then judged by their neighbours' grain.
void drop_content_bins(LevelCurve& curve) {
    while (curve.level.size() >= 3) {
        size_t worst = 0;
        double worst_ratio = 0;
        for (size_t k = 0; k < curve.level.size(); ++k) {
            // Its neighbours' line at its level (the nearest neighbour's variance at the ends).
            double expected;
            if (k == 0 || k + 1 == curve.level.size()) {
                expected = curve.variance[k == 0 ? 1 : k - 1];
            } else {
                const double t = (curve.level[k] - curve.level[k - 1]) / (curve.level[k + 1] - curve.level[k - 1]);
                expected = curve.variance[k - 1] + t * (curve.variance[k + 1] - curve.variance[k - 1]);
            }
            const double ratio = expected > 0 ? curve.variance[k] / expected : 0;
            if (ratio > worst_ratio) worst_ratio = ratio, worst = k;
        }
        if (!(worst_ratio > kContentVarianceRatio)) return;
        curve.erase(worst);
    }
}

// Across levels, grain changes its amount smoothly and boundedly: at most in proportion to the
// signal in a linear encoding, by at most this factor per unit of level in log and display
// code values. A level whose variance exceeds kContentVarianceRatio times what the quieter
// levels allow holds content at every block (a textured wall, foliage): the quietest blocks
// of a picture reach grain alone only at some levels.
constexpr double kMaxSigmaRatioPerUnitLevel = 4.0;

double max_variance_ratio(double level_a, double level_b, SignalEncoding encoding) {
    if (encoding != SignalEncoding::linear)
        return std::exp(2.0 * std::log(kMaxSigmaRatioPerUnitLevel) * std::abs(level_a - level_b));
    if (!(level_a > 0 && level_b > 0)) return INFINITY;
    return std::pow(std::max(level_a / level_b, level_b / level_a), 2.0);
}

// Two levels whose variances agree within this (times the encoding's allowance) support each
// other as grain.
constexpr double kAnchorVarianceRatio = 4.0;

// The curve without levels above that envelope. A level bounds the others only where another
// level agrees with it (a lone quiet level, such as clipped highlights, bounds nothing).
void drop_levels_above_envelope(LevelCurve& curve, SignalEncoding encoding) {
    const size_t n = curve.level.size();
    auto consistent = [&](size_t i, size_t j) {
        const double allowed = kAnchorVarianceRatio * max_variance_ratio(curve.level[i], curve.level[j], encoding);
        return curve.variance[i] > 0 && curve.variance[j] > 0 && curve.variance[i] <= allowed * curve.variance[j] &&
               curve.variance[j] <= allowed * curve.variance[i];
    };
    std::vector<char> anchor(n, 0), content(n, 0);
    for (size_t j = 0; j < n; ++j)
        for (size_t i = 0; i < n && !anchor[j]; ++i) anchor[j] = i != j && consistent(i, j);
    for (size_t k = 0; k < n; ++k)
        for (size_t j = 0; j < n && !content[k]; ++j)
            content[k] = j != k && anchor[j] &&
                         curve.variance[k] >
                             kContentVarianceRatio * curve.variance[j] * max_variance_ratio(curve.level[k], curve.level[j], encoding);
    for (size_t k = n; k-- > 0;)
        if (content[k]) curve.erase(k);
}

// Grain's response is smooth in level (a film's granularity against density is), while each
// level's estimate carries the noise of its few blocks and whatever picture content passed the
// block tests there (known 1 px grain on the Kodak plates: 10-20 % in variance at levels of
// 4-15 blocks). The reported response is a local quadratic fit of log variance against level
// (log level in a linear encoding, where grain scales with the signal), weighted by each
// level's precision, by a Gaussian of kResponseSmoothingWidth of the measured range, and by a
// Gaussian of how far apart the two levels' variances are in kPooledApartErrors of their
// combined standard errors: a step the data show plainly (a stock's toe, where grain rises
// from almost none; 25 % off in a predicted Tri-X's round trip when pooled) stays a step.
constexpr double kResponseSmoothingWidth = 0.5, kPooledApartErrors = 5.0;

void smooth_response(LevelCurve& curve, SignalEncoding encoding) {
    const size_t n = curve.level.size();
    if (n < 3) return;
    bool log_level = encoding == SignalEncoding::linear;
    for (double l : curve.level) log_level &= l > 0;
    std::vector<double> x(n), log_variance(n);
    for (size_t k = 0; k < n; ++k) {
        if (!(curve.variance[k] > 0 && curve.error[k] > 0)) return;  // no grain at a level: nothing to pool
        x[k] = log_level ? std::log(curve.level[k]) : curve.level[k];
        log_variance[k] = std::log(curve.variance[k]);
    }
    const double width = kResponseSmoothingWidth * (x.back() - x.front());
    if (!(width > 0)) return;
    // Weighted least squares on 1, u, u^2 with u = (x - x0) / width, at each level's x0; the
    // weighted mean where the levels in reach cannot hold a quadratic.
    std::vector<double> smooth(n);
    for (size_t j = 0; j < n; ++j) {
        glm::dmat3 normal(0.0);
        glm::dvec3 right(0.0);
        double weights = 0, mean = 0;
        for (size_t k = 0; k < n; ++k) {
            const double u = (x[k] - x[j]) / width, y = log_variance[k];
            const double combined_error = std::hypot(curve.error[k], curve.error[j]);
            const double apart = (y - log_variance[j]) / (2 * kPooledApartErrors * combined_error);
            const double w = std::exp(-0.5 * u * u - 0.5 * apart * apart) / (curve.error[k] * curve.error[k]);
            const glm::dvec3 f(1.0, u, u * u);
            normal += w * glm::outerProduct(f, f);
            right += w * y * f;
            weights += w, mean += w * y;
        }
        const bool solvable = std::abs(glm::determinant(normal)) > 1e-9 * normal[0][0] * normal[1][1] * normal[2][2];
        smooth[j] = std::exp(solvable ? (glm::inverse(normal) * right)[0] : mean / weights);
    }
    curve.variance = smooth;
}

// Grain variance in patch space (Liu, Tanaka and Okutomi, "Single-image noise level estimation
// for blind denoising", IEEE TIP 2013): picture content is low-rank among small patches, so
// the small eigenvalues of the patches' covariance, whitened by the grain's own (its
// autocorrelation on the patch's lags), are the grain's alone, however much content the
// other directions hold. Which are the grain's (Chen, Zhu and Heng, "An efficient statistical
// method for image noise level estimation", ICCV 2015): the most of the smallest whose mean is
// not above their median (content's eigenvalues stand out above the grain's spread); their
// mean is the variance. Sample eigenvalues spread about the true ones (Marchenko-Pastur), the
// more the fewer and the more correlated the patches, so this reads low: the same statistic on
// synthetic grain of the same autocorrelation, in as many blocks through the same surface
// fit, gives that bias, which divides it out.
constexpr int kPatchSidePx = 5;
// Patch-space directions where the grain's covariance is below this fraction of its largest
// eigenvalue are left out: the measured autocorrelation says too little there to whiten by.
constexpr double kPatchSpaceFloor = 0.1;
// Synthetic grain per channel: a few times the most blocks a level holds (at least as many),
// and at least a field of 512 x 512 px: the bias is the mean over several groups of that
// many blocks, and divides every level of that many blocks, so its own error is alike at
// all of them.
constexpr int kMinCalibrationPixels = 512 * 512, kMaxCalibrationBlocks = 4096, kCalibrationGroups = 4;
constexpr int kMaxCalibrationGroups = 64;  // bounds the eigen-solves for a level of few blocks
constexpr uint64_t kCalibrationSeed = 0x9a7c4e5;

// Sums over a set of patches (each a vector of side^2 pixels): of x x^T (row-major) and of x.
struct PatchMoments {
    std::vector<double> second, first;
    long long count = 0;
    explicit PatchMoments(int dim) : second((size_t)dim * dim, 0.0), first(dim, 0.0) {}
    void add(const PatchMoments& other) {
        for (size_t i = 0; i < second.size(); ++i) second[i] += other.second[i];
        for (size_t i = 0; i < first.size(); ++i) first[i] += other.first[i];
        count += other.count;
    }
};

struct PatchSpace {
    int side = 0, dim = 0, kept = 0;
    std::vector<double> whitening;  // kept x dim: Lambda^-1/2 V^T of the grain's patch covariance

    PatchSpace(const std::vector<double>& rho, const LagGrid& lags, int patch_side)
        : side(patch_side), dim(patch_side * patch_side) {
        std::vector<double> covariance((size_t)dim * dim), values, vectors;
        for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j)
                covariance[(size_t)i * dim + j] = rho[lags.index(j % side - i % side, j / side - i / side)];
        symmetric_eigen(covariance, dim, values, vectors);
        const double largest = *std::max_element(values.begin(), values.end());
        for (int k = 0; k < dim; ++k) {
            if (!(values[k] >= kPatchSpaceFloor * largest)) continue;
            for (int i = 0; i < dim; ++i) whitening.push_back(vectors[(size_t)i * dim + k] / std::sqrt(values[k]));
            ++kept;
        }
    }

    // Every patch of an n x n block (row-major). Patch pixels i and j lie a fixed lag apart, so
    // their products over all patches sum the block's products at that lag over a square of
    // the block: a summed-area table per lag, not a product per pair and patch.
    void accumulate(const double* block, int n, PatchMoments& m) const {
        const int origins = n - side + 1;  // patch positions along each axis
        std::vector<double> values((size_t)n * n);
        std::vector<double> table((size_t)(n + 1) * (n + 1), 0.0);  // of values: sums over [0, x) x [0, y)
        auto fill_table = [&]() {
            for (int y = 0; y < n; ++y) {
                double row = 0;
                for (int x = 0; x < n; ++x) {
                    row += values[(size_t)y * n + x];
                    table[(size_t)(y + 1) * (n + 1) + x + 1] = table[(size_t)y * (n + 1) + x + 1] + row;
                }
            }
        };
        auto origins_sum = [&](int i) {  // of values at patch pixel i over all patches
            const int x0 = i % side, y0 = i / side, x1 = x0 + origins, y1 = y0 + origins;
            auto at = [&](int x, int y) { return table[(size_t)y * (n + 1) + x]; };
            return at(x1, y1) - at(x1, y0) - at(x0, y1) + at(x0, y0);
        };
        std::copy(block, block + values.size(), values.begin());
        fill_table();
        for (int i = 0; i < dim; ++i) m.first[i] += origins_sum(i);
        // The lags from a pixel to the ones after it in row-major order (a pixel without a partner
        // at the lag is in no patch's pair: 0).
        for (int dy = 0; dy < side; ++dy)
            for (int dx = dy == 0 ? 0 : 1 - side; dx < side; ++dx) {
                std::fill(values.begin(), values.end(), 0.0);
                for (int y = 0; y + dy < n; ++y)
                    for (int x = std::max(0, -dx); x < std::min(n, n - dx); ++x)
                        values[(size_t)y * n + x] = block[(size_t)y * n + x] * block[(size_t)(y + dy) * n + x + dx];
                fill_table();
                for (int i = 0; i < dim; ++i) {
                    const int x = i % side + dx, y = i / side + dy;
                    if (x >= 0 && x < side && y < side) m.second[(size_t)i * dim + y * side + x] += origins_sum(i);
                }
            }
        m.count += (long long)origins * origins;
    }

    // The grain's variance from the patches' whitened covariance (accumulate's upper triangle),
    // before the bias correction.
    double grain_variance(const PatchMoments& m) const {
        std::vector<double> covariance((size_t)dim * dim);
        for (int i = 0; i < dim; ++i)
            for (int j = i; j < dim; ++j)
                covariance[(size_t)i * dim + j] = covariance[(size_t)j * dim + i] =
                    (m.second[(size_t)i * dim + j] - m.first[i] * m.first[j] / m.count) / (m.count - 1);
        std::vector<double> half((size_t)kept * dim, 0.0), whitened((size_t)kept * kept, 0.0);
        for (int k = 0; k < kept; ++k)
            for (int i = 0; i < dim; ++i)
                for (int j = 0; j < dim; ++j)
                    half[(size_t)k * dim + j] += whitening[(size_t)k * dim + i] * covariance[(size_t)i * dim + j];
        for (int k = 0; k < kept; ++k)
            for (int l = 0; l < kept; ++l)
                for (int j = 0; j < dim; ++j)
                    whitened[(size_t)k * kept + l] += half[(size_t)k * dim + j] * whitening[(size_t)l * dim + j];
        const std::vector<double> values = symmetric_eigenvalues(whitened, kept);
        auto mean_of_smallest = [&](int m) { return std::accumulate(values.begin(), values.begin() + m, 0.0) / m; };
        auto median_of_smallest = [&](int m) { return m % 2 ? values[m / 2] : 0.5 * (values[m / 2 - 1] + values[m / 2]); };
        int grain_count = kept;
        while (grain_count > 1 && mean_of_smallest(grain_count) > median_of_smallest(grain_count)) --grain_count;
        return mean_of_smallest(grain_count);
    }
};

// PatchSpace::grain_variance of unit grain of the measured autocorrelation, by the number of
// blocks it is read from: its mean and relative standard deviation.
class PatchCalibration {
public:
    PatchCalibration(const PatchSpace& space, const SurfaceFit& surface, const std::vector<double>& rho,
                     const LagGrid& lags, int channel, int most_blocks, int threads)
        : space_(space) {
        // Unit grain of that autocorrelation over a field of blocks, as the plate's are tiled.
        GrainProfile grain;
        GrainChannel channel_grain;
        channel_grain.level = {0.0, 1.0};
        channel_grain.sigma = {1.0, 1.0};
        channel_grain.acf_radius = lags.radius;
        channel_grain.autocorrelation = rho;
        grain.channels = {channel_grain};
        const int n = surface.size, columns = 16;
        const int count =
            std::max(most_blocks, std::clamp(kCalibrationGroups * most_blocks, kMinCalibrationPixels / (n * n), kMaxCalibrationBlocks));
        Image field(columns * n, (count + columns - 1) / columns * n, 1);
        apply_grain_profile(grain, field.view(), kCalibrationSeed, channel, threads);
        blocks_.assign(count, PatchMoments(space.dim));
        parallel_for(0, count, threads, [&](int begin, int end) {
            std::vector<double> block((size_t)n * n);
            for (int b = begin; b < end; ++b) {
                for (int y = 0; y < n; ++y)
                    for (int x = 0; x < n; ++x) block[(size_t)y * n + x] = field.at(b % columns * n + x, b / columns * n + y)[0];
                surface.subtract_from(block.data());
                space.accumulate(block.data(), n, blocks_[b]);
            }
        });
    }

    struct Bias {
        double mean = 0, relative_sd = 0;
    };
    // The mean over groups of `blocks` consecutive synthetic blocks; the spread over groups of
    // at most a quarter of them, scaled to `blocks` (a variance estimate's error falls as the
    // square root of its blocks).
    Bias at(int blocks) {
        auto found = cache_.find(blocks);
        if (found != cache_.end()) return found->second;
        Bias bias;
        const std::vector<double> variance = group_variances(blocks);
        for (double v : variance) bias.mean += v / variance.size();
        const int spread_blocks = std::min<int>(blocks, (int)blocks_.size() / kCalibrationGroups);
        const std::vector<double> spread_variance = spread_blocks == blocks ? variance : group_variances(spread_blocks);
        double mean = 0, spread = 0;
        for (double v : spread_variance) mean += v / spread_variance.size();
        for (double v : spread_variance) spread += (v - mean) * (v - mean) / (spread_variance.size() - 1);
        bias.relative_sd = std::sqrt(spread * spread_blocks / blocks) / mean;
        return cache_[blocks] = bias;
    }

private:
    std::vector<double> group_variances(int size) const {
        std::vector<double> variance;
        for (size_t start = 0; start + size <= blocks_.size() && variance.size() < kMaxCalibrationGroups; start += size) {
            PatchMoments m(space_.dim);
            for (size_t b = start; b < start + size; ++b) m.add(blocks_[b]);
            variance.push_back(space_.grain_variance(m));
        }
        return variance;
    }

    const PatchSpace& space_;
    std::vector<PatchMoments> blocks_;
    std::map<int, Bias> cache_;
};

struct ChannelState {
    std::vector<double> rho;        // autocorrelation on the lag grid
    std::vector<char> candidate;    // per block: grain-like short-range correlation, stationary
    std::vector<char> accepted;     // per block: a candidate whose variance fits the curve
    std::vector<char> clipped;      // per block: reaches the plate's lowest or highest value
    std::vector<int> bin;           // per block
    LevelCurve curve;               // the blocks' selection: the quantile of their variances
    LevelCurve response;            // reported: the same blocks' variance in patch space
    double dof = 0;                 // N - trace: expected residual sum of squares / sigma^2
    LowBand::Expectation low_band;  // of a grain-only block's LowBand::power / sigma^2
    double relative_sd = 0;         // of a grain-only block's variance estimate
};

// The blocks of the frames at one block size, and what the passes made of them.
struct BlockAnalysis {
    int block_px = 0, channels = 0, bins = 0;
    int next_block_px = 0;  // the block size to analyse next: block_px where this one is final
    LagGrid lags;
    std::vector<Block> blocks;
    std::vector<std::vector<int>> neighbours;  // per block, the blocks around it in its frame
    std::vector<ChannelState> state;
};

// How far a block's neighbourhood is above grain in channel c: the mean of its neighbours'
// variance over the curve's, less 1, each capped at the acceptance limit (an edge beside a
// block weighs no more than any block the tests reject). INFINITY without neighbours.
double neighbourhood_excess(const BlockAnalysis& a, int c, int i) {
    const ChannelState& s = a.state[c];
    double excess = 0;
    int counted = 0;
    for (int j : a.neighbours[i]) {
        const double expected = s.curve.at(a.blocks[j].level[c]);
        if (!(expected > 0)) continue;
        excess += std::min(a.blocks[j].squares[c] / s.dof / expected - 1, kRejectionSigmas * s.relative_sd);
        ++counted;
    }
    return counted ? excess / counted : INFINITY;
}

// Of the given blocks, those whose neighbourhoods are quietest by excess(i)
// (kQuietNeighbourhoodShare of them, at least kEarlyAutocorrelationBlocks), in index order.
template <class Excess>
std::vector<int> in_quietest_neighbourhoods(const std::vector<int>& candidates, Excess excess) {
    std::vector<std::pair<double, int>> by_excess;
    for (int i : candidates) by_excess.push_back({excess(i), i});
    std::sort(by_excess.begin(), by_excess.end());
    const size_t kept = std::max(std::min(by_excess.size(), (size_t)kEarlyAutocorrelationBlocks),
                                 (size_t)std::lround(kQuietNeighbourhoodShare * by_excess.size()));
    std::vector<int> quiet;
    for (size_t j = 0; j < kept; ++j) quiet.push_back(by_excess[j].second);
    std::sort(quiet.begin(), quiet.end());
    return quiet;
}

std::string format_level(double v) {
    std::ostringstream s;
    s.precision(4);
    s << v;
    return s.str();
}

long long count_blocks(const std::vector<ConstImageView>& frames, int size) {
    long long n = 0;
    for (const ConstImageView& f : frames) n += (long long)(f.window.width() / size) * (f.window.height() / size);
    return n;
}

// The block size whose lag grid holds the measured grain's correlation (kBlockPerGrainSize).
int block_size_for_grain(const BlockAnalysis& a) {
    int needed = kSmallestBlockPx;
    for (const ChannelState& s : a.state) {
        const double lag1 = std::max(s.rho[a.lags.index(1, 0)], s.rho[a.lags.index(0, 1)]);
        if (!(lag1 > 0.01)) continue;
        const double size_px = lag1 < 1 ? std::sqrt(-1.0 / (4.0 * std::log(lag1))) : INFINITY;
        const double block = std::min<double>(kLargestBlockPx, kBlockPerGrainSize * size_px);
        needed = std::max(needed, kBlockStepPx * (int)std::ceil(block / kBlockStepPx));
    }
    return needed;
}

// The block size the automatic analysis takes after one at a.block_px: larger while the
// grain needs it and the plate holds enough blocks of it.
int next_block_size(const std::vector<ConstImageView>& frames, const BlockAnalysis& a) {
    const int needed = std::min(block_size_for_grain(a), kLargestBlockPx);
    int size = a.block_px;
    while (size + kBlockStepPx <= needed && count_blocks(frames, size + kBlockStepPx) >= kMinAutoBlockCount)
        size += kBlockStepPx;
    return size;
}

// `automatic`: the block size is the automatic one; a.next_block_px says which size comes next
// (next_block_size), and an analysis it moves on from needs no response.
BlockAnalysis analyse_blocks(const std::vector<ConstImageView>& frames, const GrainAnalysisSettings& settings, int nch,
                             int bs, bool automatic) {
    BlockAnalysis a;
    a.block_px = bs;
    a.channels = nch;
    const int npx = bs * bs, half = bs / 2;
    const LagGrid lags{bs / 4};
    a.lags = lags;
    SurfaceFit surface(bs, lags);
    const LowBand low_band(surface, kLowBandCellsPerSide);

    // Cut every frame into blocks and fit the surface in each; blocks with a non-finite pixel
    // are left out.
    struct Origin {
        size_t frame;
        int x, y;
    };
    std::vector<Origin> origins;
    for (size_t f = 0; f < frames.size(); ++f) {
        const Window& w = frames[f].window;
        for (int y = w.y0; y + bs <= w.y1; y += bs)
            for (int x = w.x0; x + bs <= w.x1; x += bs) origins.push_back({f, x, y});
    }
    std::vector<Block> all(origins.size());
    std::vector<char> finite(origins.size(), 1);
    parallel_for(0, (int)origins.size(), settings.threads, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) {
            const ConstImageView& view = frames[origins[i].frame];
            Block& b = all[i];
            b.residual.resize((size_t)nch * npx);
            for (int c = 0; c < nch; ++c) {
                double* r = &b.residual[(size_t)c * npx];
                float lowest = INFINITY, highest = -INFINITY;
                for (int y = 0; y < bs; ++y)
                    for (int x = 0; x < bs; ++x) {
                        float v = view.at(origins[i].x + x, origins[i].y + y)[c];
                        if (!std::isfinite(v)) finite[i] = 0;
                        r[y * bs + x] = v;
                        lowest = std::min(lowest, v), highest = std::max(highest, v);
                    }
                b.extremes.insert(b.extremes.end(), {lowest, highest});
                double mean = 0;
                for (int p = 0; p < npx; ++p) mean += r[p];
                b.level.push_back(mean / npx);
                surface.subtract_from(r);
                double squares = 0, quadrant[4] = {};
                for (int p = 0; p < npx; ++p) {
                    squares += r[p] * r[p];
                    quadrant[2 * ((p / bs) >= half) + ((p % bs) >= half)] += r[p] * r[p];
                }
                b.squares.push_back(squares);
                double gh2 = 0, gv2 = 0, ghv = 0;
                for (int y = 0; y + 1 < bs; ++y)
                    for (int x = 0; x + 1 < bs; ++x) {
                        const double gh = r[y * bs + x + 1] - r[y * bs + x], gv = r[(y + 1) * bs + x] - r[y * bs + x];
                        gh2 += gh * gh, gv2 += gv * gv, ghv += gh * gv;
                    }
                const double gradient_px = double(bs - 1) * (bs - 1);
                b.gradient.insert(b.gradient.end(), {gh2 / gradient_px, gv2 / gradient_px, ghv / gradient_px});
                b.quadrant_squares.insert(b.quadrant_squares.end(), quadrant, quadrant + 4);
                b.low_band.push_back(low_band.power(r));
                for (const auto& lag : kShapeLags) {
                    const int dx = lag[0], dy = lag[1];
                    double sum = 0;
                    for (int y = std::max(0, -dy); y < std::min(bs, bs - dy); ++y)
                        for (int x = std::max(0, -dx); x < std::min(bs, bs - dx); ++x)
                            sum += r[y * bs + x] * r[(y + dy) * bs + x + dx];
                    b.shape.push_back(squares > 0 ? sum / pair_count(bs, dx, dy) / (squares / npx) : 0.0);
                }
            }
        }
    });
    std::vector<Block>& blocks = a.blocks;
    std::vector<int> index_of(all.size(), -1);  // in blocks, of each of all
    for (size_t i = 0; i < all.size(); ++i)
        if (finite[i]) index_of[i] = (int)blocks.size(), blocks.push_back(std::move(all[i]));
    // The blocks around each (origins run row by row through each frame's grid).
    std::vector<std::vector<int>>& neighbours = a.neighbours;
    neighbours.assign(blocks.size(), {});
    for (size_t i = 0, frame_start = 0; i < origins.size(); ++i) {
        const Window& w = frames[origins[i].frame].window;
        if (i > 0 && origins[i].frame != origins[i - 1].frame) frame_start = i;
        const int columns = w.width() / bs, rows = w.height() / bs;
        const int column = (origins[i].x - w.x0) / bs, row = (origins[i].y - w.y0) / bs;
        if (index_of[i] < 0) continue;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int x = column + dx, y = row + dy;
                if ((dx || dy) && x >= 0 && x < columns && y >= 0 && y < rows) {
                    const int j = index_of[frame_start + (size_t)y * columns + x];
                    if (j >= 0) neighbours[index_of[i]].push_back(j);
                }
            }
    }
    if (blocks.empty()) throw GrainAnalysisError("every block of the plate holds non-finite pixels");
    const int nblocks = (int)blocks.size();
    const int nbins = a.bins = std::max(1, settings.level_bins);

    std::vector<ChannelState>& state = a.state;
    state.resize(nch);
    for (int c = 0; c < nch; ++c) {
        ChannelState& s = state[c];
        s.rho.assign(lags.size(), 0.0);
        s.rho[lags.index(0, 0)] = 1.0;
        // Bins over the blocks' levels without the extreme ones (a hot pixel, a light source),
        // whose blocks join the end bins.
        std::vector<double> levels;
        for (const Block& b : blocks) levels.push_back(b.level[c]);
        const double lo = quantile_of(levels, 0.005), hi = quantile_of(levels, 0.995);
        const double width = (hi - lo) / nbins;
        for (const Block& b : blocks)
            s.bin.push_back(width > 0 ? std::clamp((int)std::floor((b.level[c] - lo) / width), 0, nbins - 1) : 0);
        s.accepted.assign(nblocks, 0);
        s.candidate.assign(nblocks, 0);
        // A block reaching the plate's lowest or highest value may be clipped there: its grain is
        // cut off (none at all where the whole block is), so it is never grain-only. An
        // unclipped plate loses the one or two blocks holding its extreme pixels; a constant
        // channel none (it has no grain, which the profile says).
        float plate_lowest = INFINITY, plate_highest = -INFINITY;
        for (const Block& b : blocks) {
            plate_lowest = std::min(plate_lowest, b.extremes[2 * c]);
            plate_highest = std::max(plate_highest, b.extremes[2 * c + 1]);
        }
        for (const Block& b : blocks)
            s.clipped.push_back(plate_lowest < plate_highest &&
                                (b.extremes[2 * c] <= plate_lowest || b.extremes[2 * c + 1] >= plate_highest));
    }

    // Whether each block's short-range correlation is near the median of the reference
    // blocks (the quietest ones at first, then the accepted ones).
    auto typical_blocks = [&](int c, const std::vector<char>& reference_blocks) {
        std::vector<double> reference(kShapeLagCount);
        for (int l = 0; l < kShapeLagCount; ++l) {
            std::vector<double> values;
            for (int i = 0; i < nblocks; ++i)
                if (reference_blocks[i]) values.push_back(blocks[i].shape[(size_t)c * kShapeLagCount + l]);
            reference[l] = median_of(values);
        }
        std::vector<double> distance(nblocks), reference_distance;
        for (int i = 0; i < nblocks; ++i) {
            double sum = 0;
            for (int l = 0; l < kShapeLagCount; ++l) {
                double d = blocks[i].shape[(size_t)c * kShapeLagCount + l] - reference[l];
                sum += d * d;
            }
            distance[i] = std::sqrt(sum);
            if (reference_blocks[i]) reference_distance.push_back(distance[i]);
        }
        double centre = median_of(reference_distance);
        for (double& d : reference_distance) d = std::abs(d - centre);
        double limit = centre + kShapeOutlierMads * 1.4826 * median_of(reference_distance);
        std::vector<char> typical(nblocks);
        for (int i = 0; i < nblocks; ++i) typical[i] = distance[i] <= limit;
        return typical;
    };

    // Whether each block's four quadrants hold alike grain (kStationarityLimit).
    auto stationary_blocks = [&](int c) {
        const ChannelState& s = state[c];
        // A quadrant's variance estimate: about gamma of shape k; its log has variance
        // trigamma(k) ~ 1/k + 1/(2 k^2).
        const double quadrant_dof = s.dof / 4, relative_sd = std::sqrt(2.0 * sum_rho2(s.rho, lags, half)) / quadrant_dof;
        const double k = 1.0 / (relative_sd * relative_sd), log_variance = 1.0 / k + 0.5 / (k * k);
        std::vector<char> stationary(nblocks);
        for (int i = 0; i < nblocks; ++i) {
            const double* q = &blocks[i].quadrant_squares[(size_t)c * 4];
            double logs[4], mean = 0, dispersion = 0;
            for (int j = 0; j < 4; ++j) mean += (logs[j] = std::log(std::max(q[j], 1e-300))) / 4;
            for (double l : logs) dispersion += (l - mean) * (l - mean);
            stationary[i] = dispersion / log_variance <= kStationarityLimit;
        }
        return stationary;
    };

    // Whether each block's largest gradient-covariance eigenvalue is within what grain of the
    // curve's sigma at its level gives (its 0.99 quantile); every block while no curve.
    auto weak_textured_blocks = [&](int c) {
        const ChannelState& s = state[c];
        std::vector<char> weak(nblocks, 1);
        if (s.curve.level.empty()) return weak;
        auto rho = [&](int dx, int dy) {
            return std::abs(dx) <= lags.radius && std::abs(dy) <= lags.radius ? s.rho[lags.index(dx, dy)] : 0.0;
        };
        // Expected gradient covariance per unit variance: E[gh^2] = 2 (1 - rho(1,0)), and so on.
        const double hh = 2 * (1 - rho(1, 0)), vv = 2 * (1 - rho(0, 1)), hv = 1 - rho(1, 0) - rho(0, 1) + rho(-1, 1);
        const double expected = largest_eigenvalue(hh, hv, vv);
        // Gamma shape of a block's mean squared gradient along x and y: mean^2 / variance, the
        // variance from the gradient's own autocorrelation (second differences of rho).
        const int m = bs - 1;
        double shape = INFINITY;
        for (int axis = 0; axis < 2; ++axis) {
            const int ex = axis == 0, ey = axis == 1;
            const double g0 = 2 * (1 - rho(ex, ey));
            if (!(g0 > 0)) continue;
            double sum = 0;
            for (int dy = -lags.radius; dy <= lags.radius; ++dy)
                for (int dx = -lags.radius; dx <= lags.radius; ++dx) {
                    const double g = (2 * rho(dx, dy) - rho(dx + ex, dy + ey) - rho(dx - ex, dy - ey)) / g0;
                    sum += pair_count(m, dx, dy) * g * g;
                }
            shape = std::min(shape, double(m) * m * m * m / (2 * sum));
        }
        const double quantile = gamma_quantile_over_mean(shape, kWeakTextureZ);
        for (int i = 0; i < nblocks; ++i) {
            const double* g = &blocks[i].gradient[(size_t)c * 3];
            weak[i] = largest_eigenvalue(g[0], g[2], g[1]) <= quantile * expected * s.curve.at(blocks[i].level[c]);
        }
        return weak;
    };

    // Whether each block's low-band power is within what grain of the curve's sigma at its level
    // gives (the 0.99 quantile of a chi-square with LowBand's degrees of freedom); every block
    // while no curve or no autocorrelation (the first pass: grain's low band grows with its
    // correlation, so white grain's would reject correlated grain everywhere).
    auto low_band_blocks = [&](int c, int pass) {
        const ChannelState& s = state[c];
        std::vector<char> smooth(nblocks, 1);
        if (pass == 0 || s.curve.level.empty() || !(s.low_band.dof > 0)) return smooth;
        const double limit = gamma_quantile_over_mean(0.5 * s.low_band.dof, kWeakTextureZ) * s.low_band.mean;
        for (int i = 0; i < nblocks; ++i)
            smooth[i] = blocks[i].low_band[c] <= limit * s.curve.at(blocks[i].level[c]);
        return smooth;
    };

    // The response through the candidates of each bin that has enough of them: the quantile
    // of their variances, or their patches' smallest whitened eigenvalue (PatchSpace).
    auto fit_curve = [&](int c, bool in_patch_space) {
        ChannelState& s = state[c];
        std::vector<std::vector<double>> variance(nbins);
        std::vector<std::vector<int>> members(nbins);
        std::vector<double> level(nbins, 0.0);
        for (int i = 0; i < nblocks; ++i)
            if (s.candidate[i]) {
                variance[s.bin[i]].push_back(blocks[i].squares[c] / s.dof);
                members[s.bin[i]].push_back(i);
                level[s.bin[i]] += blocks[i].level[c];
            }
        const int min_blocks = std::max(1, settings.min_blocks_per_level);
        int most_blocks = 0;
        for (const auto& m : members) most_blocks = std::max(most_blocks, (int)m.size());
        std::unique_ptr<PatchSpace> space;
        std::unique_ptr<PatchCalibration> calibration;
        if (in_patch_space && most_blocks >= min_blocks) {
            space = std::make_unique<PatchSpace>(s.rho, lags, std::min(kPatchSidePx, lags.radius + 1));
            calibration = std::make_unique<PatchCalibration>(*space, surface, s.rho, lags, c, most_blocks, 1);
        }
        LevelCurve curve;
        for (int k = 0; k < nbins; ++k) {
            const int n = (int)variance[k].size();
            if (n < min_blocks) continue;
            curve.level.push_back(level[k] / n);
            if (calibration) {
                PatchMoments moments(space->dim);
                for (int i : members[k]) space->accumulate(&blocks[i].residual[(size_t)c * npx], bs, moments);
                const PatchCalibration::Bias bias = calibration->at(n);
                curve.variance.push_back(space->grain_variance(moments) / bias.mean);
                curve.error.push_back(0.5 * bias.relative_sd);
            } else {
                curve.variance.push_back(quantile_of(variance[k], kResponseQuantile) / grain_quantile(s.relative_sd));
                curve.error.push_back(quantile_sigma_error(s.relative_sd, n));
            }
            curve.bin.push_back(k);
            curve.blocks.push_back(n);
        }
        drop_content_bins(curve);
        drop_levels_above_envelope(curve, settings.encoding);
        if (in_patch_space) smooth_response(curve, settings.encoding);
        return curve;
    };

    auto update_statistics = [&](ChannelState& s) {
        const SurfaceFit::Bias fit_bias = surface.bias(s.rho, lags);
        s.dof = npx - fit_bias.trace;
        s.relative_sd = std::sqrt(fit_bias.squares_variance) / s.dof;
        s.low_band = low_band.expectation(s.rho, lags);
    };

    for (int pass = 0; pass < 3; ++pass) {
        parallel_for(0, nch, settings.threads, [&](int c_begin, int c_end) {
            for (int c = c_begin; c < c_end; ++c) {
                ChannelState& s = state[c];
                update_statistics(s);
                std::vector<char> reference = s.accepted;
                if (pass == 0) {
                    // No grain-only blocks yet to compare shapes with: picture content only adds
                    // variance, so start from the quietest quarter of each bin.
                    std::vector<std::vector<std::pair<double, int>>> per_bin(nbins);
                    for (int i = 0; i < nblocks; ++i)
                        if (!s.clipped[i]) per_bin[s.bin[i]].push_back({blocks[i].squares[c], i});
                    for (auto& bin : per_bin) {
                        std::sort(bin.begin(), bin.end());
                        for (size_t j = 0; j < (bin.size() + 3) / 4; ++j) reference[bin[j].second] = 1;
                    }
                }
                const std::vector<char> typical = typical_blocks(c, reference), stationary = stationary_blocks(c);
                // The curve and the weak-texture selection, each from the other until the curve settles.
                for (int iteration = 0; iteration < kWeakTextureIterations; ++iteration) {
                    const std::vector<char> weak = weak_textured_blocks(c), smooth = low_band_blocks(c, pass);
                    for (int i = 0; i < nblocks; ++i)
                        s.candidate[i] = !s.clipped[i] && typical[i] && stationary[i] && weak[i] && smooth[i];
                    LevelCurve next = fit_curve(c, false);
                    bool settled = next.bin == s.curve.bin;
                    for (size_t k = 0; settled && k < next.variance.size(); ++k)
                        settled = std::abs(next.variance[k] / s.curve.variance[k] - 1) < kWeakTextureSettled;
                    s.curve = std::move(next);
                    if (settled) break;
                }
                for (int i = 0; i < nblocks; ++i) {
                    const double expected = s.curve.at(blocks[i].level[c]), variance = blocks[i].squares[c] / s.dof;
                    s.accepted[i] = s.candidate[i] && expected > 0 &&
                                    std::abs(variance / expected - 1.0) <= kRejectionSigmas * s.relative_sd;
                }
                // Autocorrelation of the accepted blocks (in the last pass those in the quietest
                // neighbourhoods; evenly thinned), each normalised by the curve's variance at
                // its level.
                std::vector<int> chosen;
                for (int i = 0; i < nblocks; ++i)
                    if (s.accepted[i]) chosen.push_back(i);
                if (chosen.empty()) continue;
                if (pass == 2)
                    chosen = in_quietest_neighbourhoods(chosen, [&](int i) { return neighbourhood_excess(a, c, i); });
                const int cap = pass == 2 ? kMaxAutocorrelationBlocks : kEarlyAutocorrelationBlocks;
                int step = std::max<int>(1, (int)(chosen.size() + cap - 1) / cap);
                std::vector<double> measured(lags.size(), 0.0);
                int used = 0;
                for (size_t j = 0; j < chosen.size(); j += step, ++used) {
                    const Block& b = blocks[chosen[j]];
                    const double* r = &b.residual[(size_t)c * npx];
                    std::vector<double> products = autocorrelation(r, bs, lags);
                    double scale = 1.0 / s.curve.at(b.level[c]);
                    for (size_t l = 0; l < lags.size(); ++l) measured[l] += products[l] * scale;
                }
                for (int dy = -lags.radius; dy <= lags.radius; ++dy)
                    for (int dx = -lags.radius; dx <= lags.radius; ++dx)
                        measured[lags.index(dx, dy)] /= used * pair_count(bs, dx, dy);
                // Undo the surface fit: solve rho - bias(rho) = measured (bias is linear in
                // rho). The fit removes most low-frequency power, so plain fixed-point
                // iteration converges slowly; minimal-residual steps converge in a few.
                auto unbiased = [&](const std::vector<double>& x) {
                    std::vector<double> b = surface.bias(x, lags).lag_bias;
                    for (size_t l = 0; l < x.size(); ++l) b[l] = x[l] - b[l];
                    return b;
                };
                std::vector<double> residual = unbiased(s.rho);
                for (size_t l = 0; l < lags.size(); ++l) residual[l] = measured[l] - residual[l];
                const int steps = pass == 2 ? kFinalSolverSteps : kEarlySolverSteps;
                for (int step = 0; step < steps; ++step) {
                    std::vector<double> a_residual = unbiased(residual);
                    double num = 0, den = 0;
                    for (size_t l = 0; l < lags.size(); ++l)
                        num += residual[l] * a_residual[l], den += a_residual[l] * a_residual[l];
                    if (den <= 0) break;
                    const double alpha = num / den;
                    for (size_t l = 0; l < lags.size(); ++l)
                        s.rho[l] += alpha * residual[l], residual[l] -= alpha * a_residual[l];
                }
                const double centre = s.rho[lags.index(0, 0)];
                for (double& v : s.rho) v /= centre;
            }
        });
    }
    a.next_block_px = automatic ? next_block_size(frames, a) : bs;
    if (a.next_block_px != bs) return a;
    // The final autocorrelation sets the fit's degrees of freedom for the final curve, and the
    // whitening of the response.
    parallel_for(0, nch, settings.threads, [&](int c_begin, int c_end) {
        for (int c = c_begin; c < c_end; ++c) {
            update_statistics(state[c]);
            state[c].curve = fit_curve(c, false);
            state[c].response = fit_curve(c, true);
        }
    });
    return a;
}

}  // namespace

GrainProfile analyze_grain(const std::vector<ConstImageView>& frames, const GrainAnalysisSettings& settings) {
    if (frames.empty()) throw GrainAnalysisError("no plate to analyse");
    int nch = settings.channels > 0 ? settings.channels : frames.front().channels;
    for (const ConstImageView& f : frames)
        if (f.channels < nch)
            throw GrainAnalysisError("the frames have different channel counts (" + std::to_string(f.channels) +
                                     " < " + std::to_string(nch) + ")");
    const bool automatic = settings.block_size_px <= 0;
    const int first_size = automatic ? kSmallestBlockPx : settings.block_size_px;
    if (first_size < 8) throw GrainAnalysisError("the block size must be at least 8 pixels");
    if (count_blocks(frames, first_size) < kMinBlockCount) {
        const Window& w = frames.front().window;
        throw GrainAnalysisError("the plate is too small to estimate grain from: " + std::to_string(w.width()) + "x" +
                                 std::to_string(w.height()) + " pixels holds fewer than " +
                                 std::to_string(kMinBlockCount) + " blocks of " + std::to_string(first_size) + "x" +
                                 std::to_string(first_size) + " px");
    }
    BlockAnalysis analysis = analyse_blocks(frames, settings, nch, first_size, automatic);
    // Automatic: larger blocks while the grain needs them and the plate has them.
    while (analysis.next_block_px != analysis.block_px)
        analysis = analyse_blocks(frames, settings, nch, analysis.next_block_px, automatic);
    const int bs = analysis.block_px, npx = bs * bs, nblocks = (int)analysis.blocks.size(), nbins = analysis.bins;
    const std::vector<Block>& blocks = analysis.blocks;
    const std::vector<ChannelState>& state = analysis.state;

    // Results, and what could not be estimated.
    GrainProfile profile;
    profile.colorspace = settings.colorspace;
    profile.encoding = settings.encoding;
    profile.block_size_px = bs;
    std::vector<std::string> failures;
    for (int c = 0; c < nch; ++c) {
        const ChannelState& s = state[c];
        GrainChannel ch;
        ch.name = c < (int)settings.channel_names.size() ? settings.channel_names[c]
                  : c < 3                                ? std::string(1, "RGB"[c])
                                                         : "C" + std::to_string(c);
        std::vector<double> all_level(nbins, 0.0);
        std::vector<int> seen(nbins, 0), candidates(nbins, 0);
        for (int i = 0; i < nblocks; ++i) {
            ++seen[s.bin[i]];
            all_level[s.bin[i]] += blocks[i].level[c];
            candidates[s.bin[i]] += s.candidate[i];
        }
        for (size_t k = 0; k < s.response.level.size(); ++k) {
            ch.level.push_back(s.response.level[k]);
            ch.sigma.push_back(std::sqrt(s.response.variance[k]));
            ch.samples.push_back((long long)s.response.blocks[k] * npx);
            ch.sigma_error.push_back(s.response.error[k]);
            ch.plate_samples.push_back((long long)seen[s.response.bin[k]] * npx);
        }
        // The levels seen but not estimated: too few candidates, or dropped as content.
        std::vector<SparseLevel> sparse;
        for (int k = 0; k < nbins; ++k)
            if (seen[k] > 0 && std::find(s.response.bin.begin(), s.response.bin.end(), k) == s.response.bin.end())
                sparse.push_back(
                    {ch.name, all_level[k] / seen[k], (long long)candidates[k] * npx, (long long)seen[k] * npx});
        // Below this fraction of the signal, what is left is float rounding, not grain.
        double signal = 1.0;
        for (double l : ch.level) signal = std::max(signal, std::abs(l));
        bool no_grain = !ch.sigma.empty() && *std::max_element(ch.sigma.begin(), ch.sigma.end()) <= 1e-6 * signal;
        if (ch.level.empty() || no_grain) {
            std::string seen_levels;
            for (const SparseLevel& l : sparse)
                seen_levels += (seen_levels.empty() ? "" : ", ") + format_level(l.level) + " (" +
                               std::to_string(l.samples / npx) + " grain-only blocks)";
            failures.push_back(no_grain ? "channel " + ch.name + ": no grain (the residual is 0 in every flat block)"
                                        : "channel " + ch.name + ": no level has " +
                                              std::to_string(settings.min_blocks_per_level) + " grain-only blocks of " +
                                              std::to_string(bs) + "x" + std::to_string(bs) + " px; levels seen: " +
                                              seen_levels);
        }
        profile.sparse_levels.insert(profile.sparse_levels.end(), sparse.begin(), sparse.end());
        ch.clipped_samples = (long long)std::count(s.clipped.begin(), s.clipped.end(), 1) * npx;
        ch.acf_radius = analysis.lags.radius;
        ch.autocorrelation = s.rho;
        profile.channels.push_back(std::move(ch));
    }
    if (!failures.empty()) {
        std::string message = "cannot estimate the grain (too small or too little flat area; try more frames or a "
                              "region with flat areas):";
        for (const std::string& f : failures) message += "\n  " + f;
        throw GrainAnalysisError(message);
    }

    // Channel correlation at lag 0, pooled over blocks that are grain-only in every channel, each
    // normalised by the curve they were selected by. Content is common to the channels and
    // would correlate them: of those blocks, the ones in the quieter neighbourhoods
    // (kQuietNeighbourhoodShare; their excess averaged over the channels).
    profile.channel_correlation.assign((size_t)nch * nch, 0.0);
    std::vector<int> grain_only;
    for (int i = 0; i < nblocks; ++i) {
        bool everywhere = true;
        for (int c = 0; c < nch; ++c) everywhere &= state[c].accepted[i] && state[c].curve.at(blocks[i].level[c]) > 0;
        if (everywhere) grain_only.push_back(i);
    }
    profile.blocks_used = (long long)grain_only.size();
    if (grain_only.empty())
        throw GrainAnalysisError("no block is grain-only in every channel: cannot measure the channel correlation");
    const std::vector<int> quiet = in_quietest_neighbourhoods(grain_only, [&](int i) {
        double sum = 0;
        for (int c = 0; c < nch; ++c) sum += neighbourhood_excess(analysis, c, i);
        return sum / nch;
    });
    std::vector<double> numerator((size_t)nch * nch, 0.0), denominator((size_t)nch * nch, 0.0);
    for (int i : quiet) {
        for (int a = 0; a < nch; ++a)
            for (int b = 0; b < nch; ++b) {
                const double* ra = &blocks[i].residual[(size_t)a * npx];
                const double* rb = &blocks[i].residual[(size_t)b * npx];
                double sum = 0;
                for (int p = 0; p < npx; ++p) sum += ra[p] * rb[p];
                numerator[(size_t)a * nch + b] +=
                    sum / std::sqrt(state[a].curve.at(blocks[i].level[a]) * state[b].curve.at(blocks[i].level[b]));
                denominator[(size_t)a * nch + b] += std::sqrt(state[a].dof * state[b].dof);
            }
    }
    for (int a = 0; a < nch; ++a)
        for (int b = 0; b < nch; ++b) {
            double r = a == b ? 1.0 : numerator[(size_t)a * nch + b] / denominator[(size_t)a * nch + b];
            profile.channel_correlation[(size_t)a * nch + b] = std::clamp(r, -1.0, 1.0);
        }
    // Symmetric by construction up to rounding; make it exact for the file format.
    for (int a = 0; a < nch; ++a)
        for (int b = 0; b < a; ++b)
            profile.channel_correlation[(size_t)b * nch + a] = profile.channel_correlation[(size_t)a * nch + b];
    return profile;
}

const char* quality_name(ProfileQuality quality) {
    switch (quality) {
        case ProfileQuality::good: return "good";
        case ProfileQuality::usable: return "usable";
        case ProfileQuality::unreliable: return "unreliable";
    }
    return "unreliable";
}

ProfileAssessment assess_grain_profile(const GrainProfile& profile) {
    struct Grade {
        ProfileQuality quality;
        int min_levels;
        double min_fraction, max_error;
    };
    constexpr Grade kGrades[] = {{ProfileQuality::good, 4, 0.5, 0.10}, {ProfileQuality::usable, 2, 0.25, 0.25}};
    ProfileAssessment out;
    double worst_rank = 0;
    for (const GrainChannel& ch : profile.channels) {
        if (ch.samples.empty()) continue;
        // Each level weighs by the plate's pixels at it (alike in a profile without the counts):
        // levels the plate barely shows say little about whether it is grain or content.
        const bool by_pixels = !ch.plate_samples.empty();
        double shown = 0, within_share[2] = {0, 0};
        int within[2] = {0, 0}, levels = (int)ch.level.size();
        for (const SparseLevel& s : profile.sparse_levels)
            if (s.channel == ch.name) {
                shown += by_pixels ? double(s.plate_samples) : 1.0;
                ++levels;
            }
        for (size_t i = 0; i < ch.level.size(); ++i) {
            const double weight = by_pixels ? double(ch.plate_samples[i]) : 1.0;
            shown += weight;
            for (int g = 0; g < 2; ++g)
                if (ch.sigma_error.empty() || ch.sigma_error[i] <= kGrades[g].max_error) {
                    ++within[g];
                    within_share[g] += weight;
                }
        }
        for (double& share : within_share) share /= shown;
        int grade = 0;
        while (grade < 2 && !(within[grade] >= kGrades[grade].min_levels && within_share[grade] >= kGrades[grade].min_fraction))
            ++grade;
        // The weakest channel by grade, then by the share of the plate it measured well.
        const int shown_grade = std::min(grade, 1);
        const double rank = grade + 1.0 - within_share[shown_grade];
        if (rank <= worst_rank) continue;
        worst_rank = rank;
        out.quality = grade < 2 ? kGrades[grade].quality : ProfileQuality::unreliable;
        out.reason = "channel " + ch.name + ": " + std::to_string(within[shown_grade]) + " of " +
                     std::to_string(levels) + " levels measured within " +
                     std::to_string(int(100 * kGrades[shown_grade].max_error)) + " %" +
                     (by_pixels ? ", holding " + std::to_string(std::lround(100 * within_share[shown_grade])) +
                                      " % of the plate's pixels"
                                : "") +
                     (grade == 0 ? "" : " (the rest holds picture content or too few flat blocks)");
    }
    if (out.reason.empty()) out.reason = "every level measured within 10 %";
    return out;
}

}  // namespace darkroom
