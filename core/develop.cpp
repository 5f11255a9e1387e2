#include "core/develop.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <future>
#include <iomanip>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "core/develop_rows.h"
#include "core/material_stages.h"
#include "core/parallel.h"
#include "core/print_grain_fold.h"
#include "core/simd.h"
#include "core/stages/filters.h"
#include "core/spectral.h"

namespace darkroom {

namespace {

// How far past a stock's curve the fast tiers' print tables reach (grain's excursions).
constexpr double kTableDensityMargin = 0.3;
constexpr double kLn10 = 2.302585092994046;

// How the look says a print (or a projected slide) is seen.
ViewSettings view_settings(const DevelopSettings& s) { return {s.print_viewing, s.print_gamut_compression}; }

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

// The most pixels a layer's working plane may have: the frame grown by a kernel's reach on
// every side (a grain or halo many times the frame) past this would take gigabytes and
// minutes for what the frame cannot show (256 MB a float plane; a 4K frame with its
// stocks' kernels has some 10 million).
constexpr double kMaxGrownPlanePx = 64e6;

// Throws std::invalid_argument, before a kernel is designed, when one of `radius_px` makes
// the frame's working planes larger than kMaxGrownPlanePx: `what` names the kernel and why
// it is that wide, `remedy` the settings that narrow it.
void require_kernel_budget(double radius_px, int frame_width_px, int frame_height_px, const std::string& what,
                           const std::string& remedy) {
    const double grown = (frame_width_px + 2 * radius_px) * (frame_height_px + 2 * radius_px);
    if (grown <= kMaxGrownPlanePx) return;
    throw std::invalid_argument(what + " reaches " + std::to_string((long long)radius_px) + " px, which would make each " +
                                std::to_string(frame_width_px) + "x" + std::to_string(frame_height_px) +
                                " px layer " + fmt(grown * 4 / 1e9, 2) + " GB of working memory (at most " +
                                fmt(kMaxGrownPlanePx * 4 / 1e9, 2) + " GB): " + remedy);
}

// proxy_factor: the preview's proxy's pixel pitch over the frame's (1: no proxy).
MaterialStages build_stages(const Stock& stock, double width_mm, int frame_width_px, int frame_height_px,
                            const DevelopSettings& s, const PlanStructure& structure, uint32_t stream_base,
                            const char* role, int proxy_factor,
                            std::vector<std::string>& skipped, int threads) {
    const QualityTier& tier = quality_tier(s.quality);
    MaterialStages m;
    m.stock = stock;
    m.pixel_pitch_um = width_mm * 1000.0 / frame_width_px;
    // (The width the message asks for, divided by the pixels, may round to just below the limit.)
    if (!(m.pixel_pitch_um >= kMinPixelPitchUm * (1 - 1e-12))) {
        const char* width = std::string(role) == "film" ? "frame" : "print";  // (the settings' names)
        throw std::invalid_argument(std::string("the ") + role + "'s pixel pitch, " + fmt(m.pixel_pitch_um) + " um (" +
                                    fmt(width_mm) + " mm across " + std::to_string(frame_width_px) + " px), is below " +
                                    fmt(kMinPixelPitchUm) + " um: give a " + width + " width of at least " +
                                    fmt(kMinPixelPitchUm * frame_width_px / 1000.0) + " mm");
    }
    const std::string pitch = " at " + fmt(m.pixel_pitch_um) + " um pitch";
    const std::string width_setting = std::string(role) == "film" ? "frame width" : "print width";
    for (size_t i = 0; i < stock.layers.size(); ++i) {
        const Layer& layer = stock.layers[i];
        std::string where = std::string(role) + " layer " + layer.name;
        m.rgb_weights.push_back(rgb_exposure_weights(layer.sensitivity, stock.exposure_illuminant));

        // Each kernel's reach (its design's 4 standard deviations) checked before it is designed.
        if (s.halation * layer.halation.strength > 0)
            require_kernel_budget(4 * layer.halation.radius_um / m.pixel_pitch_um, frame_width_px, frame_height_px,
                                  "the halation of " + where + " (" + fmt(layer.halation.radius_um) + " um" + pitch + ")",
                                  "give a larger " + width_setting + " or halation 0");
        HalationKernel halation = design_halation(layer.halation.strength * s.halation, layer.halation.radius_um,
                                                  m.pixel_pitch_um, tier.halation_decimation);
        m.halation.push_back(std::nullopt);
        if (!halation.is_noop() || !structure.skip_noop_stages)
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
        if (spec.rms_granularity > 0)
            require_kernel_budget(4 * spec.grain_size_um / m.pixel_pitch_um, frame_width_px, frame_height_px,
                                  "the grain of " + where + " (" + fmt(spec.grain_size_um) + " um" + pitch + ")",
                                  "give a smaller grain size or a larger " + width_setting);
        const NoiseKey key{s.seed, s.frame, stream_base + uint32_t(i)};
        // (The texture output takes its exposure fluctuation from the filtered-noise field.)
        if (tier.grain == GrainMethod::boolean_model && s.output != OutputMode::texture) {
            BooleanGrain boolean = design_boolean_grain(spec, layer.density_curve.y_min(), m.pixel_pitch_um, key);
            if (!boolean.is_noop() || !structure.skip_noop_stages) {
                m.boolean_grain.back() = boolean;
                continue;
            }
        }
        const bool fast_grain = tier.grain == GrainMethod::hashed_noise;
        GrainModel g = design_grain(spec, layer.density_curve.y_min(), m.pixel_pitch_um, key, fast_grain);
        // The preview's proxy: its grain, drawn at the proxy's pitch and upsampled, keeps the
        // frame's per-pixel standard deviation (averaging a block and interpolating each lower
        // it: to 0.375 for grain finer than a pixel at factor 2); its texture stays the coarser one.
        if (proxy_factor > 1 && !g.is_noop()) {
            const GrainModel frame_grain = design_grain(spec, layer.density_curve.y_min(),
                                                        m.pixel_pitch_um / proxy_factor, key, fast_grain);
            g.sigma_per_pixel *= frame_grain.pixel_sigma_at_unit_density() /
                                 (g.pixel_sigma_at_unit_density() *
                                  proxy_upsampled_sigma_ratio(g.lag1_correlation(), proxy_factor));
        }
        if (!structure.skip_noop_stages)
            m.grain.back() = g;
        else if (!s.grain)
            skipped.push_back("grain (" + where + "): grain turned off");
        else if (g.is_noop())
            skipped.push_back("grain (" + where + "): " + fmt(g.pixel_sigma_at_unit_density(), 2) +
                              " D per pixel is below " + fmt(GrainModel::kNoOpSigma, 2) + pitch);
        else
            m.grain.back() = g;
    }
    // A colour negative's DIR couplers (the texture output develops nothing, its tone unchanged).
    const DirCouplerSpec couplers = stock_dir_couplers(stock);
    if (s.output != OutputMode::texture && couplers != DirCouplerSpec{}) {
        if (s.dir_couplers == 0) {
            skipped.push_back("DIR couplers (" + std::string(role) + "): turned off");
        } else {
            require_kernel_budget(4 * couplers.diffusion_um * s.dir_coupler_spread / m.pixel_pitch_um, frame_width_px,
                                  frame_height_px,
                                  "the DIR couplers' inhibitor (" + fmt(couplers.diffusion_um) + " um x " +
                                      fmt(s.dir_coupler_spread) + pitch + ")",
                                  "give a smaller dir-coupler-spread or a larger " + width_setting);
            m.couplers = design_couplers(stock, s.dir_couplers, s.dir_coupler_spread, m.pixel_pitch_um,
                                         tier.curve_table_bits, tier.coupler_decimation);
        }
    }
    // The tabulated curves; with grain, each also gives the grain's amplitude at its density
    // from the same lookup (develop and grain then run as one pass over the rows).
    if (tier.curve_table_bits > 0)
        for (size_t i = 0; i < stock.layers.size(); ++i) {
            LogAxisTable::Function amplitude;
            if (const auto& g = m.grain[i]) amplitude = [g](double density) { return g->amplitude_at(density); };
            m.curve_tables.emplace_back(m.develop_curve(i), tier.curve_table_bits, amplitude);
        }
    return m;
}

// `out` of a plane that covers it (the plane itself when it is `out`).
Plane cropped(Plane p, const Window& out) {
    if (p.window == out) return p;
    Plane c = Plane::unset(out);
    for (int y = out.y0; y < out.y1; ++y) std::copy_n(p.row(y) + (out.x0 - p.window.x0), out.width(), c.row(y));
    return c;
}

// Halation then scatter of one layer's exposure (on its window) into `out`.
Plane spread_exposure(const MaterialStages& m, size_t layer, Plane exposure, const Window& out, const Window& frame,
                      int threads, StageTimes* times) {
    if (m.halation[layer]) {
        StageTimer timer(times, "halation");
        Plane halated = Plane::unset(scatter_input_window(m.scatter[layer], out, frame));
        apply_halation(exposure, halated, *m.halation[layer], frame, threads);
        exposure = std::move(halated);
    }
    if (!m.scatter[layer].is_identity()) {
        StageTimer timer(times, "scatter");
        Plane spread = Plane::unset(out);
        scatter(exposure, spread, m.scatter[layer], frame, threads);
        return spread;
    }
    return cropped(std::move(exposure), out);  // another layer's halo made it larger than this one needs
}

// The DIR couplers (core/stages/couplers.h): every layer's exposure spread onto `developed`
// grown by the inhibitor's reach, the donors' net densities from it, spread, and each layer's
// exposure on `developed` lowered by its inhibition.
std::vector<Plane> inhibited_exposure(const MaterialStages& m, std::vector<Plane> exposure, const Window& developed,
                                      const Window& frame, int threads, StageTimes* times) {
    const CouplerStage& c = *m.couplers;
    const Window reach = developed.grown(c.radius()).intersected(frame);
    for (size_t l = 0; l < 3; ++l) exposure[l] = spread_exposure(m, l, std::move(exposure[l]), reach, frame, threads, times);
    StageTimer timer(times, "DIR couplers");
    if (c.spread.decimation > 1) {
        // The spread on the coarse grid, a stream per band (as the one pass runs it).
        std::vector<Plane> inhibited;
        for (size_t l = 0; l < 3; ++l) inhibited.push_back(Plane::unset(developed));
        parallel_for(developed.y0, developed.y1, threads, [&](int y0, int y1) {
            CoarseCouplerStream stream(c, Window{developed.x0, y0, developed.x1, y1}, frame,
                                       [&](int y, int x_begin, int x_end, float* const* rows) {
                                           for (size_t l = 0; l < 3; ++l) {
                                               const float* in = exposure[l].row(y) - exposure[l].window.x0;
                                               std::copy(in + x_begin, in + x_end, rows[l]);
                                           }
                                       });
            for (int y = y0; y < y1; ++y) {
                float* const* rows = stream.row(y);
                for (size_t l = 0; l < 3; ++l) std::copy_n(rows[l], developed.width(), inhibited[l].row(y));
            }
        });
        return inhibited;
    }
    std::vector<Plane> donor;
    for (size_t l = 0; l < 3; ++l) {
        donor.push_back(Plane::unset(reach));
        parallel_for(reach.y0, reach.y1, threads, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) coupler_donor_row(c, l, exposure[l].row(y), donor[l].row(y), reach.width());
        });
        if (c.radius() > 0) {
            Plane spread = Plane::unset(developed);
            convolve_separable(donor[l], spread, c.spread.taps, frame, threads);
            donor[l] = std::move(spread);
        }
        exposure[l] = cropped(std::move(exposure[l]), developed);
    }
    parallel_for(developed.y0, developed.y1, threads, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            float* rows[3] = {exposure[0].row(y), exposure[1].row(y), exposure[2].row(y)};
            const float* spread[3] = {donor[0].row(y), donor[1].row(y), donor[2].row(y)};
            inhibit_rows(c, rows, spread, developed.width());
        }
    });
    return exposure;
}

// One material: exposure planes (one per layer) on their window -> density planes on `out`.
std::vector<Plane> develop_material(const MaterialStages& m, std::vector<Plane> exposure, const Window& out,
                                    const Window& frame, int threads, StageTimes* times) {
    if (m.couplers)
        exposure = inhibited_exposure(m, std::move(exposure), m.layers_developed_window(out, frame), frame, threads, times);
    std::vector<Plane> density;
    for (size_t i = 0; i < exposure.size(); ++i) {
        // The Boolean grain of a pixel depends on the densities around it: develop those too.
        const Window developed = m.developed_window(i, out, frame);
        Plane d = m.couplers ? cropped(std::move(exposure[i]), developed)
                             : spread_exposure(m, i, std::move(exposure[i]), developed, frame, threads, times);
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
                        const Curve& curve = m.develop_curve(i);
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
            d = cropped(std::move(d), out);
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
    check_range(s.scan_aim_code, 0, kMaxScanCode, "scan aim", "a code value 0-1023");
    check_range(s.dir_couplers, 0, kMaxDirCouplers, "DIR couplers", "0-3");
    check_range(s.dir_coupler_spread, 0, kMaxDirCouplerSpread, "DIR coupler spread", "0-10");
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


// The last few values of a kind built, found by the bytes of everything they read (`key`);
// `build` makes one that is not there. Shared by every plan of the process.
// Bumped by forget_print_tables: keys carry it, so what was kept before is never found again.
std::atomic<unsigned> kept_generation{0};

template <typename T>
std::shared_ptr<const T> recently_built(const std::string& bytes, const std::function<std::shared_ptr<const T>()>& build) {
    const std::string key = std::to_string(kept_generation.load()) + ":" + bytes;
    static std::mutex mutex;
    static std::vector<std::pair<std::string, std::shared_ptr<const T>>> recent;  // the last used last
    constexpr size_t kKept = 4;
    {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = std::find_if(recent.begin(), recent.end(), [&](const auto& e) { return e.first == key; });
        if (it != recent.end()) {
            std::rotate(it, it + 1, recent.end());
            return recent.back().second;
        }
    }
    std::shared_ptr<const T> value = build();
    std::lock_guard<std::mutex> lock(mutex);  // (another compile may have built it meanwhile: either serves)
    if (recent.size() == kKept) recent.erase(recent.begin());
    recent.emplace_back(key, value);
    return value;
}

template <typename T>
void append_bytes(std::string& key, const T* v, size_t count) {
    key.append(reinterpret_cast<const char*>(v), sizeof *v * count);
}

// Appends what viewing a material reads (stages/print.h, PrintView): its base, dyes and
// curves (their minima are the dyes' zero).
void append_view_key(std::string& key, const Stock& material) {
    const size_t layers = material.layers.size();
    append_bytes(key, &layers, 1), append_bytes(key, material.base_density.data(), material.base_density.size());
    for (const Layer& l : material.layers) {
        append_bytes(key, l.dye_density.data(), l.dye_density.size());
        for (const std::vector<double>* v : {&l.density_curve.x, &l.density_curve.y}) {
            const size_t n = v->size();
            append_bytes(key, &n, 1), append_bytes(key, v->data(), n);
        }
    }
}

// The paper's log10 exposures at every node of a grid of negatives' densities, printed at
// unit lights (PrintExposure::at_unit_lights): the printer lights and print exposure add
// log10 of their light to a layer's, so one grid serves every light. By rows of nodes along
// x, as the table reads them: row (j, k)'s three layers one after another.
struct PaperLogExposures {
    int nodes = 0;
    std::vector<double, UnsetAllocator<double>> log_h;
    // Where row (j, k) starts in log_h: layer l's log exposure at its node i is l * nodes + i on.
    size_t rows(int j, int k) const { return (size_t(k) * size_t(nodes) + size_t(j)) * 3 * size_t(nodes); }
};

// log10 of n doubles (simd::log10_lanes, the same on every processor); values that are not
// positive normal doubles (0: no light) are std::log10's (-inf).
struct Log10 {
    template <typename D, typename L>
    __attribute__((always_inline)) static void apply(const D& v, D& result) {
        simd::log10_lanes<D, L>(v, result);
    }
};

void log10_row(const double* in, double* out, int n) {
    simd::map_doubles<Log10>(in, out, n);
    for (int i = 0; i < n; ++i)
        if (!(in[i] >= std::numeric_limits<double>::min() && in[i] <= std::numeric_limits<double>::max()))
            out[i] = std::log10(in[i]);
}

std::shared_ptr<const PaperLogExposures> paper_log_exposures(const PrintExposure& enlarger,
                                                             const std::array<double, 3>& lo,
                                                             const std::array<double, 3>& hi, int nodes, int threads) {
    const PrintExposure unit = enlarger.at_unit_lights();
    std::string key = unit.fingerprint();
    append_bytes(key, lo.data(), 3), append_bytes(key, hi.data(), 3), append_bytes(key, &nodes, 1);
    return recently_built<PaperLogExposures>(key, [&] {
        // Each axis node's factor of the negative's transmittance, computed once; the x axis's
        // transposed, for the rows of nodes along x in vectors (PrintExposure::expose_row).
        std::array<std::vector<Spectrum>, 3> transmittance;
        for (int a = 0; a < 3 && unit.spectral(); ++a)
            for (int i = 0; i < nodes; ++i)
                transmittance[a].push_back(unit.layer_transmittance(a, Table3D::node_coordinate(lo[a], hi[a], nodes, i)));
        // Each row padded to whole vectors with copies of its last node's.
        const int stride = (nodes + PrintExposure::kRowStride - 1) / PrintExposure::kRowStride * PrintExposure::kRowStride;
        std::vector<float> along_x(size_t(kSpectralSamples) * size_t(stride));
        for (int i = 0; i < stride && unit.spectral(); ++i)
            for (int s = 0; s < kSpectralSamples; ++s)
                along_x[size_t(s) * stride + i] = float(transmittance[0][size_t(std::min(i, nodes - 1))][size_t(s)]);
        auto grid = std::make_shared<PaperLogExposures>();
        grid->nodes = nodes;
        grid->log_h.resize(3 * size_t(nodes) * nodes * nodes);  // (unset: each node is written below)
        parallel_for(0, nodes, threads, [&](int k_begin, int k_end) {
            // A row's exposures, paper layer after layer.
            std::vector<double> h(3 * size_t(stride), 1.0);
            for (int k = k_begin; k < k_end; ++k)
                for (int j = 0; j < nodes; ++j) {
                    if (unit.spectral())
                        unit.expose_row(along_x.data(), stride, transmittance[1][size_t(j)], transmittance[2][size_t(k)],
                                        h.data());
                    else
                        for (int i = 0; i < nodes; ++i) {
                            const double d[3] = {Table3D::node_coordinate(lo[0], hi[0], nodes, i),
                                                 Table3D::node_coordinate(lo[1], hi[1], nodes, j),
                                                 Table3D::node_coordinate(lo[2], hi[2], nodes, k)};
                            double at[3];
                            unit.expose(d, at);
                            for (int l = 0; l < 3; ++l) h[size_t(l * stride + i)] = at[l];
                        }
                    double* const rows = &grid->log_h[grid->rows(j, k)];
                    for (int l = 0; l < 3; ++l)  // (-inf for no light)
                        log10_row(&h[size_t(l) * size_t(stride)], rows + size_t(l) * size_t(nodes), nodes);
                }
        });
        return std::shared_ptr<const PaperLogExposures>(std::move(grid));
    });
}

// The paper's view as a table over its densities (print_view_table), kept for every print
// table of that paper and viewing: the view at each of the print table's nodes took most of
// the table's build. (Its nodes: the error CIEDE2000 max 0.08 at 65, 0.16 at 49.)
constexpr int kPaperViewNodes = 65;

std::shared_ptr<const PrintViewTable> paper_view_table(const Stock& paper, PrintViewing viewing, int threads) {
    std::string key;  // (what PrintView and the grid read: the viewing, the paper's base, dyes and density ranges)
    append_bytes(key, &viewing, 1);
    append_bytes(key, paper.base_density.data(), paper.base_density.size());
    for (const Layer& l : paper.layers) {
        const double range[2] = {l.density_curve.y_min(), l.density_curve.y_max()};
        append_bytes(key, l.dye_density.data(), l.dye_density.size()), append_bytes(key, range, 2);
    }
    return recently_built<PrintViewTable>(key, [&] {
        return std::make_shared<const PrintViewTable>(print_view_table(paper, viewing, kPaperViewNodes, threads));
    });
}

// The one print table of a colour negative on colour paper: the negative's densities -> the
// print's linear Rec.709, held as cube roots (tables.h). Each node is the paper's curves at
// its log exposures (paper_log_exposures, shifted by the lights) viewed through the paper's
// view table, both kept across plans: a plan compiled again for another exposure, grain, MTF
// or halation prints the same table, taken from the last few built; one for other printer
// lights or print exposure (a slider dragged in a host) only develops and views the grid's
// exposures again, and one for other filtration exposes the grid again too.
std::shared_ptr<const Table3D> shared_print_table(const Stock& film, const Stock& paper, const PrintExposure& enlarger,
                                                  int nodes, int threads) {
    std::array<double, 3> lo, hi;
    table_density_range(film, lo, hi);
    std::string key = enlarger.fingerprint();
    append_bytes(key, lo.data(), 3), append_bytes(key, hi.data(), 3), append_bytes(key, &nodes, 1);
    append_view_key(key, paper);  // (what the paper's curves and view read)
    return recently_built<Table3D>(key, [&] {
        const std::shared_ptr<const PaperLogExposures> grid = paper_log_exposures(enlarger, lo, hi, nodes, threads);
        // The view's table stops short of the gamut compression, applied at each node.
        const ViewSettings seen = enlarger.view();
        const std::shared_ptr<const PrintViewTable> view = paper_view_table(paper, seen.viewing, threads);
        double log_light[3];
        for (int j = 0; j < 3; ++j) log_light[j] = std::log10(enlarger.light_lux_s()[size_t(j)]);
        const double log_max = std::log10(kMaxInput), log_min = -30;  // (develop_paper's clamp)
        // A row of nodes at a time: the paper's densities, then their view in vectors.
        return std::make_shared<const Table3D>(Table3D::by_rows(lo, hi, nodes, threads, [&](int j, int k, double* rgb) {
            const double* log_h = &grid->log_h[grid->rows(j, k)];
            // The rows' scratch, per thread: kept from row to row (nodes^2 rows a table).
            thread_local std::vector<double> at, density, linear;
            thread_local std::vector<float> densities, xyz;
            at.resize(size_t(nodes)), density.resize(size_t(nodes)), linear.resize(3 * size_t(nodes));
            densities.resize(3 * size_t(nodes)), xyz.resize(3 * size_t(nodes));
            const float* density_rows[3] = {&densities[0], &densities[size_t(nodes)], &densities[2 * size_t(nodes)]};
            float* xyz_rows[3] = {&xyz[0], &xyz[size_t(nodes)], &xyz[2 * size_t(nodes)]};
            for (int l = 0; l < 3; ++l) {
                for (int i = 0; i < nodes; ++i)
                    at[size_t(i)] = std::clamp(log_light[l] + log_h[size_t(l) * size_t(nodes) + size_t(i)], log_min, log_max);
                paper.layers[size_t(l)].density_curve.row(at.data(), density.data(), nodes);
                for (int i = 0; i < nodes; ++i) densities[size_t(l * nodes + i)] = float(density[size_t(i)]);
            }
            view->xyz.apply_row(density_rows, xyz_rows, nodes);
            double* const linear_rows[3] = {&linear[0], &linear[size_t(nodes)], &linear[2 * size_t(nodes)]};
            const Matrix3& m = view->xyz_to_rgb;  // (multiply's sums, in its order)
            for (int c = 0; c < 3; ++c)
                for (int i = 0; i < nodes; ++i)
                    linear_rows[c][i] = m[size_t(c)][0] * double(xyz_rows[0][i]) + m[size_t(c)][1] * double(xyz_rows[1][i]) +
                                        m[size_t(c)][2] * double(xyz_rows[2][i]);
            if (seen.compress_gamut) compress_to_gamut_row(linear_rows, nodes);
            for (int i = 0; i < nodes; ++i)
                for (int c = 0; c < 3; ++c) rgb[3 * i + c] = linear_rows[c][i];
        }, Table3D::Encoding::cube_root));
    });
}

// The fast tiers' view of a colour reversal film (the print output): its densities -> the
// projected slide's linear Rec.709, PrintView at each node, held as cube roots.
std::shared_ptr<const Table3D> shared_view_table(const Stock& film, const ViewSettings& seen, int nodes, int threads) {
    std::array<double, 3> lo, hi;
    table_density_range(film, lo, hi);
    std::string key = "view ";
    append_bytes(key, &seen.viewing, 1), append_bytes(key, &seen.compress_gamut, 1);
    append_bytes(key, lo.data(), 3), append_bytes(key, hi.data(), 3), append_bytes(key, &nodes, 1);
    append_view_key(key, film);
    return recently_built<Table3D>(key, [&] {
        const PrintView view(film, seen);
        return std::make_shared<const Table3D>(
            lo, hi, nodes, threads, [&](const int*, const double* d, double* rgb) { view.rgb(d, rgb); },
            Table3D::Encoding::cube_root);
    });
}

}  // namespace

void forget_print_tables() { ++kept_generation; }

void print_densities(const PrintExposure& enlarger, const Stock& paper, const double* negative_density,
                     double* paper_density) {
    double h[3];
    enlarger.expose(negative_density, h);
    develop_paper(paper, h, paper_density);
}

int MaterialStages::halo_px() const {
    int r = 0, spread = 0, boolean = 0;
    for (size_t i = 0; i < scatter.size(); ++i) {
        const int layer_spread = scatter[i].radius + (halation[i] ? halation[i]->radius : 0);
        const int layer_boolean = boolean_grain[i] ? boolean_grain[i]->halo_px : 0;
        r = std::max(r, layer_spread + layer_boolean);
        spread = std::max(spread, layer_spread), boolean = std::max(boolean, layer_boolean);
    }
    // The couplers develop every layer on the union of their windows, and spread the inhibitor.
    return couplers ? spread + boolean + couplers->radius() : r;
}

Window MaterialStages::developed_window(size_t layer, const Window& out, const Window& frame) const {
    return boolean_grain[layer] ? out.grown(boolean_grain[layer]->halo_px).intersected(frame) : out;
}

namespace {

Window united(const Window& a, const Window& b) {
    return Window{std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
}

}  // namespace

Window MaterialStages::layers_developed_window(const Window& out, const Window& frame) const {
    Window all = out;
    for (size_t i = 0; i < boolean_grain.size(); ++i) all = united(all, developed_window(i, out, frame));
    return all;
}

Window MaterialStages::input_window(const Window& out, const Window& frame) const {
    // With couplers every layer is exposed onto the layers' developed windows together, grown
    // by the inhibitor's reach (inhibited_exposure).
    const std::optional<Window> coupled =
        couplers ? std::optional(layers_developed_window(out, frame).grown(couplers->radius()).intersected(frame))
                 : std::nullopt;
    Window needed = out;
    for (size_t i = 0; i < scatter.size(); ++i) {
        Window w = scatter_input_window(scatter[i], coupled ? *coupled : developed_window(i, out, frame), frame);
        if (halation[i]) w = w.grown(halation[i]->radius).intersected(frame);
        needed = united(needed, w);
    }
    return needed;
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
                   const FrameGeometry& frame, int threads, const PlanStructure& structure) {
    const Window image = image_window(frame);
    const int factor = proxy_factor(quality_tier(settings.quality), frame);
    if (factor == 1) return compile_pixels(film, paper, settings, frame, threads, structure);
    // The proxy's film and print widths are its pixels' (a frame whose width is no multiple
    // of the factor has part of a block past its edge), so its pitch is exactly `factor`
    // times the frame's.
    const FrameGeometry proxy = proxy_geometry(frame, factor);
    const double widen = double(proxy.film_width_px()) * factor / frame.film_width_px();
    DevelopSettings at_proxy = settings;
    at_proxy.frame_width_mm = (settings.frame_width_mm > 0 ? settings.frame_width_mm : film.frame_width_mm) * widen;
    if (paper) at_proxy.print_width_mm = (settings.print_width_mm > 0 ? settings.print_width_mm : paper->frame_width_mm) * widen;
    Plan p = compile_pixels(film, paper, at_proxy, proxy, threads, structure, factor);
    p.proxy_ = std::make_shared<const Plan>(p);
    p.proxy_factor_ = factor;
    p.settings_ = settings;
    p.frame_ = image;
    p.film_width_px_ = frame.film_width_px();
    return p;
}

Plan Plan::compile_pixels(const Stock& film, const Stock* paper, const DevelopSettings& settings,
                          const FrameGeometry& frame, int threads, const PlanStructure& structure, int proxy_factor) {
    const Window image = image_window(frame);
    if (!is_camera_film(film.kind))
        throw std::invalid_argument("'" + film.id + "' is not a film stock (it is a paper or print film)");
    if (paper && is_camera_film(paper->kind))
        throw std::invalid_argument("'" + paper->id + "' is a camera film, not a paper or print film");
    // A reversal film's print is the film itself, projected: no paper.
    const bool views_film = settings.output == OutputMode::print && film.kind == StockKind::reversal;
    if (settings.output == OutputMode::print && !paper && !views_film)
        throw std::invalid_argument("print output needs a paper (or choose the negative, density, scan or texture output)");
    validate(settings);

    Plan p;
    p.settings_ = settings;
    p.structure_ = structure;
    p.frame_ = image;
    p.film_width_px_ = frame.film_width_px();
    p.monochrome_ = frame.monochrome;
    const QualityTier& tier = quality_tier(settings.quality);
    const bool printing = settings.output == OutputMode::print && !views_film;
    p.views_film_ = views_film;
    const bool one_print_table =
        printing && tier.print_table_nodes > 0 && film.is_colour() && paper->is_colour();
    const double film_width_mm = settings.frame_width_mm > 0 ? settings.frame_width_mm : film.frame_width_mm;
    const double print_width_mm =
        !printing ? 0.0 : settings.print_width_mm > 0 ? settings.print_width_mm : paper->frame_width_mm;
    auto film_stages = std::make_shared<MaterialStages>(build_stages(
        film, film_width_mm, p.film_width_px_, frame.height, settings, structure, 0, "film", proxy_factor, p.skipped_,
        threads));
    auto paper_stages = std::make_shared<MaterialStages>();
    p.monochrome_input_ = frame.monochrome && structure.skip_noop_stages;
    if (p.monochrome_input_ && settings.output != OutputMode::texture)
        p.skipped_.push_back("spectral sensitivity: the input is grey, so each layer's exposure is one scale of it");
    p.film_exposure_scale_ = settings.input_units == InputUnits::lux_seconds
                                 ? 1.0
                                 : mid_grey_exposure_lux_s(film.iso_speed) / 0.18 * std::exp2(settings.exposure_ev);

    for (size_t l = 0; l < film.layers.size(); ++l)
        p.scan_base_density_[l] = scan_base_density(film, l, settings.scan_balance, settings.scan_aim_code);
    if (printing) {
        *paper_stages = build_stages(*paper, print_width_mm, p.film_width_px_, frame.height, settings, structure, 16,
                                     "paper", proxy_factor, p.skipped_, threads);
        p.print_ = PrintExposure::design(film, *paper,
                                         {mid_grey_exposure_lux_s(film.iso_speed), settings.printer_lights,
                                          settings.filtration_ymc, settings.print_exposure_ev, view_settings(settings)});
        if (one_print_table) {
            // The table is built on a thread of its own while the paper's grain is folded into
            // the film's: a print edit's table fills the core the fold leaves idle (its halves of
            // the grey levels take unequal times, and it has serial steps). Neither reads what
            // the other writes; the future waits for the table even where the fold throws. A
            // plan compiled on one thread builds it after the fold, on that thread.
            const auto when = resolve_thread_count(threads) > 1 ? std::launch::async : std::launch::deferred;
            std::future<std::shared_ptr<const Table3D>> table = std::async(when, [&] {
                return shared_print_table(film, *paper, *p.print_, tier.print_table_nodes, threads);
            });
            fold_paper_grain(*film_stages, *paper_stages, *p.print_, p.film_exposure_scale_, tier.curve_table_bits,
                             threads);
            leave_out_paper_grain(*paper_stages, *film_stages, p.skipped_);
            p.print_table_ = table.get();
        }
    } else if (views_film) {
        if (tier.print_table_nodes > 0 && film.is_colour())
            p.print_table_ = shared_view_table(film, view_settings(settings), tier.print_table_nodes, threads);
        if (paper) p.skipped_.push_back("print (" + paper->id + "): a reversal film is its own picture, projected");
    } else if (paper) {
        p.skipped_.push_back("print: the output stops at the negative");
    }
    p.film_stages_ = std::move(film_stages);
    p.paper_stages_ = std::move(paper_stages);
    return p;
}

double scan_base_density(const Stock& film, size_t layer, bool balance, double aim_code) {
    const Curve& curve = film.layers[layer].density_curve;
    if (!balance) return curve.y_min();
    return curve(std::log10(mid_grey_exposure_lux_s(film.iso_speed))) - (aim_code - kScanBaseCode) * kScanDensityPerCode;
}

Plan Plan::in_image(const FrameGeometry& image) const {
    if (image.film_width_px() != film_width_px_ || image.monochrome != monochrome_ ||
        (proxy_ && proxy_factor(quality_tier(settings_.quality), image) != proxy_factor_))
        throw std::invalid_argument(
            "Plan::in_image: another film frame width, proxy factor or channel count needs its own plan");
    Plan p = *this;
    p.frame_ = image_window(image);
    if (proxy_) p.proxy_ = std::make_shared<const Plan>(proxy_->in_image(proxy_geometry(image, proxy_factor_)));
    return p;
}

Plan Plan::for_frame(int frame) const {
    Plan p = *this;
    p.settings_.frame = frame;
    for (std::shared_ptr<const MaterialStages>* stages : {&p.film_stages_, &p.paper_stages_}) {
        auto m = std::make_shared<MaterialStages>(**stages);
        for (auto& g : m->grain) {
            if (!g) continue;
            g->key.frame = frame;
            for (GrainModel::NoiseTerm& term : g->mixed_noise) term.key.frame = frame;  // (the film layers' keys)
        }
        for (auto& g : m->boolean_grain)
            if (g) g->key.frame = frame;
        *stages = std::move(m);
    }
    if (proxy_) p.proxy_ = std::make_shared<const Plan>(proxy_->for_frame(frame));
    return p;
}

int Plan::halo_px() const {
    const int own = film_stages_->halo_px() + (print_ ? paper_stages_->halo_px() : 0);
    // (A proxy's halo in its pixels, its interpolation's pixel, and a block's rounding.)
    return proxy_ ? proxy_factor_ * (own + 1) + proxy_factor_ - 1 : own;
}

Window Plan::input_window(const Window& output) const {
    if (proxy_) {
        const Window proxy_in = proxy_->input_window(proxy_window(output));
        const int n = proxy_factor_;
        return Window{n * proxy_in.x0, n * proxy_in.y0, n * proxy_in.x1, n * proxy_in.y1}.intersected(frame_);
    }
    return film_stages_->input_window(film_output_window(output), frame_);
}

Window Plan::film_output_window(const Window& output) const {
    return print_ ? paper_stages_->input_window(output, frame_) : output;
}

std::vector<Plane> Plan::develop_film(const ConstImageView& in, const Window& film_out, int threads,
                                      StageTimes* times) const {
    const Window film_in = film_stages_->input_window(film_out, frame_);
    std::vector<Plane> exposure;
    StageTimer expose_timer(times, "expose");
    const auto& weights = film_stages_->rgb_weights;
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
    return develop_material(*film_stages_, std::move(exposure), film_out, frame_, threads, times);
}

std::vector<Plane> Plan::print(std::vector<Plane> negative, const Window& out, int threads,
                               StageTimes* times) const {
    if (print_table_) {
        // The paper's MTF on the negative's densities, layer i's kernel on film layer i (the
        // paper layer its dye mostly prints on: cyan dye modulates the red light).
        if (paper_stages_->halo_px() > 0) {
            StageTimer timer(times, "scatter");
            for (size_t l = 0; l < negative.size(); ++l) {
                Plane spread = Plane::unset(out);
                scatter(negative[l], spread, paper_stages_->scatter[l], frame_, threads);
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
        develop_material(*paper_stages_, std::move(paper_exposure), out, frame_, threads, times);
    StageTimer view_timer(times, "view");
    const PrintView view(paper_stages_->stock, enlarger.view());
    return per_pixel(paper_density, out, 3, threads, [&](const double* d, double* rgb) { view.rgb(d, rgb); });
}

namespace {

// A layer's developed density at one exposure, as develop_material computes it per pixel
// (with couplers, in a uniform grey field: every layer at that exposure).
double developed_density(const MaterialStages& m, size_t layer, double exposure_lux_s) {
    if (m.couplers) {
        float h[3], n[3], *rows[3] = {&h[0], &h[1], &h[2]};
        const float* spread[3] = {&n[0], &n[1], &n[2]};
        for (size_t l = 0; l < 3; ++l) h[l] = float(std::clamp(exposure_lux_s, 0.0, kMaxInput));
        for (size_t l = 0; l < 3; ++l) coupler_donor_row(*m.couplers, l, &h[l], &n[l], 1);
        inhibit_rows(*m.couplers, rows, spread, 1);
        exposure_lux_s = h[layer];
    }
    if (!m.curve_tables.empty()) return m.curve_tables[layer](float(exposure_lux_s));
    return m.develop_curve(layer)(std::log10(std::max(exposure_lux_s, 1e-30)));
}

}  // namespace

void Plan::view_film_row(const float* const* density, float* const* rgb, int width) const {
    if (print_table_) {
        print_table_->apply_row(density, rgb, width);
        return;
    }
    const Stock& film = film_stages_->stock;
    const PrintView view(film, view_settings(settings_));
    double d[3], out[3];
    for (int x = 0; x < width; ++x) {
        for (size_t l = 0; l < film.layers.size(); ++l) d[l] = density[l][x];
        view.rgb(d, out);
        for (int c = 0; c < 3; ++c) rgb[c][x] = float(out[c]);
    }
}

const Stock& Plan::film() const { return film_stages_->stock; }

std::array<double, 3> Plan::film_exposure_weights(size_t layer) const {
    std::array<double, 3> w = film_stages_->rgb_weights[layer];
    for (double& v : w) v *= film_exposure_scale_;
    return w;
}

double Plan::film_density(size_t layer, double exposure_lux_s) const {
    return developed_density(*film_stages_, layer, exposure_lux_s);
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
    if (views_film_) {
        PrintView(film_stages_->stock, view_settings(settings_)).rgb(density, result);
        return;
    }
    if (print_) {
        double h[3], paper_density[3];
        print_->expose(density, h);
        for (int j = 0; j < print_->paper_layers(); ++j)
            paper_density[j] = developed_density(*paper_stages_, size_t(j), std::clamp(h[j], 0.0, kMaxInput));
        PrintView(paper_stages_->stock, print_->view()).rgb(paper_density, result);
        return;
    }
    const size_t layers = film_stages_->stock.layers.size();
    for (size_t c = 0; c < 3; ++c) {
        const size_t l = std::min(c, layers - 1);  // (a single layer serves all three)
        float v = float(density[l]);
        convert_row(settings_.output, scan_base_density_[l], &v, 1);
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
    const MaterialStages& m = *film_stages_;
    const Window film_in = m.input_window(out, frame_);
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
        // (Its magnitude: a reversal film's curve falls, and the grain's sign is random.)
        double gamma = std::max(0.05, std::abs(curve(mid_grey_log_h + 0.5) - curve(mid_grey_log_h - 0.5)));
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

    if (proxy_) {
        run_proxy(in, out, out_window, threads, times);
        return;
    }
    if (runs_in_one_pass()) {
        run_one_pass(in, out, out_window, threads, times);
        return;
    }
    std::vector<Plane> result;
    if (settings_.output == OutputMode::texture) {
        result = texture(in, out_window, threads, times);
    } else if (print_) {
        result = print(develop_film(in, film_output_window(out_window), threads, times), out_window, threads, times);
    } else if (views_film_) {
        const std::vector<Plane> density = develop_film(in, out_window, threads, times);
        StageTimer timer(times, "view");
        result = per_row(density, out_window, 3, threads,
                         [&](const float* const* d, float* const* rgb, int width) { view_film_row(d, rgb, width); });
    } else {
        result = develop_film(in, out_window, threads, times);
        StageTimer timer(times, "convert");
        for (size_t l = 0; l < result.size(); ++l)
            convert_row(settings_.output, scan_base_density_[l], result[l].pixels.data(),
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
    for (const MaterialStages* m : {film_stages_.get(), paper_stages_.get()})
        for (const auto& g : m->boolean_grain)
            if (g) grains += g->grains_per_pixel_at(1.0);
    return grains;
}

double Plan::silver_grains_drawn(const Window& output) const {
    double grains = 0;
    auto add = [&](const MaterialStages* m, const Window& out) {
        if (!m) return;
        for (size_t i = 0; i < m->boolean_grain.size(); ++i)
            if (const auto& g = m->boolean_grain[i]) {
                // Its cells reach the footprint's width beyond the developed window.
                const int footprint_px = int(std::ceil(g->footprint_reach_um / g->pixel_pitch_um));
                const Window rendered = m->developed_window(i, out, frame_).grown(footprint_px);
                grains += g->grains_per_pixel_at(1.0) * double(rendered.pixel_count());
            }
    };
    if (print_) add(paper_stages_.get(), output);
    add(film_stages_.get(), film_output_window(output));
    return grains;
}

double reference_cpu_seconds(const Plan& plan, const Window& out) {
    return plan.silver_grains_drawn(out) * kReferenceCpuSecondsPerSilverGrain;
}

std::string check_reference_render_budget(const Plan& plan, const Window& out, const std::string& quality_setting) {
    const double grains = plan.silver_grains_drawn(out);
    const double cpu_seconds = grains * kReferenceCpuSecondsPerSilverGrain;
    if (cpu_seconds < kReferenceWarningCpuSeconds) return {};
    std::ostringstream message;
    message.precision(2);
    message << quality_setting << "reference draws every silver grain: about " << grains << " for the window "
            << out.x0 << "," << out.y0 << "," << out.width() << "," << out.height() << " ("
            << plan.silver_grains_per_pixel() << " a pixel), roughly " << std::fixed << std::setprecision(1)
            << cpu_seconds / 3600 << " CPU hours";
    if (cpu_seconds > kReferenceCpuBudgetSeconds)
        throw std::invalid_argument(message.str() + ", over its budget of " +
                                    std::to_string(int(kReferenceCpuBudgetSeconds / 3600)) +
                                    " CPU hours; render a smaller window or " + quality_setting +
                                    "high, which gives the same grain statistics as filtered noise");
    message << "; " << quality_setting << "high gives the same grain statistics as filtered noise";
    return message.str();
}

std::vector<std::string> Plan::describe() const {
    std::vector<std::string> lines;
    if (proxy_) {
        const Window& proxy = proxy_->frame_;
        const std::string n = std::to_string(proxy_factor_);
        lines.push_back("proxy: the frame at 1/" + n + " of its resolution (" + std::to_string(proxy.width()) + "x" +
                        std::to_string(proxy.height()) + " px, " + n + " times the pixel pitch), each pixel the mean of a " +
                        n + "x" + n + " block; its result upsampled bilinearly");
        for (const std::string& line : proxy_->describe()) lines.push_back(line);
        return lines;
    }
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
                            fmt(l.density_curve.y_max()) +
                            (m.couplers ? ", through the curve before the DIR couplers' inhibition" : ""));
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
                        fmt(film_stages_->stock.iso_speed) + ", " + fmt(settings_.exposure_ev) + " EV)");
    material(*film_stages_, "film", settings_.output != OutputMode::texture);
    if (const auto& c = film_stages_->couplers) {
        std::string rows;
        for (int i = 0; i < 3; ++i)
            rows += std::string(i ? "; " : "") + fmt(c->matrix[3 * i]) + " " + fmt(c->matrix[3 * i + 1]) + " " +
                    fmt(c->matrix[3 * i + 2]);
        lines.push_back("  DIR couplers: log H lowered by M x net density (rows R, G, B: " + rows +
                        "), the inhibitor spread " + std::to_string(c->radius()) + " px" +
                        (c->spread.decimation > 1
                             ? ", on a " + std::to_string(c->spread.decimation) + "x coarser grid"
                             : std::string()));
    }
    switch (settings_.output) {
        case OutputMode::print: {
            if (views_film_) {
                if (print_table_)
                    lines.push_back("print: one table of " + std::to_string(print_table_->nodes()) +
                                    " nodes per axis from the film's densities to the projected slide's colour");
                lines.push_back("convert: the reversal film's spectral transmittance -> linear Rec.709 under D65 "
                                "(the film is the picture; no paper)");
                break;
            }
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
            material(*paper_stages_, "paper", false);
            lines.push_back(std::string("convert: print density -> linear Rec.709 under D65, ") +
                            (e.view().viewing == PrintViewing::media_relative
                                 ? "adapted to the print's white, mid grey at 0.18"
                                 : "absolute") +
                            (e.view().compress_gamut ? ", gamut compressed" : ""));
            break;
        }
        case OutputMode::negative: lines.push_back("convert: density -> transmittance"); break;
        case OutputMode::density: lines.push_back("convert: none (diffuse density written)"); break;
        case OutputMode::scan:
            lines.push_back("convert: density -> Cineon log code values / 1023" +
                            (settings_.scan_balance ? ", mid grey at code " + fmt(settings_.scan_aim_code)
                                                    : std::string(", base+fog at code 95")));
            break;
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
