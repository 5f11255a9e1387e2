#include "core/stages/scatter.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

#include "core/fft.h"
#include "core/parallel.h"
#include "core/stages/filters.h"

namespace darkroom {

namespace {

// The MTF with the slope of its continuation past the last sample computed once: the
// kernel's design evaluates it millions of times.
class MtfResponse {
public:
    explicit MtfResponse(const Curve& mtf) : mtf_(mtf) {
        const size_t n = mtf.x.size();
        if (n < 2) return;
        const double r0 = mtf.y[n - 2], r1 = mtf.y[n - 1];
        if (r0 > r1 && r0 > 0 && r1 > 0) log_slope_ = (std::log(r1) - std::log(r0)) / (mtf.x[n - 1] - mtf.x[n - 2]);
    }
    double operator()(double f) const {
        const size_t n = mtf_.x.size();
        if (f <= mtf_.x_max() || n < 2) return std::max(0.0, mtf_(f));
        const double r1 = mtf_.y[n - 1];
        if (!(r1 > 0)) return 0.0;
        return r1 * std::exp(log_slope_ * (f - mtf_.x[n - 1]));
    }

private:
    const Curve& mtf_;
    double log_slope_ = 0;  // never rising
};

}  // namespace

double mtf_response(const Curve& mtf, double f) { return MtfResponse(mtf)(f); }

double mtf_deviation_to_nyquist(const Curve& mtf, double pixel_pitch_um) {
    double nyquist = 1000.0 / (2.0 * pixel_pitch_um);
    const MtfResponse response(mtf);
    double f_end = nyquist * std::sqrt(2.0), worst = 0;
    for (int i = 0; i <= 512; ++i) worst = std::max(worst, std::abs(response(f_end * i / 512) - 1.0));
    return worst;
}

// Kernel on an N x N periodic grid: h[m][n] = 1/N^2 sum_k sum_l H(f_kl) cos(2pi(km+ln)/N),
// evaluated as two passes of 1D cosine sums (the grid is symmetric). H is the MTF
// periodised over the sampling frequency, H(f) = sum_j MTF(f + j/pitch), so h is the
// continuous PSF sampled at pixel centres: compact even where the MTF is still high at
// Nyquist, where a band-limited design would ring across the whole grid.
// Each value is summed by one thread in one order, so the kernel is the same on any number.
static std::vector<double> periodic_kernel(const Curve& mtf, double pitch_mm, int N, int threads) {
    const MtfResponse response_at(mtf);
    const double sampling = 1.0 / pitch_mm;  // cycles/mm
    int alias_orders = 0;                      // replicas beyond which the MTF is negligible
    while (alias_orders < 32 && response_at((alias_orders + 0.5) * sampling) > 1e-5) ++alias_orders;
    // H at frequency index (k, l) is even in each (the replicas are symmetric) and symmetric
    // in the two (the MTF is radial): summed for 0 <= l <= k <= N/2. The kernel then has the
    // same symmetries: its part 0 <= n <= m <= N/2 is summed, then mirrored and transposed, so
    // that its taps are symmetric exactly; the sums read H's rows k <= N/2 only (the others
    // are their mirror images), kept in `response`, and `partial` holds k, n <= N/2.
    const int half = N / 2, up_to_half = half + 1;  // (up_to_half: the indices 0 ... N/2)
    auto mirrored = [N](int i) { return std::min(i, N - i); };
    std::vector<double> response(size_t(up_to_half) * N), cosines(size_t(N) * N),
        partial(size_t(up_to_half) * up_to_half, 0.0), h(size_t(N) * N, 0.0);
    // One axis's frequency at index k in each replica j: axis[k * replicas + j].
    const int replicas = 2 * alias_orders + 1;
    std::vector<double> axis(size_t(up_to_half) * replicas);
    for (int k = 0; k <= half; ++k)
        for (int j = 0; j < replicas; ++j) axis[k * replicas + j] = double(k) / (N * pitch_mm) + (j - alias_orders) * sampling;
    // (k, l) pairs shared out evenly (rows of the triangle differ in length); each writes
    // its own places: row k at columns l and N - l, row l at columns k and N - k.
    std::vector<std::pair<int, int>> pairs;
    for (int k = 0; k <= half; ++k)
        for (int l = 0; l <= k; ++l) pairs.emplace_back(k, l);
    parallel_for(0, int(pairs.size()), threads, [&](int begin, int end) {
        for (int p = begin; p < end; ++p) {
            const auto [k, l] = pairs[size_t(p)];
            double sum = 0;
            for (int jx = 0; jx < replicas; ++jx)
                for (int jy = 0; jy < replicas; ++jy) {
                    const double fx = axis[k * replicas + jx], fy = axis[l * replicas + jy];
                    sum += response_at(std::sqrt(fx * fx + fy * fy));
                }
            for (int ll : {l, (N - l) % N}) response[k * N + ll] = sum;
            for (int kk : {k, (N - k) % N}) response[l * N + kk] = sum;
        }
    });
    for (int k = 0; k < N; ++k)
        for (int m = 0; m < N; ++m) cosines[k * N + m] = std::cos(2.0 * M_PI * double((long long)k * m % N) / N);
    parallel_for(0, up_to_half, threads, [&](int begin, int end) {
        for (int k = begin; k < end; ++k)
            for (int l = 0; l < N; ++l)
                for (int n = 0; n <= half; ++n) partial[k * up_to_half + n] += response[k * N + l] * cosines[l * N + n];
    });
    parallel_for(0, up_to_half, threads, [&](int begin, int end) {
        for (int m = begin; m < end; ++m)
            for (int k = 0; k < N; ++k)
                for (int n = 0; n <= m; ++n) h[m * N + n] += cosines[k * N + m] * partial[mirrored(k) * up_to_half + n];
    });
    for (int m = 0; m <= half; ++m)
        for (int n = 0; n <= m; ++n) h[m * N + n] /= double(N) * N;
    for (int m = 0; m < N; ++m)
        for (int n = 0; n < N; ++n) {
            const int a = std::max(mirrored(m), mirrored(n)), b = std::min(mirrored(m), mirrored(n));
            if (a != m || b != n) h[m * N + n] = h[a * N + b];
        }
    return h;
}

// The kernel keeps all but this fraction of its absolute weight; the design grid stops
// growing at kMaxGrid (a 127 px radius), where an MTF still high at Nyquist rings.
constexpr double kTailWeight = 1e-3;
constexpr int kMaxGrid = 256;

namespace {

// The gain of separable terms: each term's sum squared, signed.
double terms_gain(const std::vector<std::vector<float>>& terms, const std::vector<float>& signs) {
    double gain = 0;
    for (size_t k = 0; k < terms.size(); ++k) {
        double sum = 0;
        for (float v : terms[k]) sum += v;
        gain += signs[k] * sum * sum;
    }
    return gain;
}

// Scales the separable terms so that with the centre they sum to exactly 1, as the taps do:
// the terms left out would otherwise change the image's mean (by up to the tolerance per tap).
void unit_gain(ScatterKernel& kernel) {
    const float scale = float(std::sqrt((1.0 - kernel.centre) / terms_gain(kernel.separable, kernel.separable_sign)));
    for (auto& term : kernel.separable)
        for (float& v : term) v *= scale;
}

// A kernel matrix's eigen-decomposition as separable terms, largest |eigenvalue| first (the
// best approximation of each rank), until the residual is within `tolerance` everywhere or
// there are `max_terms` terms; not found where the tolerance needs so many terms that the
// direct sum is cheaper (2 passes of 2r+1 taps per term against (2r+1)^2).
// The PSF is even in x and in y, so every eigenvector with a non-zero eigenvalue is even:
// the decomposition runs on the r + 1 components from the centre out, in the coordinates
// w_0 = u_0, w_b = sqrt(2) u_b (where the full vector's norm is |w|), whose matrix
// S_ab = d_a d_b K(a, b) is symmetric (d_0 = 1, d_b = sqrt(2)); K is the kernel's even part.
struct SeparableFit {
    bool found = false;
    std::vector<std::vector<float>> terms;
    std::vector<float> signs;
    double worst = 0;  // the largest |residual tap|
};

SeparableFit fit_separable(const std::vector<double>& taps, int r, double tolerance, int max_terms) {
    const int side = 2 * r + 1, n = r + 1;
    auto tap = [&](int x, int y) { return taps[size_t(y + r) * side + (x + r)]; };
    auto d = [](int b) { return b ? M_SQRT2 : 1.0; };  // component b's scale, d_b above
    std::vector<double> s(size_t(n) * n);
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const double even = (tap(a, b) + tap(-a, b) + tap(a, -b) + tap(-a, -b) + tap(b, a) + tap(-b, a) + tap(b, -a) +
                                 tap(-b, -a)) / 8;
            s[size_t(a) * n + b] = d(a) * d(b) * even;
        }
    std::vector<double> values, vectors;
    symmetric_eigen(s, n, values, vectors);
    std::vector<int> order(n);
    for (int k = 0; k < n; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](int i, int j) { return std::abs(values[i]) > std::abs(values[j]); });

    SeparableFit fit;
    std::vector<double> residual = taps;
    const int cheaper_terms = r;  // k terms cost less than the direct sum: 2 (2r+1) k < (2r+1)^2
    for (int term = 0; term <= cheaper_terms; ++term) {
        fit.worst = 0;
        for (double v : residual) fit.worst = std::max(fit.worst, std::abs(v));
        if (fit.worst <= tolerance || (max_terms > 0 && term == max_terms)) {
            fit.found = true;
            return fit;
        }
        if (term == cheaper_terms) break;
        const int k = order[term];
        const double scale = std::sqrt(std::abs(values[k]));
        std::vector<float> scaled(side);
        for (int b = 0; b < n; ++b)
            scaled[r + b] = scaled[r - b] = float(vectors[size_t(b) * n + k] / d(b) * scale);
        const float sign = values[k] < 0 ? -1.0f : 1.0f;
        // Deflate with the float term, so the residual measures what the convolution uses.
        for (int i = 0; i < side; ++i)
            for (int j = 0; j < side; ++j) residual[size_t(i) * side + j] -= double(sign) * scaled[i] * scaled[j];
        fit.terms.push_back(scaled);
        fit.signs.push_back(sign);
    }
    return SeparableFit{};
}

// The centre weights tried for a delta split off the centre tap: this many steps of it.
constexpr int kCentreSteps = 200;

// The kernel's separable form (design.separable_tolerance, max_terms, centre_term), with
// unit gain; none where the direct sum is cheaper.
void make_separable(ScatterKernel& kernel, const ScatterDesign& design) {
    const int r = kernel.radius;
    const std::vector<double> taps(kernel.taps.begin(), kernel.taps.end());
    double largest = 0;
    for (double v : taps) largest = std::max(largest, std::abs(v));
    const double tolerance = design.separable_tolerance * largest;
    SeparableFit best = fit_separable(taps, r, tolerance, design.max_terms);
    double best_centre = 0;
    const size_t centre_index = size_t(r) * (2 * r + 1) + r;
    for (int step = 1; design.centre_term && step <= kCentreSteps; ++step) {
        const double centre = taps[centre_index] * step / kCentreSteps;
        std::vector<double> rest = taps;
        rest[centre_index] -= centre;
        SeparableFit fit = fit_separable(rest, r, tolerance, design.max_terms);
        // At least one term: a delta alone within the tolerance per tap can still leave out
        // the MTF's few percent at Nyquist, which the no-op test (mtf_deviation_to_nyquist)
        // is the measure of. (And terms that could not take the rest of the gain, 1 -
        // centre, would be no kernel.)
        if (!fit.found || fit.terms.empty() || !((1.0 - centre) / terms_gain(fit.terms, fit.signs) > 0)) continue;
        if (!best.found || fit.terms.size() < best.terms.size() ||
            (fit.terms.size() == best.terms.size() && fit.worst < best.worst))
            best = std::move(fit), best_centre = centre;
    }
    if (!best.found) return;
    kernel.separable = std::move(best.terms);
    kernel.separable_sign = std::move(best.signs);
    kernel.centre = float(best_centre);
    unit_gain(kernel);
}

// Tapers the kernel to zero at max_radius (a raised cosine from half of it) and
// renormalises it to unit sum. The taper is zero on the whole ring at max_radius (each of
// its taps is at least max_radius from the centre), so the tapered kernel's taps reach
// max_radius - 1: its radius, the ring of zeros not kept (a pair of zero taps in each pass
// of each term would cost two loads and a multiply-add a pixel and add nothing).
void taper(ScatterKernel& kernel, int max_radius) {
    const int r = kernel.radius, side = 2 * r + 1, r_new = max_radius - 1, side_new = 2 * r_new + 1;
    std::vector<float> taps(side_new * side_new);
    double sum = 0;
    for (int y = -r_new; y <= r_new; ++y)
        for (int x = -r_new; x <= r_new; ++x) {
            double rho = std::hypot(x, y) / max_radius, weight = 1.0;
            if (rho >= 1.0)
                weight = 0.0;
            else if (rho > 0.5)
                weight = 0.5 * (1.0 + std::cos(M_PI * (rho - 0.5) / 0.5));
            double v = weight * kernel.taps[(y + r) * side + (x + r)];
            taps[(y + r_new) * side_new + (x + r_new)] = float(v);
            sum += v;
        }
    for (float& v : taps) v = float(v / sum);
    kernel.taps = std::move(taps);
    kernel.radius = r_new;
}

}  // namespace

namespace {

ScatterKernel design_uncached(const Curve& mtf, double pixel_pitch_um, const ScatterDesign& design, int threads) {
    if (!(mtf_response(mtf, 0.0) > 0))
        throw std::invalid_argument("the MTF's response at 0 cycles/mm must be positive (it is normalised to 1 there)");
    ScatterKernel kernel;
    if (mtf_deviation_to_nyquist(mtf, pixel_pitch_um) < kMtfNoOpTolerance) {
        kernel.taps = {1.0f};
        return kernel;
    }
    double pitch_mm = pixel_pitch_um / 1000.0;
    for (int N = 32;; N *= 2) {
        std::vector<double> h = periodic_kernel(mtf, pitch_mm, N, threads);
        auto tap = [&](int x, int y) { return h[((y + N) % N) * N + (x + N) % N]; };
        // Weight outside each radius r, from the outermost ring inwards.
        double total = 0;
        for (double v : h) total += std::abs(v);
        std::vector<double> ring(N / 2 + 1, 0.0);
        for (int y = -N / 2 + 1; y < N / 2; ++y)
            for (int x = -N / 2 + 1; x < N / 2; ++x) ring[std::max(std::abs(x), std::abs(y))] += std::abs(tap(x, y));
        int radius = N / 2 - 1;
        for (double outside = 0; radius > 0 && outside + ring[radius] < kTailWeight * total; --radius) outside += ring[radius];
        if (radius >= N / 4 && N < kMaxGrid) continue;  // the PSF wraps around this grid: use a larger one
        kernel.radius = radius;
        int side = 2 * radius + 1;
        kernel.taps.resize(side * side);
        double sum = 0;
        for (int y = -radius; y <= radius; ++y)
            for (int x = -radius; x <= radius; ++x) sum += tap(x, y);
        for (int y = -radius; y <= radius; ++y)
            for (int x = -radius; x <= radius; ++x)
                kernel.taps[(y + radius) * side + (x + radius)] = float(tap(x, y) / sum);
        if (design.max_radius_px > 0 && radius > design.max_radius_px) taper(kernel, design.max_radius_px);
        if (design.separable_tolerance > 0) make_separable(kernel, design);
        return kernel;
    }
}

}  // namespace

// A design takes up to seconds (the DFT grid and the eigen-terms) and every frame of a
// sequence asks for the same few: each is computed once per process.
ScatterKernel design_scatter_kernel(const Curve& mtf, double pixel_pitch_um, const ScatterDesign& design,
                                    int threads) {
    using Key = std::tuple<std::vector<double>, std::vector<double>, double, int, double, int, bool>;
    static std::mutex mutex;
    static std::map<Key, ScatterKernel> cache;
    Key key{mtf.x, mtf.y, pixel_pitch_um, design.max_radius_px, design.separable_tolerance, design.max_terms,
            design.centre_term};
    {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = cache.find(key);
        if (it != cache.end()) return it->second;
    }
    ScatterKernel kernel = design_uncached(mtf, pixel_pitch_um, design, threads);
    std::lock_guard<std::mutex> lock(mutex);
    // A long session (a plugin across many pitches and stocks) must not grow it without bound.
    if (cache.size() >= kMaxCachedKernels) cache.clear();
    return cache.emplace(key, std::move(kernel)).first->second;
}

std::vector<double> ScatterKernel::applied_taps() const {
    if (separable.empty()) return std::vector<double>(taps.begin(), taps.end());
    const int side = 2 * radius + 1;
    std::vector<double> applied(size_t(side) * side, 0.0);
    for (size_t k = 0; k < separable.size(); ++k)
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x)
                applied[size_t(y) * side + x] += double(separable_sign[k]) * separable[k][y] * separable[k][x];
    applied[size_t(radius) * side + radius] += centre;
    return applied;
}

void scatter_direct(const Plane& src, Plane& dst, const ScatterKernel& kernel, const Window& frame, int threads,
                    const Window& region) {
    const int r = kernel.radius, side = 2 * r + 1;
    const Window& w = region.empty() ? dst.window : region;
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            float* out = dst.row(y);
            for (int x = w.x0; x < w.x1; ++x) {
                double acc = 0;
                for (int dy = -r; dy <= r; ++dy) {
                    const float* in = src.row(std::clamp(y + dy, frame.y0, frame.y1 - 1));
                    const float* k = &kernel.taps[(dy + r) * side + r];
                    for (int dx = -r; dx <= r; ++dx)
                        acc += double(k[dx]) * in[std::clamp(x + dx, frame.x0, frame.x1 - 1) - src.window.x0];
                }
                out[x - dst.window.x0] = float(acc);
            }
        }
    });
}

namespace {

// The FFT's side for a kernel: at least two kernel widths, so that a tile's outputs are at
// least a quarter of its grid. A window computes its tiles whole, and under a print the
// film's stages (its silver grain) over the paper's tiles: smaller grids keep a small
// window's cost down, where four widths would make the whole frame's FFT cheaper (a 4K
// frame's radius-114 scatter: 1.4x).
int fft_side(int radius) {
    int n = 64;
    while (n < 2 * (2 * radius + 1)) n *= 2;
    return n;
}

// The FFT's tiles: squares of side n - 2r on a grid of absolute coordinates.
int fft_tile(int radius) { return fft_side(radius) - 2 * radius; }

}  // namespace

Window scatter_input_window(const ScatterKernel& kernel, const Window& out, const Window& frame) {
    const int r = kernel.radius;
    if (!kernel.separable.empty() || r < kMinFftRadius || out.empty()) return out.grown(r).intersected(frame);
    const int tile = fft_tile(r);
    const Window tiles{floor_div(out.x0, tile) * tile, floor_div(out.y0, tile) * tile,
                       (floor_div(out.x1 - 1, tile) + 1) * tile, (floor_div(out.y1 - 1, tile) + 1) * tile};
    return tiles.grown(r).intersected(frame);
}

namespace {

// The direct sum by FFT: the plane in square tiles of side n - 2r on a grid of absolute
// coordinates, each with the r pixels around it on an n x n grid, multiplied there by the
// kernel's spectrum. The r pixels around a tile's outputs cover every tap, so the circular
// convolution wraps nothing into them: each output is the direct sum's up to the FFT's
// rounding, about log2(n) roundings of the largest value in its tile's grid. Every output
// depends on the whole grid through that rounding, so the grid is always read whole
// (scatter_input_window: src covers it in every window), with the frame's clamped edges:
// a tile's outputs are the same bits in any window. A grid with a value that is not finite
// (which the FFT would spread over the whole tile) is summed directly.
void scatter_by_fft(const Plane& src, Plane& dst, const ScatterKernel& kernel, const Window& frame, int threads) {
    const int r = kernel.radius, side = 2 * r + 1, n = fft_side(r), tile = fft_tile(r);
    if (!src.window.contains(scatter_input_window(kernel, dst.window, frame)))
        throw std::invalid_argument("scatter: the source plane does not cover the FFT tiles of the window");
    const Fft fft(n);
    // out(p) = sum over d of k(d) in(p + d): a convolution with k(-d), at (-d) mod n, scaled
    // by the inverse transform's 1/n^2.
    std::vector<std::complex<double>> spectrum(size_t(n) * n), grid(size_t(n) * n);
    for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
            spectrum[size_t((n - dy) % n) * n + (n - dx) % n] = double(kernel.taps[size_t(dy + r) * side + (dx + r)]) / (double(n) * n);
    fft_2d(fft, spectrum, false, threads);
    const Window& w = dst.window;
    for (int ty = floor_div(w.y0, tile); ty * tile < w.y1; ++ty)
        for (int tx = floor_div(w.x0, tile); tx * tile < w.x1; ++tx) {
            const Window outputs = Window{tx * tile, ty * tile, (tx + 1) * tile, (ty + 1) * tile}.intersected(w);
            const int gx0 = tx * tile - r, gy0 = ty * tile - r;  // the grid's first pixel
            bool finite = true;
            for (int j = 0; j < n; ++j) {
                const float* in = src.row(std::clamp(gy0 + j, frame.y0, frame.y1 - 1));
                for (int i = 0; i < n; ++i) {
                    const float v = in[std::clamp(gx0 + i, frame.x0, frame.x1 - 1) - src.window.x0];
                    finite = finite && std::isfinite(v);
                    grid[size_t(j) * n + i] = v;
                }
            }
            if (!finite) {
                scatter_direct(src, dst, kernel, frame, threads, outputs);
                continue;
            }
            fft_2d(fft, grid, false, threads);
            for (size_t i = 0; i < grid.size(); ++i) {
                const std::complex<double> a = grid[i], b = spectrum[i];
                grid[i] = {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
            }
            fft_2d(fft, grid, true, threads);
            for (int y = outputs.y0; y < outputs.y1; ++y) {
                float* out = dst.row(y);
                for (int x = outputs.x0; x < outputs.x1; ++x)
                    out[x - w.x0] = float(grid[size_t(y - gy0) * n + (x - gx0)].real());
            }
        }
}

}  // namespace

void scatter(const Plane& src, Plane& dst, const ScatterKernel& kernel, const Window& frame, int threads) {
    if (!kernel.separable.empty()) {
        convolve_separable(src, dst, kernel.separable_filter(), frame, threads);
        return;
    }
    if (kernel.radius >= kMinFftRadius)
        scatter_by_fft(src, dst, kernel, frame, threads);
    else
        scatter_direct(src, dst, kernel, frame, threads);
}

}  // namespace darkroom
