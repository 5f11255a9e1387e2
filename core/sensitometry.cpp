#include "core/sensitometry.h"

#include <cmath>
#include <complex>

#include "core/develop.h"
#include "core/stages/scatter.h"

namespace darkroom {

namespace {

// The pipeline runs films; a paper is measured by running it as the one material of a
// density-output plan (its curve is already anchored to its own speed definition).
Stock as_measured_material(const Stock& stock, size_t layer) {
    Stock s = stock;
    s.kind = stock.kind == StockKind::reversal ? StockKind::reversal : StockKind::negative;
    s.layers = {stock.layers[layer]};
    return s;
}

// Develops a lux-seconds image through a one-layer material and returns its density.
Image develop_density(const Stock& material, const Image& exposure, double pitch_um, bool grain, bool mtf,
                      const SensitometryOptions& o) {
    DevelopSettings s;
    s.quality = Quality::high;  // the model as defined: per-pixel curves, the PSF to 1e-6
    s.output = OutputMode::density;
    s.input_units = InputUnits::lux_seconds;
    s.grain = grain;
    s.mtf = mtf;
    s.seed = o.seed;
    s.frame_width_mm = pitch_um * exposure.window.width() / 1000.0;
    Plan plan = Plan::compile(material, nullptr, s, {exposure.window.width(), exposure.window.height()}, o.threads);
    Image out(exposure.window, 3);
    plan.run(exposure.view(), out.view(), o.threads);
    return out;
}

// Where the curve reaches a density (a reversal film's falls to it).
double log_h_at_density(const Curve& curve, double density, StockKind kind) {
    double at;
    const bool found = density_falls_with_exposure(kind) ? curve.first_x_down_to(density, &at)
                                                        : curve.first_x_at(density, &at);
    return found ? at : curve.x_max();
}

}  // namespace

std::vector<GreyPatch> print_grey_scale(const Stock& film, const Stock& paper, const DevelopSettings& settings,
                                        const std::vector<double>& evs) {
    DevelopSettings s = settings;
    s.quality = Quality::reference;
    s.output = OutputMode::print;
    s.input_units = InputUnits::scene_linear;
    s.grain = s.mtf = false;
    s.halation = 0;
    const Plan plan = Plan::compile(film, &paper, s, {1, 1}, 1);
    const Xyz white = linear_srgb_to_xyz({1.0, 1.0, 1.0});
    std::vector<GreyPatch> patches;
    for (double ev : evs) {
        const double scene = 0.18 * std::exp2(ev);
        double density[3];
        for (size_t l = 0; l < film.layers.size(); ++l) {
            const std::array<double, 3> w = plan.film_exposure_weights(l);
            density[l] = plan.film_density(l, (w[0] + w[1] + w[2]) * scene);
        }
        GreyPatch patch;
        patch.ev = ev;
        plan.result_of_negative(density, patch.print.data());
        const Lab lab = xyz_to_lab(linear_srgb_to_xyz(patch.print), white);
        patch.chroma = std::hypot(lab[1], lab[2]);
        patches.push_back(patch);
    }
    return patches;
}

bool Measurement::passes() const {
    double allowed = relative ? tolerance * std::abs(declared) : tolerance;
    return std::abs(measured - declared) <= allowed;
}

double curve_gamma(const std::vector<double>& x, const std::vector<double>& y) {
    double best = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        double sx = 0, sy = 0, sxx = 0, sxy = 0;
        int n = 0;
        for (size_t j = i; j < x.size() && x[j] <= x[i] + 1.0 + 1e-9; ++j, ++n) {
            sx += x[j], sy += y[j], sxx += x[j] * x[j], sxy += x[j] * y[j];
        }
        if (n < 3 || x[i + n - 1] - x[i] < 0.99) continue;
        best = std::max(best, std::abs((n * sxy - sx * sy) / (n * sxx - sx * sx)));  // (a reversal film falls)
    }
    return best;
}

double mtf50_cycles_per_mm(const Curve& mtf) {
    for (size_t i = 1; i < mtf.x.size(); ++i)
        if (mtf.y[i] <= 0.5 && mtf.y[i - 1] > 0.5)
            return mtf.x[i - 1] + (mtf.y[i - 1] - 0.5) / (mtf.y[i - 1] - mtf.y[i]) * (mtf.x[i] - mtf.x[i - 1]);
    // Still above 0.5 at the last sample: where the model's extrapolation (the one the
    // scatter stage uses) falls to 0.5.
    double lo = mtf.x_max(), hi = lo;
    while (mtf_response(mtf, hi) > 0.5 && hi < 1e5) hi *= 2;
    for (int i = 0; i < 100; ++i) {
        double mid = 0.5 * (lo + hi);
        (mtf_response(mtf, mid) > 0.5 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

SensitometryReport measure_stock(const Stock& stock, const SensitometryOptions& o) {
    SensitometryReport report;
    report.stock_id = stock.id;
    const SpeedDefinition speed = speed_definition(stock.kind);
    for (size_t li = 0; li < stock.layers.size(); ++li) {
        const Layer& layer = stock.layers[li];
        const Stock material = as_measured_material(stock, li);
        const std::string prefix = stock.layers.size() > 1 ? layer.name + " " : "";

        // Step wedge: patches 0.05 log H apart across the whole curve, 16 px square at 5 um.
        const double step = 0.05, lo = layer.density_curve.x_min() - 0.5, hi = layer.density_curve.x_max() + 0.5;
        const int patches = int((hi - lo) / step) + 1, patch_px = 16;
        Image wedge(patches * patch_px, patch_px, 3);
        for (int p = 0; p < patches; ++p)
            for (int y = 0; y < patch_px; ++y)
                for (int x = 0; x < patch_px; ++x)
                    for (int c = 0; c < 3; ++c) wedge.at(p * patch_px + x, y)[c] = float(std::pow(10.0, lo + p * step));
        Image wedge_d = develop_density(material, wedge, 5.0, false, true, o);
        std::vector<double> log_h, density;
        for (int p = 0; p < patches; ++p) {
            log_h.push_back(lo + p * step);
            density.push_back(wedge_d.at(p * patch_px + patch_px / 2, patch_px / 2)[0]);
        }
        const Curve measured = make_curve(log_h, density, "measured wedge");
        // (A reversal film's D-min is at the wedge's bright end, its D-max at the dark end.)
        const double fog = measured.y_min(), d_max = measured.y_max();
        auto speed_point = [&](const Curve& c) {
            double at;
            return curve_speed_point_log_h(c, stock.kind, &at) ? at : c.x_max();
        };
        const double hm_log = speed_point(measured), hm_declared = speed_point(layer.density_curve);
        auto add = [&](std::string name, std::string unit, double declared, double value, double tol, bool rel) {
            report.measurements.push_back({prefix + name, unit, declared, value, tol, rel});
        };
        add("ISO speed", "", speed.k / std::pow(10.0, hm_declared), speed.k / std::pow(10.0, hm_log),
            std::exp2(1.0 / 3.0) - 1.0, true);
        add("contrast (gamma)", "", curve_gamma(layer.density_curve.x, layer.density_curve.y),
            curve_gamma(log_h, density), 0.05, true);
        add("Dmin", "D", layer.density_curve.y_min(), fog, 0.02, false);
        add("Dmax", "D", layer.density_curve.y_max(), d_max, 0.02, false);

        // RMS granularity: a uniform patch at net density 1.0, 2 um pixels, read through
        // non-overlapping 48 um apertures in transmittance (as a microdensitometer does).
        const double pitch_um = 2.0, net = 1.0;
        if (layer.grain.rms_granularity > 0 && layer.density_curve.y_max() > fog + net) {
            const int side = 1536, aperture_px = int(48.0 / pitch_um);
            const double h = std::pow(10.0, log_h_at_density(layer.density_curve, layer.density_curve.y_min() + net,
                                                             stock.kind));
            Image patch(side, side, 3, float(h));
            Image d = develop_density(material, patch, pitch_um, true, false, o);
            const double radius = 24.0 / pitch_um;
            std::vector<double> readings;
            for (int cy = aperture_px / 2; cy + aperture_px / 2 < side; cy += aperture_px)
                for (int cx = aperture_px / 2; cx + aperture_px / 2 < side; cx += aperture_px) {
                    double sum_t = 0;
                    int n = 0;
                    for (int y = cy - aperture_px / 2; y <= cy + aperture_px / 2; ++y)
                        for (int x = cx - aperture_px / 2; x <= cx + aperture_px / 2; ++x)
                            if (std::hypot(x - cx, y - cy) <= radius) sum_t += std::pow(10.0, -d.at(x, y)[0]), ++n;
                    readings.push_back(-std::log10(sum_t / n));
                }
            double mean = 0, var = 0;
            for (double r : readings) mean += r / readings.size();
            for (double r : readings) var += (r - mean) * (r - mean) / (readings.size() - 1);
            add("RMS granularity (48 um, D 1.0)", "D", layer.grain.rms_granularity, std::sqrt(var), 0.10, true);
        }

        // MTF: sine-modulated exposure around mid-scale, read back through the inverse
        // H&D curve (effective exposure); the response is the modulation ratio. Pixels are
        // fine enough that Nyquist is four times the declared MTF50, so aliasing is negligible.
        const double mid_log_h = log_h_at_density(layer.density_curve, 0.5 * (fog + d_max), stock.kind);
        const int width = 2048, rows = 1;
        const double declared_mtf50 = mtf50_cycles_per_mm(layer.mtf);
        const double sine_pitch_um = 1000.0 / (8.0 * declared_mtf50);
        auto response_at = [&](double f) {
            Image target(width, rows, 3);
            const double modulation = 0.1, h0 = std::pow(10.0, mid_log_h);
            for (int x = 0; x < width; ++x) {
                double v = h0 * (1.0 + modulation * std::sin(2 * M_PI * f * (x + 0.5) * sine_pitch_um / 1000.0));
                for (int c = 0; c < 3; ++c) target.at(x, 0)[c] = float(v);
            }
            Image d = develop_density(material, target, sine_pitch_um, false, true, o);
            // Whole periods in the middle half, away from the clamped edges.
            int period_count = std::max(1, int(std::floor(f * (width / 2) * sine_pitch_um / 1000.0)));
            int n = int(std::lround(period_count * 1000.0 / (f * sine_pitch_um)));
            int x0 = width / 4;
            std::complex<double> acc = 0;
            double mean = 0;
            for (int x = x0; x < x0 + n; ++x) mean += std::pow(10.0, log_h_at_density(layer.density_curve, d.at(x, 0)[0], stock.kind)) / n;
            for (int x = x0; x < x0 + n; ++x) {
                double e = std::pow(10.0, log_h_at_density(layer.density_curve, d.at(x, 0)[0], stock.kind)) - mean;
                acc += e * std::polar(1.0, -2 * M_PI * f * (x + 0.5) * sine_pitch_um / 1000.0);
            }
            return 2.0 * std::abs(acc) / n / (modulation * mean);
        };
        double f_lo = 0.5 * declared_mtf50, f_hi = 2.0 * declared_mtf50;
        for (int i = 0; i < 12; ++i) {
            double mid = std::sqrt(f_lo * f_hi);
            (response_at(mid) > 0.5 ? f_lo : f_hi) = mid;
        }
        add("MTF50", "cycles/mm", declared_mtf50, std::sqrt(f_lo * f_hi), 0.10, true);
    }
    return report;
}

}  // namespace darkroom
