#include "core/stages/grain.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "core/parallel.h"
#include "core/stages/filters.h"

namespace darkroom {

namespace {

double aperture_integral(double s_um, double d_um) {
    // Integrand in u = pi d f: the aperture term [2 J1(u)/u]^2 decays as u^-3, so integrate to
    // u_max and add the tail's mean (4/(pi u^3)) analytically, damped by the grain spectrum.
    // Simpson's rule at 20 nodes per period of J1: within 4e-8 of the integral to u_max
    // (checked at 40 times as many nodes), and with the tail's mean within 5e-7 of the
    // closed form at s = 0 (tested); a tenth of the Bessel functions the trapezoid rule needs.
    constexpr double u_max = 600.0;
    constexpr int steps = 12000;
    // The aperture term at the nodes depends on u alone: computed once per process (a Bessel
    // function takes about a microsecond, and every grain size's integral needs all of them).
    static const std::vector<double> airy = [] {
        std::vector<double> a(steps + 1);
        for (int i = 0; i <= steps; ++i) {
            const double u = u_max * i / steps;
            a[size_t(i)] = u < 1e-8 ? 1.0 : 2.0 * std::cyl_bessel_j(1.0, u) / u;
        }
        return a;
    }();
    auto integrand = [&](int i) {
        double f = u_max * i / steps / (M_PI * d_um);
        return 2.0 * M_PI * f * std::exp(-4.0 * M_PI * M_PI * s_um * s_um * f * f) * airy[size_t(i)] *
               airy[size_t(i)] / (M_PI * d_um);
    };
    double sum = integrand(0) + integrand(steps);
    for (int i = 1; i < steps; ++i) sum += (i % 2 ? 4 : 2) * integrand(i);
    sum *= u_max / steps / 3;
    double f_max = u_max / (M_PI * d_um);
    double tail = 8.0 / (M_PI * M_PI * M_PI * d_um * d_um * d_um * f_max);
    sum += tail * std::exp(-4.0 * M_PI * M_PI * s_um * s_um * f_max * f_max);
    return std::sqrt(sum);
}

// The grain filter along one axis, in pixels. A pixel reads the continuous field (white
// noise of power W0 through the Gaussian of std s) averaged over its width p: per axis
// the window w = box(p) * G(s), whose autocorrelation at whole-pixel lags is
//   a(n) = (triangle * G(sqrt 2 s / p))(n)     (in pixels, a(0) -> 1 as s -> 0).
// The discrete filter k is the zero-phase one with that autocorrelation: its spectrum is
// sqrt(A(f)), A the (non-negative, aliased) spectrum of a(n). So unit white noise per
// pixel through k in x and y has the variance and neighbour correlations of the pixel
// averages; for s of a pixel or more k is close to the pixel-integrated Gaussian.
std::vector<float> pixel_averaged_grain_kernel(double s_px) {
    const double sigma = std::sqrt(2.0) * s_px;
    const int lags = int(std::ceil(6.0 * sigma)) + 2, radius = int(std::ceil(4.0 * s_px)) + 1;
    std::vector<double> a(lags + 1);
    for (int n = 0; n <= lags; ++n) {
        // (triangle * G)(n) = integral over |t| < 1 of (1 - |t|) G(n - t) dt (Simpson).
        const int steps = 400;
        double sum = 0;
        for (int i = 0; i <= steps; ++i) {
            double t = -1.0 + 2.0 * i / steps;
            double g = sigma < 1e-9 ? (std::abs(n - t) < 1e-12 ? 1.0 : 0.0)
                                    : std::exp(-0.5 * (n - t) * (n - t) / (sigma * sigma)) /
                                          (sigma * std::sqrt(2.0 * M_PI));
            double weight = (i == 0 || i == steps) ? 1 : (i % 2 ? 4 : 2);
            sum += weight * (1.0 - std::abs(t)) * g;
        }
        a[n] = sigma < 1e-9 ? (n == 0 ? 1.0 : 0.0) : sum * (2.0 / steps) / 3.0;
    }
    const int frequencies = 1024;
    std::vector<double> root(frequencies + 1);
    for (int i = 0; i <= frequencies; ++i) {
        double f = 0.5 * i / frequencies, spectrum = a[0];
        for (int n = 1; n <= lags; ++n) spectrum += 2.0 * a[n] * std::cos(2.0 * M_PI * f * n);
        root[i] = std::sqrt(std::max(0.0, spectrum));
    }
    std::vector<double> k(2 * radius + 1);
    double total = 0;
    for (int j = 0; j <= radius; ++j) {
        double sum = 0;  // k_j = 2 integral over [0, 1/2] of sqrt(A(f)) cos(2 pi f j) df (trapezoid)
        for (int i = 0; i <= frequencies; ++i)
            sum += (i == 0 || i == frequencies ? 0.5 : 1.0) * root[i] * std::cos(2.0 * M_PI * (0.5 * i / frequencies) * j);
        k[radius + j] = k[radius - j] = 2.0 * sum * (0.5 / frequencies);
    }
    for (double v : k) total += v;
    std::vector<float> taps;
    for (double v : k) taps.push_back(float(v / total));  // unit sum: the 48 um reading is kept
    return taps;
}

// The autocorrelation of a kernel at lags 0 ... its length - 1, over its value at lag 0.
std::vector<double> normalised_autocorrelation(const std::vector<float>& k) {
    std::vector<double> a(k.size(), 0.0);
    for (size_t lag = 0; lag < k.size(); ++lag)
        for (size_t j = 0; j + lag < k.size(); ++j) a[lag] += double(k[j]) * k[j + lag];
    for (size_t lag = k.size(); lag-- > 0;) a[lag] /= a[0];
    return a;
}

// The kernel with its outer pairs of taps dropped (and the rest rescaled to unit sum) while
// the field's correlation at every lag stays within `tolerance` of the full kernel's.
std::vector<float> trimmed_grain_kernel(const std::vector<float>& full, double tolerance) {
    const std::vector<double> target = normalised_autocorrelation(full);
    std::vector<float> kept = full;
    while (kept.size() > 1) {
        std::vector<float> shorter(kept.begin() + 1, kept.end() - 1);
        double sum = 0;
        for (float v : shorter) sum += v;
        for (float& v : shorter) v = float(v / sum);
        const std::vector<double> a = normalised_autocorrelation(shorter);
        double worst = 0;
        for (size_t lag = 0; lag < target.size(); ++lag)
            worst = std::max(worst, std::abs((lag < a.size() ? a[lag] : 0.0) - target[lag]));
        if (worst > tolerance) break;
        kept = std::move(shorter);
    }
    return kept;
}

}  // namespace

// The integral takes tens of milliseconds (Bessel functions on a fine grid) and every plan of
// every frame needs it for the same few grain sizes: computed once per (size, aperture).
double aperture_rms_per_unit_noise(double s_um, double d_um) {
    static std::mutex mutex;
    static std::map<std::pair<double, double>, double> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto key = std::make_pair(s_um, d_um);
    auto it = cache.find(key);
    if (it == cache.end()) it = cache.emplace(key, aperture_integral(s_um, d_um)).first;
    return it->second;
}

bool GrainModel::is_noop() const { return pixel_sigma_at_unit_density() < kNoOpSigma; }

double GrainModel::field_sigma() const {
    double k2 = 0;
    for (float k : kernel) k2 += double(k) * k;
    return k2;
}

double GrainModel::lag1_correlation() const {
    double lagged = 0;
    for (size_t i = 0; i + 1 < kernel.size(); ++i) lagged += double(kernel[i]) * kernel[i + 1];
    const double k2 = field_sigma();
    return k2 > 0 ? lagged / k2 : 0.0;
}

double GrainModel::pixel_sigma_at_unit_density() const { return sigma_per_pixel * field_sigma(); }

GrainModel design_grain(const GrainSpec& spec, double d_min, double pitch_um, NoiseKey key, bool fast) {
    GrainModel g;
    g.fast = fast;
    g.d_min = float(d_min);
    g.density_exponent = spec.density_exponent;
    g.key = key;
    double unit_noise_sigma48 = aperture_rms_per_unit_noise(spec.grain_size_um, kGranularityApertureUm);
    g.sigma_per_pixel = spec.rms_granularity / unit_noise_sigma48 / pitch_um;
    g.kernel = pixel_averaged_grain_kernel(spec.grain_size_um / pitch_um);
    if (fast) g.kernel = trimmed_grain_kernel(g.kernel, kFastGrainCorrelationTolerance);
    g.radius = int(g.kernel.size() / 2);
    return g;
}

GrainNoiseStream::GrainNoiseStream(const std::vector<const GrainModel*>& grains, const Window& w) {
    int r = 0;
    std::vector<SeparableFilter> filters;
    for (const GrainModel* g : grains) {
        filters.push_back(SeparableFilter{{g->kernel}, {1.0f}});
        r = std::max(r, g->radius);
    }
    // White noise at absolute coordinates, from R before the window's first column: noise
    // exists at every coordinate, so the vertical pass reads real rows, never clamped ones.
    const int x0 = w.x0 - r, n = w.width() + 2 * r;
    const bool fast = grains.front()->fast;  // (one plan's grains are all fast or none)
    if (!fast) {
        for (const GrainModel* g : grains)
            if (!g->mixed_noise.empty()) throw std::logic_error("GrainNoiseStream: only hashed noise mixes fields");
        stream_ = std::make_unique<SeparableStream>(w.width(), std::move(filters), w.y0 - r, w.y1 + r, w.y1,
                                                    [grains, x0, n](int y, float* const* noise) {
            for (size_t l = 0; l < grains.size(); ++l)
                for (int i = 0; i < n; ++i) noise[l][i] = standard_normal(grains[l]->key, x0 + i, y);
        });
        return;
    }
    // The fields the grains' noises sum (a grain's own alone where it mixes none), each hashed once.
    std::vector<NoiseKey> fields;
    std::vector<NoiseMix> mixes(grains.size());
    for (size_t l = 0; l < grains.size(); ++l) {
        const std::vector<GrainModel::NoiseTerm> own{{grains[l]->key, 1.0f}};
        for (const GrainModel::NoiseTerm& term : grains[l]->mixed_noise.empty() ? own : grains[l]->mixed_noise) {
            const auto field = std::find(fields.begin(), fields.end(), term.key);
            NoiseMix& mix = mixes[l];
            if (mix.terms == kMaxNoiseFields || (field == fields.end() && fields.size() == kMaxNoiseFields))
                throw std::logic_error("GrainNoiseStream: more noise fields than kMaxNoiseFields");
            mix.field[mix.terms] = int(field - fields.begin());
            mix.weight[mix.terms++] = term.weight;
            if (field == fields.end()) fields.push_back(term.key);
        }
    }
    stream_ = std::make_unique<SeparableStream>(w.width(), std::move(filters), w.y0 - r, w.y1 + r, w.y1,
                                                [fields, mixes, x0, n](int y, float* const* noise) {
        uint32_t row_hashes[kMaxNoiseFields];
        for (size_t f = 0; f < fields.size(); ++f) row_hashes[f] = hashed_noise_row(fields[f], y);
        mixed_hashed_noise_run(row_hashes, int(fields.size()), mixes.data(), int(mixes.size()), x0, n, noise);
    });
}

namespace {

// The grain's filtered noise on `w`, one row at a time to sink(y, field row), by bands of rows.
void filter_grain_noise(const GrainModel& g, const Window& w, int threads, const RowSink& sink) {
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        GrainNoiseStream stream({&g}, w);
        for (int y = y_begin; y < y_end; ++y) sink(y, stream.row(y)[0]);
    });
}

}  // namespace

Plane grain_field(const GrainModel& g, const Window& w, int threads) {
    Plane field(w);
    filter_grain_noise(g, w, threads, [&](int y, const float* n) { std::copy_n(n, w.width(), field.row(y)); });
    return field;
}

double GrainModel::amplitude_at(double density) const {
    return sigma_per_pixel * std::pow(std::max(0.0, density - d_min), density_exponent);
}

double grain_sigma_at(const GrainModel& g, double density) {
    double net = std::max(0.0, density - g.d_min);
    return g.pixel_sigma_at_unit_density() * std::pow(net, g.density_exponent);
}

// Held at d_min: a Gaussian fluctuation wider than the net density would otherwise take
// away more silver (or dye) than developed, giving densities below base+fog or below 0
// (transmitting or reflecting more than falls on it).
void apply_grain(Plane& density, const GrainModel& g, int threads) {
    filter_grain_noise(g, density.window, threads, [&](int y, const float* n) {
        float* d = density.row(y);
        for (int x = 0; x < density.window.width(); ++x)
            d[x] = float(std::max(double(g.d_min), d[x] + g.amplitude_at(d[x]) * n[x]));
    });
}

void develop_row_with_grain(const LogAxisTable& develop, const GrainModel& g, const float* noise, int width,
                            const float* exposure, float* density) {
    develop.apply_row_with_noise(exposure, noise, g.d_min, density, width);
}

void develop_with_grain(Plane& plane, const LogAxisTable& develop, const GrainModel& g, int threads) {
    filter_grain_noise(g, plane.window, threads, [&](int y, const float* n) {
        float* row = plane.row(y);
        develop_row_with_grain(develop, g, n, plane.window.width(), row, row);
    });
}

}  // namespace darkroom
