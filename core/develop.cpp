#include "core/develop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include <glm/glm.hpp>

#include "core/develop_rows.h"
#include "core/parallel.h"
#include "core/stages/filters.h"
#include "core/spectral.h"

namespace darkroom {

namespace {

// How far past a stock's curve the fast tiers' print tables reach (grain's excursions).
constexpr double kTableDensityMargin = 0.3;
constexpr double kLn10 = 2.302585092994046;

// Adds the time from construction to destruction to a stage (when timing).
class StageTimer {
public:
    StageTimer(StageTimes* times, const char* stage) : times_(times), stage_(stage) {}
    ~StageTimer() { stop(); }
    void stop() {
        if (times_) times_->add(stage_, std::chrono::duration<double>(Clock::now() - start_).count());
        times_ = nullptr;
    }

private:
    using Clock = std::chrono::steady_clock;
    StageTimes* times_;
    const char* stage_;
    Clock::time_point start_ = Clock::now();
};

std::string fmt(double v, int precision = 4) {
    std::ostringstream s;
    s.precision(precision);
    s << v;
    return s.str();
}

// The stock's grain for a layer with the user's per-channel overrides (channel = layer).
GrainSpec layer_grain(const GrainSpec& stock, const DevelopSettings& s, size_t channel) {
    GrainSpec g = stock;
    g.rms_granularity *= s.grain_amount[channel];
    g.grain_size_um *= s.grain_size[channel];
    if (std::isfinite(s.grain_density_exponent[channel])) g.density_exponent = s.grain_density_exponent[channel];
    return g;
}

// The finest pixel pitch a plan is made for: below the wavelength of light a film's MTF,
// grain and halation describe nothing a pixel could show, and their kernels' radii in pixels
// (halation's hundreds of um) grow past what memory holds.
constexpr double kMinPixelPitchUm = 0.1;

MaterialStages build_stages(const Stock& stock, double width_mm, int frame_width_px, const DevelopSettings& s,
                            uint32_t stream_base, const char* role, std::vector<std::string>& skipped, int threads) {
    const QualityTier& tier = quality_tier(s.quality);
    MaterialStages m;
    m.stock = stock;
    m.pixel_pitch_um = width_mm * 1000.0 / frame_width_px;
    if (!(m.pixel_pitch_um >= kMinPixelPitchUm)) {
        const char* width = std::string(role) == "film" ? "frame" : "print";  // (the settings' names)
        throw std::invalid_argument(std::string("the ") + role + "'s pixel pitch, " + fmt(m.pixel_pitch_um) + " um (" +
                                    fmt(width_mm) + " mm across " + std::to_string(frame_width_px) + " px), is below " +
                                    fmt(kMinPixelPitchUm) + " um: give a " + width + " width of at least " +
                                    fmt(kMinPixelPitchUm * frame_width_px / 1000.0) + " mm");
    }
    const std::string pitch = " at " + fmt(m.pixel_pitch_um) + " um pitch";
    for (size_t i = 0; i < stock.layers.size(); ++i) {
        const Layer& layer = stock.layers[i];
        std::string where = std::string(role) + " layer " + layer.name;
        m.rgb_weights.push_back(rgb_exposure_weights(layer.sensitivity, stock.exposure_illuminant));

        HalationKernel halation = design_halation(layer.halation.strength * s.halation, layer.halation.radius_um,
                                                  m.pixel_pitch_um, tier.halation_decimation);
        m.halation.push_back(std::nullopt);
        if (!halation.is_noop() || !s.skip_noop_stages)
            m.halation.back() = halation;
        else if (layer.halation.strength > 0)
            skipped.push_back("halation (" + where + "): " + (s.halation == 0 ? "turned off" : "below 1e-5"));

        if (!s.mtf) {
            m.scatter.push_back(ScatterKernel{0, {1.0f}, {}, {}});
            skipped.push_back("scatter (" + where + "): MTF turned off");
        } else {
            double deviation = mtf_deviation_to_nyquist(layer.mtf, m.pixel_pitch_um);
            ScatterKernel kernel = design_scatter_kernel(layer.mtf, m.pixel_pitch_um, tier.scatter, threads);
            m.scatter.push_back(kernel);
            if (deviation < kMtfNoOpTolerance)
                skipped.push_back("scatter (" + where + "): MTF within " + fmt(deviation, 2) + " of 1 up to Nyquist" +
                                  pitch);
            else if (kernel.is_identity())
                skipped.push_back("scatter (" + where + "): the point spread function is within one pixel" + pitch);
        }

        m.grain.push_back(std::nullopt);
        m.boolean_grain.push_back(std::nullopt);
        GrainSpec spec = layer_grain(layer.grain, s, i);
        if (!s.grain) spec.rms_granularity = 0;
        const NoiseKey key{s.seed, s.frame, stream_base + uint32_t(i)};
        // (The texture output takes its exposure fluctuation from the filtered-noise field.)
        if (tier.grain == GrainMethod::boolean_model && s.output != OutputMode::texture) {
            BooleanGrain boolean = design_boolean_grain(spec, layer.density_curve.y_min(), m.pixel_pitch_um, key);
            if (!boolean.is_noop() || !s.skip_noop_stages) {
                m.boolean_grain.back() = boolean;
                continue;
            }
        }
        GrainModel g = design_grain(spec, layer.density_curve.y_min(), m.pixel_pitch_um, key,
                                    tier.grain == GrainMethod::hashed_noise);
        if (!s.skip_noop_stages)
            m.grain.back() = g;
        else if (!s.grain)
            skipped.push_back("grain (" + where + "): grain turned off");
        else if (g.is_noop())
            skipped.push_back("grain (" + where + "): " + fmt(g.pixel_sigma_at_unit_density(), 2) +
                              " D per pixel is below " + fmt(GrainModel::kNoOpSigma, 2) + pitch);
        else
            m.grain.back() = g;
    }
    // The tabulated curves; with grain, each also gives the grain's amplitude at its density
    // from the same lookup (develop and grain then run as one pass over the rows).
    if (tier.curve_table_bits > 0)
        for (size_t i = 0; i < stock.layers.size(); ++i) {
            LogAxisTable::Function amplitude;
            if (const auto& g = m.grain[i]) amplitude = [g](double density) { return g->amplitude_at(density); };
            m.curve_tables.emplace_back(stock.layers[i].density_curve, tier.curve_table_bits, amplitude);
        }
    return m;
}

// Halation then scatter of one layer's exposure (on its window) into `out`.
Plane spread_exposure(const MaterialStages& m, size_t layer, Plane exposure, const Window& out, const Window& frame,
                      int threads, StageTimes* times) {
    if (m.halation[layer]) {
        StageTimer timer(times, "halation");
        Plane halated = Plane::unset(out.grown(m.scatter[layer].radius).intersected(frame));
        apply_halation(exposure, halated, *m.halation[layer], frame, threads);
        exposure = std::move(halated);
    }
    if (!m.scatter[layer].is_identity()) {
        StageTimer timer(times, "scatter");
        Plane spread = Plane::unset(out);
        scatter(exposure, spread, m.scatter[layer], frame, threads);
        return spread;
    }
    if (exposure.window == out) return exposure;
    Plane cropped = Plane::unset(out);  // another layer's halo made the exposure larger than this one needs
    for (int y = out.y0; y < out.y1; ++y)
        std::copy_n(exposure.row(y) + (out.x0 - exposure.window.x0), out.width(), cropped.row(y));
    return cropped;
}

// One material: exposure planes (one per layer) on their window -> density planes on `out`.
std::vector<Plane> develop_material(const MaterialStages& m, std::vector<Plane> exposure, const Window& out,
                                    const Window& frame, int threads, StageTimes* times) {
    std::vector<Plane> density;
    for (size_t i = 0; i < exposure.size(); ++i) {
        // The Boolean grain of a pixel depends on the densities around it: develop those too.
        const Window developed = m.boolean_grain[i] ? out.grown(m.boolean_grain[i]->halo_px).intersected(frame) : out;
        Plane d = spread_exposure(m, i, std::move(exposure[i]), developed, frame, threads, times);
        if (m.grain[i] && !m.curve_tables.empty()) {
            StageTimer timer(times, kDevelopAndGrainStage);
            develop_with_grain(d, m.curve_tables[i], *m.grain[i], threads);
            density.push_back(std::move(d));
            continue;
        }
        {
            StageTimer timer(times, "develop");
            // Exposure below 0 (a PSF's negative lobes) is no light.
            parallel_for(developed.y0, developed.y1, threads, [&](int y0, int y1) {
                for (int y = y0; y < y1; ++y) {
                    float* row = d.row(y);
                    if (!m.curve_tables.empty()) {
                        m.curve_tables[i].apply_row(row, row, developed.width());
                    } else {
                        const Curve& curve = m.stock.layers[i].density_curve;
                        for (int x = 0; x < developed.width(); ++x)
                            row[x] = float(curve(std::log10(std::max(double(row[x]), 1e-30))));
                    }
                }
            });
        }
        if (m.grain[i]) {
            StageTimer timer(times, "grain");
            apply_grain(d, *m.grain[i], threads);
        }
        if (m.boolean_grain[i]) {
            StageTimer timer(times, "grain");
            apply_boolean_grain(d, *m.boolean_grain[i], threads);
            Plane cropped = Plane::unset(out);
            for (int y = out.y0; y < out.y1; ++y) std::copy_n(d.row(y) + (out.x0 - developed.x0), out.width(), cropped.row(y));
            d = std::move(cropped);
        }
        density.push_back(std::move(d));
    }
    return density;
}

// Applies f(layer density rows, result rows, width) to each row of `window`, result planes
// of `channels`: whole rows, so that the fast tiers' exponentials vectorise.
template <typename F>
std::vector<Plane> per_row(const std::vector<Plane>& in, const Window& window, size_t channels, int threads, F f) {
    std::vector<Plane> out;
    for (size_t c = 0; c < channels; ++c) out.push_back(Plane::unset(window));
    parallel_for(window.y0, window.y1, threads, [&](int y0, int y1) {
        const float* in_rows[3];
        float* out_rows[3];
        for (int y = y0; y < y1; ++y) {
            for (size_t l = 0; l < in.size(); ++l) in_rows[l] = in[l].row(y) + (window.x0 - in[l].window.x0);
            for (size_t c = 0; c < channels; ++c) out_rows[c] = out[c].row(y);
            f(in_rows, out_rows, window.width());
        }
    });
    return out;
}

// Applies f(layer densities, result) in double to every pixel of `window` (the spectral tiers).
template <typename F>
std::vector<Plane> per_pixel(const std::vector<Plane>& in, const Window& window, size_t channels, int threads, F f) {
    return per_row(in, window, channels, threads, [&](const float* const* d, float* const* result, int width) {
        double values[3], results[3];
        for (int x = 0; x < width; ++x) {
            for (size_t l = 0; l < in.size(); ++l) values[l] = d[l][x];
            f(values, results);
            for (size_t c = 0; c < channels; ++c) result[c][x] = float(results[c]);
        }
    });
}

// Refuses a setting outside [lo, hi] (NaN included), naming it and the value it was given:
// "<what> must be <range>, not <value>".
void check_range(double value, double lo, double hi, const std::string& what, const std::string& range) {
    if (value >= lo && value <= hi) return;
    std::ostringstream given;
    given << value;
    throw std::invalid_argument(what + " must be " + range + ", not " + given.str());
}

void validate(const DevelopSettings& s) {
    check_range(s.exposure_ev, -kMaxExposureEv, kMaxExposureEv, "camera exposure", "within +-64 EV");
    check_range(s.print_exposure_ev, -kMaxExposureEv, kMaxExposureEv, "print exposure", "within +-64 EV");
    check_range(s.frame_width_mm, 0, kMaxFormatMm, "frame width", "0-10000 mm");
    check_range(s.print_width_mm, 0, kMaxFormatMm, "print width", "0-10000 mm");
    check_range(s.halation, 0, kMaxHalation, "halation", "0-100");
    for (int c = 0; c < 3; ++c) {
        const std::string channel = std::string(" (") + "RGB"[c] + ")";
        check_range(s.grain_amount[c], 0, kMaxGrainScale, "grain amount" + channel, "0-100");
        check_range(s.grain_size[c], 0, kMaxGrainScale, "grain size" + channel, "0-100");
        // NaN: the stock's own response.
        if (!std::isnan(s.grain_density_exponent[c]))
            check_range(s.grain_density_exponent[c], 0, kMaxGrainResponse, "grain response (density exponent)" + channel,
                        "0-4");
        check_range(s.printer_lights[c], kPrinterLightsAuto - kMaxPrinterPoints, kPrinterLightsAuto + kMaxPrinterPoints,
                    "printer lights" + channel, "within 25 +-200 points");
        check_range(s.filtration_ymc[c], 0, kMaxFiltrationCc, std::string("filtration (") + "YMC"[c] + ")", "0-1000 CC");
    }
}

// The print tables span each layer's densities, widened for grain; beyond, they clamp.
void table_density_range(const Stock& stock, std::array<double, 3>& lo, std::array<double, 3>& hi) {
    for (int l = 0; l < 3; ++l) {
        lo[l] = stock.layers[l].density_curve.y_min() - kTableDensityMargin;
        hi[l] = stock.layers[l].density_curve.y_max() + kTableDensityMargin;
    }
}

// The paper's layer densities from its layers' exposures, through its curves.
void develop_paper(const Stock& paper, const double* paper_exposure_lux_s, double* paper_density) {
    for (int j = 0; j < 3; ++j)
        paper_density[j] =
            paper.layers[j].density_curve(std::log10(std::clamp(paper_exposure_lux_s[j], 1e-30, kMaxInput)));
}

// The paper's layer densities printed from the negative's (colour on colour): the enlarger's
// exposure developed through the paper's curves.
void print_densities(const PrintExposure& enlarger, const Stock& paper, const double* negative_density,
                     double* paper_density) {
    double h[3];
    enlarger.expose(negative_density, h);
    develop_paper(paper, h, paper_density);
}

// The one print table of a colour negative on colour paper: the negative's densities -> the
// print's linear Rec.709, the high tier's print at each node, held as cube roots (tables.h).
// A plan compiled again for another exposure, grain, MTF or halation (a slider dragged in a
// host) prints the same: its table, about a tenth of a second of spectral sums on two cores,
// is taken from the last few built, found by the bytes of everything it reads.
std::shared_ptr<const Table3D> shared_print_table(const Stock& film, const Stock& paper, const PrintExposure& enlarger,
                                                  int nodes, int threads) {
    std::array<double, 3> lo, hi;
    table_density_range(film, lo, hi);
    std::string key = enlarger.fingerprint();
    auto append = [&](const auto* v, size_t count) { key.append(reinterpret_cast<const char*>(v), sizeof *v * count); };
    append(lo.data(), 3), append(hi.data(), 3), append(&nodes, 1);
    const size_t layers = paper.layers.size();  // (then what the paper's curves and view read)
    append(&layers, 1), append(paper.base_density.data(), paper.base_density.size());
    for (const Layer& l : paper.layers) {
        append(l.dye_density.data(), l.dye_density.size());
        for (const std::vector<double>* v : {&l.density_curve.x, &l.density_curve.y}) {
            const size_t n = v->size();
            append(&n, 1), append(v->data(), n);
        }
    }
    static std::mutex mutex;
    static std::vector<std::pair<std::string, std::shared_ptr<const Table3D>>> recent;  // the last used last
    constexpr size_t kKept = 4;
    auto find = [&]() -> std::shared_ptr<const Table3D> {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = std::find_if(recent.begin(), recent.end(), [&](const auto& e) { return e.first == key; });
        if (it == recent.end()) return nullptr;
        std::rotate(it, it + 1, recent.end());
        return recent.back().second;
    };
    if (auto table = find()) return table;
    // Each axis node's factor of the negative's transmittance, computed once.
    std::array<std::vector<Spectrum>, 3> transmittance;
    for (int a = 0; a < 3 && enlarger.spectral(); ++a)
        for (int i = 0; i < nodes; ++i)
            transmittance[a].push_back(
                enlarger.layer_transmittance(a, Table3D::node_coordinate(lo[a], hi[a], nodes, i)));
    const PrintView view(paper);
    auto table = std::make_shared<const Table3D>(lo, hi, nodes, threads, [&](const int* node, const double* d, double* rgb) {
        double h[3], paper_density[3];
        if (enlarger.spectral())
            enlarger.expose({&transmittance[0][node[0]], &transmittance[1][node[1]], &transmittance[2][node[2]]}, h);
        else
            enlarger.expose(d, h);
        develop_paper(paper, h, paper_density);
        view.rgb(paper_density, rgb);
    }, Table3D::Encoding::cube_root);
    std::lock_guard<std::mutex> lock(mutex);  // (another compile may have built it meanwhile: either serves)
    if (recent.size() == kKept) recent.erase(recent.begin());
    recent.emplace_back(std::move(key), table);
    return table;
}

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

// The x >= 0 that minimises |A x - b| for a 3x3 A, with x_i held at 0 where !free[i]: exact
// minimisation along one coordinate at a time, projected onto x_i >= 0 (it converges for
// this convex problem; the sweeps are far more than three unknowns need).
std::array<double, 3> nonnegative_least_squares(const double (&a)[3][3], const double (&b)[3], const bool (&free)[3]) {
    std::array<double, 3> x{};
    for (int sweep = 0; sweep < 300; ++sweep)
        for (int i = 0; i < 3; ++i) {
            double column_norm = 0, gradient = 0;  // of |A x - b|^2 / 2 along x_i
            for (int j = 0; j < 3; ++j) {
                gradient += a[j][i] * (a[j][0] * x[0] + a[j][1] * x[1] + a[j][2] * x[2] - b[j]);
                column_norm += a[j][i] * a[j][i];
            }
            if (free[i] && column_norm > 0) x[i] = std::max(0.0, x[i] - gradient / column_norm);
        }
    return x;
}

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
    const PrintView view(paper.stock);
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
    // 3 with the cross terms, each level on its own.
    std::vector<std::array<double, 3>> extra(levels.size());  // e_i at each level
    parallel_for(0, int(levels.size()), threads, [&](int begin, int end) {
        for (int level = begin; level < end; ++level) {
            const Level& e = equations[size_t(level)];
            std::array<double, 3> t = nonnegative_least_squares(e.a, e.b, grained);
            for (int iteration = 0; iteration < 30; ++iteration) {
                double s[3], b[3];
                for (int i = 0; i < 3; ++i) s[i] = std::sqrt(e.film_variance[i] + t[i]);
                for (int c = 0; c < 3; ++c) {
                    b[c] = e.b[c];
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j)
                            if (i != j) b[c] -= e.m[c][i] * e.m[c][j] * s[i] * s[j] * correlation[i][j];
                }
                const std::array<double, 3> next = nonnegative_least_squares(e.a, b, grained);
                if (next == t) break;  // (settled: every later sweep would repeat it)
                t = next;
            }
            for (int i = 0; i < 3; ++i) extra[size_t(level)][size_t(i)] = grained[i] ? std::sqrt(t[i]) / gain[i] : 0.0;
        }
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
        film.curve_tables[i] = LogAxisTable(film.stock.layers[i].density_curve, curve_table_bits,
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

}  // namespace

int MaterialStages::halo_px() const {
    int r = 0;
    for (size_t i = 0; i < scatter.size(); ++i)
        r = std::max(r, scatter[i].radius + (halation[i] ? halation[i]->radius : 0) +
                            (boolean_grain[i] ? boolean_grain[i]->halo_px : 0));
    return r;
}

namespace {

// The image's window in the film frame's coordinates; throws for an unusable geometry.
Window image_window(const FrameGeometry& frame) {
    if (frame.width <= 0 || frame.height <= 0)
        throw std::invalid_argument("frame size " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                                    " is empty");
    if (frame.film_width < 0) throw std::invalid_argument("film frame width " + std::to_string(frame.film_width) + " px is negative");
    // (Far inside int's range, so that windows grown by a halo never overflow.)
    constexpr int kMaxCoordinate = 1 << 28;
    for (long long v : {(long long)frame.x0, (long long)frame.y0, (long long)frame.x0 + frame.width,
                        (long long)frame.y0 + frame.height})
        if (std::abs(v) > kMaxCoordinate)
            throw std::invalid_argument("the image's window (" + std::to_string(frame.x0) + ", " + std::to_string(frame.y0) +
                                        ") + " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                                        " reaches beyond +-2^28 pixels of the film frame");
    return Window{frame.x0, frame.y0, frame.x0 + frame.width, frame.y0 + frame.height};
}

}  // namespace

Plan Plan::compile(const Stock& film, const Stock* paper, const DevelopSettings& settings,
                   const FrameGeometry& frame, int threads) {
    const Window image = image_window(frame);
    if (film.kind != StockKind::negative) throw std::invalid_argument("'" + film.id + "' is not a film stock (it is a paper or print film)");
    if (paper && paper->kind == StockKind::negative)
        throw std::invalid_argument("'" + paper->id + "' is a camera film, not a paper or print film");
    if (settings.output == OutputMode::print && !paper)
        throw std::invalid_argument("print output needs a paper (or choose the negative, density, scan or texture output)");
    validate(settings);

    Plan p;
    p.settings_ = settings;
    p.frame_ = image;
    p.film_width_px_ = frame.film_width_px();
    p.monochrome_ = frame.monochrome;
    const QualityTier& tier = quality_tier(settings.quality);
    const bool printing = settings.output == OutputMode::print;
    const bool one_print_table =
        printing && tier.print_table_nodes > 0 && film.is_colour() && paper->is_colour();
    const double film_width_mm = settings.frame_width_mm > 0 ? settings.frame_width_mm : film.frame_width_mm;
    const double print_width_mm =
        !printing ? 0.0 : settings.print_width_mm > 0 ? settings.print_width_mm : paper->frame_width_mm;
    p.film_stages_ = build_stages(film, film_width_mm, p.film_width_px_, settings, 0, "film", p.skipped_, threads);
    p.monochrome_input_ = frame.monochrome && settings.skip_noop_stages;
    if (p.monochrome_input_ && settings.output != OutputMode::texture)
        p.skipped_.push_back("spectral sensitivity: the input is grey, so each layer's exposure is one scale of it");
    p.film_exposure_scale_ = settings.input_units == InputUnits::lux_seconds
                                 ? 1.0
                                 : mid_grey_exposure_lux_s(film.iso_speed) / 0.18 * std::exp2(settings.exposure_ev);

    if (printing) {
        p.paper_stages_ = build_stages(*paper, print_width_mm, p.film_width_px_, settings, 16, "paper", p.skipped_,
                                       threads);
        p.print_ = PrintExposure::design(film, *paper,
                                         {mid_grey_exposure_lux_s(film.iso_speed), settings.printer_lights,
                                          settings.filtration_ymc, settings.print_exposure_ev});
        if (one_print_table) {
            fold_paper_grain(p.film_stages_, p.paper_stages_, *p.print_, p.film_exposure_scale_,
                             tier.curve_table_bits, threads);
            leave_out_paper_grain(p.paper_stages_, p.film_stages_, p.skipped_);
            p.print_table_ = shared_print_table(film, *paper, *p.print_, tier.print_table_nodes, threads);
        }
    } else if (paper) {
        p.skipped_.push_back("print: the output stops at the negative");
    }
    return p;
}

Plan Plan::in_image(const FrameGeometry& image) const {
    if (image.film_width_px() != film_width_px_ || image.monochrome != monochrome_)
        throw std::invalid_argument("Plan::in_image: another film frame width or channel count needs its own plan");
    Plan p = *this;
    p.frame_ = image_window(image);
    return p;
}

Plan Plan::for_frame(int frame) const {
    Plan p = *this;
    p.settings_.frame = frame;
    for (MaterialStages* m : {&p.film_stages_, &p.paper_stages_}) {
        for (auto& g : m->grain) {
            if (!g) continue;
            g->key.frame = frame;
            for (GrainModel::NoiseTerm& term : g->mixed_noise) term.key.frame = frame;  // (the film layers' keys)
        }
        for (auto& g : m->boolean_grain)
            if (g) g->key.frame = frame;
    }
    return p;
}

int Plan::halo_px() const { return film_stages_.halo_px() + (print_ ? paper_stages_.halo_px() : 0); }

Window Plan::input_window(const Window& output) const { return output.grown(halo_px()).intersected(frame_); }

std::vector<Plane> Plan::develop_film(const ConstImageView& in, const Window& film_out, int threads,
                                      StageTimes* times) const {
    const Window film_in = film_out.grown(film_stages_.halo_px()).intersected(frame_);
    std::vector<Plane> exposure;
    StageTimer expose_timer(times, "expose");
    const auto& weights = film_stages_.rgb_weights;
    for (size_t l = 0; l < weights.size(); ++l) exposure.push_back(Plane::unset(film_in));
    const FilmExposure exposer(in, weights, monochrome_input_, film_exposure_scale_);
    parallel_for(film_in.y0, film_in.y1, threads, [&](int y0, int y1) {
        float* rows[3];
        for (int y = y0; y < y1; ++y) {
            for (size_t l = 0; l < weights.size(); ++l) rows[l] = exposure[l].row(y);
            exposer.row(y, film_in.x0, film_in.width(), rows);
        }
    });
    expose_timer.stop();
    return develop_material(film_stages_, std::move(exposure), film_out, frame_, threads, times);
}

std::vector<Plane> Plan::print(std::vector<Plane> negative, const Window& out, int threads,
                               StageTimes* times) const {
    if (print_table_) {
        // The paper's MTF on the negative's densities, layer i's kernel on film layer i (the
        // paper layer its dye mostly prints on: cyan dye modulates the red light).
        if (paper_stages_.halo_px() > 0) {
            StageTimer timer(times, "scatter");
            for (size_t l = 0; l < negative.size(); ++l) {
                Plane spread = Plane::unset(out);
                scatter(negative[l], spread, paper_stages_.scatter[l], frame_, threads);
                negative[l] = std::move(spread);
            }
        }
        StageTimer timer(times, "print table");
        return per_row(negative, out, 3, threads, [&](const float* const* d, float* const* rgb, int width) {
            print_table_->apply_row(d, rgb, width);
        });
    }
    const PrintExposure& enlarger = *print_;
    StageTimer enlarger_timer(times, "enlarger");
    std::vector<Plane> paper_exposure =
        per_pixel(negative, negative[0].window, enlarger.paper_layers(), threads, [&](const double* d, double* h) {
            enlarger.expose(d, h);
            for (int j = 0; j < enlarger.paper_layers(); ++j) h[j] = std::clamp(h[j], 0.0, kMaxInput);
        });
    enlarger_timer.stop();
    std::vector<Plane> paper_density =
        develop_material(paper_stages_, std::move(paper_exposure), out, frame_, threads, times);
    StageTimer view_timer(times, "view");
    const PrintView view(paper_stages_.stock);
    return per_pixel(paper_density, out, 3, threads, [&](const double* d, double* rgb) { view.rgb(d, rgb); });
}

namespace {

// A layer's developed density at one exposure, as develop_material computes it per pixel.
double developed_density(const MaterialStages& m, size_t layer, double exposure_lux_s) {
    if (!m.curve_tables.empty()) return m.curve_tables[layer](float(exposure_lux_s));
    return m.stock.layers[layer].density_curve(std::log10(std::max(exposure_lux_s, 1e-30)));
}

}  // namespace

std::array<double, 3> Plan::film_exposure_weights(size_t layer) const {
    std::array<double, 3> w = film_stages_.rgb_weights[layer];
    for (double& v : w) v *= film_exposure_scale_;
    return w;
}

double Plan::film_density(size_t layer, double exposure_lux_s) const {
    return developed_density(film_stages_, layer, exposure_lux_s);
}

void Plan::result_of_negative(const double* density, double* result) const {
    if (settings_.output == OutputMode::texture)
        throw std::invalid_argument("Plan::result_of_negative: the texture output develops no negative");
    if (print_table_) {
        const float d[3] = {float(density[0]), float(density[1]), float(density[2])};
        float rgb[3];
        (*print_table_)(d, rgb);
        std::copy_n(rgb, 3, result);
        return;
    }
    if (print_) {
        double h[3], paper_density[3];
        print_->expose(density, h);
        for (int j = 0; j < print_->paper_layers(); ++j)
            paper_density[j] = developed_density(paper_stages_, size_t(j), std::clamp(h[j], 0.0, kMaxInput));
        PrintView(paper_stages_.stock).rgb(paper_density, result);
        return;
    }
    const size_t layers = film_stages_.stock.layers.size();
    for (size_t c = 0; c < 3; ++c) {
        const size_t l = std::min(c, layers - 1);  // (a single layer serves all three)
        float v = float(density[l]);
        convert_row(settings_.output, film_stages_.stock.layers[l].density_curve.y_min(), &v, 1);
        result[c] = v;
    }
}

// Texture: each channel c is treated as the exposure of film layer c (a single-layer film
// serves all three), spread by halation (normalised, so it moves light without adding
// any) and the MTF, and multiplied by the grain's exposure fluctuation
//   exp(k g - k^2 sigma^2 / 2),  k = ln 10 / gamma,
// g the density grain at the pixel's developed density (standard deviation sigma) and
// gamma the curve's slope at mid grey: a log-normal factor of mean exactly 1, so a flat
// patch keeps its mean. Negative input values keep their sign.
std::vector<Plane> Plan::texture(const ConstImageView& in, const Window& out, int threads, StageTimes* times) const {
    const MaterialStages& m = film_stages_;
    const Window film_in = out.grown(m.halo_px()).intersected(frame_);
    // Where the scene's mid grey falls (with the input in lux seconds, 0.18 is no grey: the film's
    // own mid grey at its ISO speed).
    const double mid_grey_log_h = std::log10(settings_.input_units == InputUnits::lux_seconds
                                                 ? mid_grey_exposure_lux_s(m.stock.iso_speed)
                                                 : 0.18 * film_exposure_scale_);
    std::vector<Plane> result;
    std::vector<std::optional<Plane>> fields(m.stock.layers.size());
    for (int c = 0; c < 3; ++c) {
        size_t layer = m.stock.layers.size() == 3 ? size_t(c) : 0;
        Plane h(film_in);
        for (int y = film_in.y0; y < film_in.y1; ++y)
            for (int x = film_in.x0; x < film_in.x1; ++x)
                // Clamped as the film's exposure is: at +64 EV a 1e30 pixel would overflow a float.
                h.at(x, y) = float(std::clamp(sanitize(in.at(x, y)[colour_channel(in, c)]) * film_exposure_scale_,
                                              -kMaxInput, kMaxInput));
        Plane spread = spread_exposure(m, layer, std::move(h), out, frame_, threads, times);
        const float normalise = float(1.0 / (1.0 + (m.halation[layer] ? m.halation[layer]->strength : 0.0)));
        const auto& grain = m.grain[layer];
        if (grain && !fields[layer]) fields[layer] = grain_field(*grain, out, threads);
        const Curve& curve = m.stock.layers[layer].density_curve;
        double gamma = std::max(0.05, curve(mid_grey_log_h + 0.5) - curve(mid_grey_log_h - 0.5));
        double k = kLn10 / gamma;
        // grain_field's standard deviation per pixel (sum of the 2D kernel's squares).
        double field_sigma = grain ? grain->field_sigma() : 1.0;
        parallel_for(out.y0, out.y1, threads, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                for (int x = out.x0; x < out.x1; ++x) {
                    double exposure = double(spread.at(x, y)) * normalise;
                    double factor = 1.0;
                    if (grain) {
                        // The density grain here is sigma times the field normalised to unit variance.
                        double density = curve(std::log10(std::max(exposure, 1e-30)));
                        double sigma = grain_sigma_at(*grain, density);
                        double g = sigma * fields[layer]->at(x, y) / field_sigma;
                        factor = std::exp(k * g - 0.5 * k * k * sigma * sigma);
                    }
                    spread.at(x, y) = float(exposure / film_exposure_scale_ * factor);
                }
        });
        result.push_back(std::move(spread));
    }
    return result;
}

void StageTimes::add(const std::string& stage, double s) {
    for (auto& entry : seconds)
        if (entry.first == stage) {
            entry.second += s;
            return;
        }
    seconds.emplace_back(stage, s);
}

void Plan::run(const ConstImageView& in, const ImageView& out, int threads, StageTimes* times) const {
    const Window out_window = out.window.intersected(frame_);
    if (out_window.empty()) return;
    if (!in.window.contains(input_window(out_window)))
        throw std::invalid_argument("the input image does not cover the window and its halo");
    if (in.channels < 1 || out.channels < 3) throw std::invalid_argument("need 1+ input channels and 3+ output channels");

    if (runs_in_one_pass()) {
        run_one_pass(in, out, out_window, threads, times);
        return;
    }
    std::vector<Plane> result;
    if (settings_.output == OutputMode::texture) {
        result = texture(in, out_window, threads, times);
    } else if (print_) {
        const Window film_out = out_window.grown(paper_stages_.halo_px()).intersected(frame_);
        result = print(develop_film(in, film_out, threads, times), out_window, threads, times);
    } else {
        result = develop_film(in, out_window, threads, times);
        StageTimer timer(times, "convert");
        for (size_t l = 0; l < result.size(); ++l)
            convert_row(settings_.output, film_stages_.stock.layers[l].density_curve.y_min(), result[l].pixels.data(),
                        int(result[l].pixels.size()));
    }

    StageTimer timer(times, "write");
    parallel_for(out_window.y0, out_window.y1, threads, [&](int y0, int y1) {
        const float* rows[3];
        for (int y = y0; y < y1; ++y) {
            for (size_t l = 0; l < result.size(); ++l) rows[l] = result[l].row(y);
            write_row(rows, result.size(), in, out, y, out_window.x0, out_window.width());
        }
    });
}

double Plan::silver_grains_per_pixel() const {
    double grains = 0;
    for (const MaterialStages* m : {&film_stages_, &paper_stages_})
        for (const auto& g : m->boolean_grain)
            if (g) grains += g->grains_per_pixel_at(1.0);
    return grains;
}

// The reference tier's grain costs about this much CPU time per silver grain drawn: 0.75 us
// on a 2-core machine, in the benchmark (its 4K reference frame, extrapolated from
// its sample windows: 24 700 s on 2 threads for 7 500 grains a pixel).
constexpr double kCpuSecondsPerSilverGrain = 0.75e-6;
constexpr double kLongRenderCpuSeconds = 900;

std::string long_reference_render_warning(const Plan& plan, const Window& out, const std::string& quality_setting) {
    const double per_pixel = plan.silver_grains_per_pixel();
    const double grains = per_pixel * double(out.width()) * double(out.height());
    const double cpu_seconds = grains * kCpuSecondsPerSilverGrain;
    if (cpu_seconds < kLongRenderCpuSeconds) return {};
    std::ostringstream message;
    message.precision(2);
    message << quality_setting << "reference draws every silver grain: about " << grains << " here ("
            << per_pixel << " a pixel), roughly " << cpu_seconds / 3600 << " CPU hours; "
            << quality_setting << "high gives the same grain statistics as filtered noise";
    return message.str();
}

std::vector<std::string> Plan::describe() const {
    std::vector<std::string> lines;
    auto material = [&](const MaterialStages& m, const char* role, bool exposed_by_scene) {
        lines.push_back(std::string(role) + " " + m.stock.id + ": pixel pitch " + fmt(m.pixel_pitch_um) + " um");
        for (size_t i = 0; i < m.stock.layers.size(); ++i) {
            const Layer& l = m.stock.layers[i];
            const auto& w = m.rgb_weights[i];
            if (exposed_by_scene && !monochrome_input_)
                lines.push_back("  spectral sensitivity (" + l.name + ", " + m.stock.exposure_illuminant_name +
                                "): exposure = " + fmt(w[0]) + " R + " + fmt(w[1]) + " G + " + fmt(w[2]) + " B");
            if (m.halation[i])
                lines.push_back("  halation (" + l.name + "): " + fmt(m.halation[i]->strength) + " of the exposure, " +
                                "halo " + std::to_string(m.halation[i]->radius) + " px" +
                                (m.halation[i]->decimation > 1
                                     ? ", on a " + std::to_string(m.halation[i]->decimation) + "x coarser grid"
                                     : std::string()));
            if (!m.scatter[i].is_identity())
                lines.push_back("  scatter (" + l.name + "): MTF kernel radius " + std::to_string(m.scatter[i].radius) +
                                " px, " +
                                (m.scatter[i].separable.empty()
                                     ? std::string("direct 2D sum")
                                     : std::to_string(m.scatter[i].separable.size()) + " separable terms" +
                                           (m.scatter[i].centre != 0 ? " and a centre delta" : "")));
            lines.push_back("  develop (" + l.name + "): H&D curve, D " + fmt(l.density_curve.y_min()) + " to " +
                            fmt(l.density_curve.y_max()));
            if (m.grain[i])
                lines.push_back("  grain (" + l.name + "): " + fmt(m.grain[i]->pixel_sigma_at_unit_density()) +
                                " D per pixel at net density 1, filter radius " + std::to_string(m.grain[i]->radius) +
                                " px" + (m.grain[i]->fast ? ", hashed noise" : ""));
            if (m.boolean_grain[i])
                lines.push_back("  grain (" + l.name + "): silver disks (Boolean model), radius " +
                                fmt(m.boolean_grain[i]->radius_at(1.0), 3) + " um at net density 1, " +
                                fmt(m.boolean_grain[i]->intensity_at(1.0), 3) + " grains per um^2, " +
                                fmt(m.boolean_grain[i]->grains_per_pixel_at(1.0), 3) +
                                " per pixel");
        }
    };
    if (settings_.input_units == InputUnits::lux_seconds)
        lines.push_back("expose: input pixels are exposures in lux-seconds");
    else
        lines.push_back("expose: scene-linear 0.18 -> " + fmt(0.18 * film_exposure_scale_) + " lux-s (ISO " +
                        fmt(film_stages_.stock.iso_speed) + ", " + fmt(settings_.exposure_ev) + " EV)");
    material(film_stages_, "film", settings_.output != OutputMode::texture);
    switch (settings_.output) {
        case OutputMode::print: {
            const PrintExposure& e = *print_;
            std::string lights;
            for (int j = 0; j < e.paper_layers(); ++j)
                lights += (j ? ", " : "") + fmt(e.light_lux_s()[j]) + " (aim D " + fmt(e.aim_density()[j], 3) + ")";
            if (print_table_)
                lines.push_back("print: one table of " + std::to_string(print_table_->nodes()) +
                                " nodes per axis from the negative's densities to the print's colour; the "
                                "paper's MTF on the negative's densities");
            lines.push_back("print: 3200 K enlarger, " +
                            std::string(e.spectral() ? "spectral transmittance of the dyed negative"
                                                     : "neutral (silver) negative") +
                            "; lights through clear base " + lights + " lux-s");
            material(paper_stages_, "paper", false);
            lines.push_back("convert: print density -> linear Rec.709 under D65");
            break;
        }
        case OutputMode::negative: lines.push_back("convert: density -> transmittance"); break;
        case OutputMode::density: lines.push_back("convert: none (diffuse density written)"); break;
        case OutputMode::scan: lines.push_back("convert: density -> Cineon log code values / 1023"); break;
        case OutputMode::texture:
            lines.push_back("convert: texture: grain, MTF and halation applied to the scene-linear input");
            break;
    }
    lines.push_back(runs_in_one_pass() ? "run: every stage a row at a time, the frame's planes never stored"
                                       : "run: stage after stage over whole planes");
    for (const std::string& s : skipped_) lines.push_back("skipped " + s);
    return lines;
}

}  // namespace darkroom
