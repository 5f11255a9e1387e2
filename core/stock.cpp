#include "core/stock.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/builtin_stock_data.h"
#include "core/did_you_mean.h"
#include "core/json_file.h"
#include "core/stock_json.h"

namespace darkroom {

using nlohmann::json;
using stock_json::FieldReader;

SpeedDefinition speed_definition(StockKind kind) {
    switch (kind) {
        case StockKind::negative: return {0.8, 0.1};
        case StockKind::reversal: return {10.0, 0.2, 2.0};
        case StockKind::paper:
        case StockKind::print_film: break;
    }
    return {1000.0, 0.6};
}

bool curve_speed_point_log_h(const Curve& curve, StockKind kind, double* log_hm) {
    const SpeedDefinition sd = speed_definition(kind);
    const double d_min = curve.y_min();
    if (!density_falls_with_exposure(kind)) return curve.first_x_at(d_min + sd.density_over_fog, log_hm);
    // The highlight point (little density, much exposure) and the shadow point.
    double highlight, shadow;
    if (!curve.first_x_down_to(d_min + sd.density_over_fog, &highlight) ||
        !curve.first_x_down_to(d_min + sd.shadow_density_over_fog, &shadow))
        return false;
    *log_hm = 0.5 * (highlight + shadow);
    return true;
}

double mid_grey_exposure_lux_s(double iso_speed) { return 0.65 * 12.5 / iso_speed; }

double speed_point_log_h(const Stock& stock) {
    return std::log10(speed_definition(stock.kind).k / stock.iso_speed);
}

namespace {

using stock_json::kHuge;
using stock_json::kMaxDensity;
using stock_json::kMaxDirCoupling;
using stock_json::kMaxDirDiffusionUm;
using stock_json::kMaxIsoSpeed;
using stock_json::kMaxGrainSizeUm;
using stock_json::kMaxHalationRadiusUm;
using stock_json::kMinDensityRise;
using stock_json::kMinIsoSpeed;

// A density curve may not fall by more than this between samples (rounding in a sampled
// analytic curve, e.g. a written parametric one, stays far below it).
constexpr double kFallTolerance = 1e-9;

Curve read_curve(const FieldReader& r, const json& obj, const char* x_key, const char* y_key, double y_min,
                 double y_max) {
    auto xs = r.at(x_key).numbers(r.field(obj, x_key), -kHuge, kHuge);
    auto ys = r.at(y_key).numbers(r.field(obj, y_key), y_min, y_max);
    if (xs.size() != ys.size())
        r.fail("'" + std::string(x_key) + "' has " + std::to_string(xs.size()) + " values but '" + y_key + "' has " +
               std::to_string(ys.size()));
    try {
        return make_curve(xs, ys, r.path());
    } catch (const std::invalid_argument& e) {
        r.fail(e.what());
    }
}

// The named illuminants a stock may be balanced for: "D50", "D55", "D65", "A", "<K>K".
Spectrum read_illuminant(const FieldReader& r, const std::string& name) {
    if (name == "D50") return illuminant_d50();
    if (name == "D55") return illuminant_d55();
    if (name == "D65") return illuminant_d65();
    if (name == "A") return illuminant_a();
    if (name.size() > 1 && name.back() == 'K') {
        try {
            size_t used = 0;
            double kelvin = std::stod(name.substr(0, name.size() - 1), &used);
            if (used == name.size() - 1 && kelvin >= 1000 && kelvin <= 25000) return blackbody(kelvin);
        } catch (const std::exception&) {
        }
    }
    r.fail("unknown illuminant '" + name + "' (known: D50, D55, D65, A, or a blackbody such as 3200K in 1000-25000 K)");
}

// A spectral function (docs/reference/stocks.md): a sum of Gaussians plus a constant,
// or a table (linear or log10 values, linearly interpolated, 0 outside its wavelengths),
// or for black-and-white sensitivities an emulsion class. Tables on any wavelength grid
// are resampled onto the model's 380-780 nm grid.
Spectrum read_spectrum(const FieldReader& r, const json& v, bool allow_emulsion) {
    if (!v.is_object()) r.fail("expected an object");
    if (v.contains("emulsion")) {
        if (!allow_emulsion) r.at("emulsion").fail("an emulsion class only describes a sensitivity");
        std::string type = r.at("emulsion").text(v["emulsion"]);
        if (type == "panchromatic") return emulsion_sensitivity(Emulsion::panchromatic);
        if (type == "orthochromatic") return emulsion_sensitivity(Emulsion::orthochromatic);
        if (type == "blue-sensitive") return emulsion_sensitivity(Emulsion::blue_sensitive);
        r.at("emulsion").fail("unknown emulsion '" + type + "' (known: panchromatic, orthochromatic, blue-sensitive)");
    }
    if (v.contains("gaussians")) {
        double constant = v.contains("constant") ? r.at("constant").number(v["constant"], -10.0, 10.0) : 0.0;
        Spectrum s = flat_spectrum(constant);
        FieldReader rg = r.at("gaussians");
        const json& list = v["gaussians"];
        if (!list.is_array() || list.empty()) rg.fail("expected a non-empty array of {nm, sigma_nm, weight}");
        for (size_t k = 0; k < list.size(); ++k) {
            FieldReader rk = rg.at(k);
            double nm = rk.at("nm").number(rk.field(list[k], "nm"), 100.0, 1500.0);
            double sigma = rk.at("sigma_nm").number(rk.field(list[k], "sigma_nm"), 0.1, 1000.0);
            double weight = rk.at("weight").number(rk.field(list[k], "weight"), -100.0, 100.0);
            for (int i = 0; i < kSpectralSamples; ++i) {
                double u = (wavelength_nm(i) - nm) / sigma;
                s[i] += weight * std::exp(-0.5 * u * u);
            }
        }
        return s;
    }
    auto nm = r.at("nm").numbers(r.field(v, "nm"), 100.0, 1500.0);
    const char* key = v.contains("log10_sensitivity") ? "log10_sensitivity" : v.contains("relative") ? "relative" : "values";
    bool is_log = std::string(key) == "log10_sensitivity";
    auto values = r.at(key).numbers(r.field(v, key), is_log ? -stock_json::kMaxLog10Sensitivity : -kHuge,
                                    is_log ? stock_json::kMaxLog10Sensitivity : kHuge);
    if (nm.size() != values.size())
        r.fail("'nm' has " + std::to_string(nm.size()) + " values but '" + key + "' has " +
               std::to_string(values.size()));
    for (double& x : values) x = is_log ? std::pow(10.0, x) : x;
    Curve c;
    try {
        c = make_curve(nm, values, r.path());
    } catch (const std::invalid_argument& e) {
        r.fail(e.what());
    }
    if (c.x_max() < kWavelengthMinNm || c.x_min() > kWavelengthMaxNm)
        r.fail("the wavelengths do not overlap the 380-780 nm grid");
    Spectrum s{};
    for (int i = 0; i < kSpectralSamples; ++i) {
        double nm_i = wavelength_nm(i);
        s[i] = (nm_i < c.x_min() || nm_i > c.x_max()) ? 0.0 : c(nm_i);
    }
    return s;
}

// Scales a spectrum to peak 1; fails if it has no positive value on the grid.
Spectrum peak_normalised(const FieldReader& r, Spectrum s) {
    double peak = *std::max_element(s.begin(), s.end());
    if (!(peak > 0)) r.fail("the spectrum is not positive anywhere on 380-780 nm");
    for (double& x : s) x = std::max(0.0, x / peak);
    return s;
}

// Every density curve, tabulated or sampled from a formula, is checked the same way so that
// stock_to_json writes what reads back: its densities lie within [0, kMaxDensity] (rounding
// errors of up to 1e-9 are clamped), and they never fall as exposure grows (development never
// removes density; a parametric curve with a sharp toe and a broad shoulder would), or for a
// reversal film (`falls`) never rise: its first development uses up the silver halide that
// exposure made developable, so more exposure leaves less to form dye.
Curve checked_density_curve(const FieldReader& r, Curve c, bool falls) {
    // A curve must change: a flat one (or one exposure) prints every pixel the same and has no speed.
    if (c.x.size() < 2 || !(c.x.back() > c.x.front()))
        r.fail("the curve needs densities at two or more exposures (log H)");
    const char* direction = falls ? "fall" : "rise";
    const auto [lowest, highest] = std::minmax_element(c.y.begin(), c.y.end());
    if (!(*highest - *lowest >= kMinDensityRise)) {
        std::ostringstream problem;
        problem << "the curve " << (falls ? "falls " : "rises ") << *highest - *lowest << " D over its exposures: a "
                << (falls ? "reversal film's" : "film's") << " density must " << direction
                << " with exposure, by at least " << kMinDensityRise << " D";
        r.fail(problem.str());
    }
    for (size_t i = 0; i < c.y.size(); ++i) {
        const double step = i > 0 ? c.y[i] - c.y[i - 1] : 0.0;
        if (falls ? step > kFallTolerance : step < -kFallTolerance)
            r.fail("the curve " + std::string(falls ? "rises" : "falls") + " at log H " + std::to_string(c.x[i]) +
                   (falls ? ": a reversal film's density must not increase with exposure"
                          : ": density must not decrease with exposure"));
        if (c.y[i] < -1e-9 || c.y[i] > kMaxDensity + 1e-9) {
            std::ostringstream problem;
            problem << "the curve reaches density " << c.y[i] << " at log H " << c.x[i] << ", outside [0, "
                    << kMaxDensity << "]";
            r.fail(problem.str());
        }
        c.y[i] = std::clamp(c.y[i], 0.0, kMaxDensity);
    }
    return c;
}

// D(x) = d_min + sum_k slope_k width_k ln(1 + exp((x - log_h_k) / width_k)), sampled every
// 0.01 log H from 12 widths before the first knot (where the softplus is within 6e-6 of its
// asymptote) to 12 widths, and at least 3 log H (10 stops), past the last: a curve that
// still rises at the end of its data keeps its final slope that far, then is held. A
// reversal film's curve (`falls`) starts from its D-max instead:
// D(x) = d_max - sum_k slope_k width_k ln(1 + exp((x - log_h_k) / width_k)).
Curve read_softplus_curve(const FieldReader& r, const json& v, bool falls) {
    const char* start_key = falls ? "d_max" : "d_min";
    if (falls && v.is_object() && v.contains("d_min") && !v.contains("d_max"))
        r.at("d_min").fail("a reversal film's curve falls from its D-max: give 'd_max', and D(x) = d_max - sum of "
                           "the knots' terms");
    const double d_start = r.at(start_key).number(r.field(v, start_key), 0.0, kMaxDensity);
    const double sign = falls ? -1.0 : 1.0;
    FieldReader rk = r.at("knots");
    const json& list = r.field(v, "knots");
    if (!list.is_array() || list.empty()) rk.fail("expected a non-empty array of {log_h, slope, width}");
    std::vector<std::array<double, 3>> knots;
    double lo = kHuge, hi = -kHuge;
    for (size_t k = 0; k < list.size(); ++k) {
        FieldReader rj = rk.at(k);
        double x = rj.at("log_h").number(rj.field(list[k], "log_h"), -20.0, 20.0);
        double slope = rj.at("slope").number(rj.field(list[k], "slope"), -50.0, 50.0);
        double width = rj.at("width").number(rj.field(list[k], "width"), 0.005, 10.0);
        knots.push_back({x, slope, width});
        lo = std::min(lo, x - 12 * width);
        hi = std::max(hi, std::max(x + 12 * width, x + 3.0));
    }
    std::vector<double> xs, ys;
    int n = (int)std::ceil((hi - lo) / 0.01);
    for (int i = 0; i <= n; ++i) {
        double x = lo + (hi - lo) * i / n, d = d_start;
        for (const auto& [at, slope, width] : knots) {
            double u = (x - at) / width;
            d += sign * slope * width * (u > 30 ? u : std::log1p(std::exp(u)));
        }
        xs.push_back(x);
        ys.push_back(d);
    }
    return checked_density_curve(r, make_curve(xs, ys, r.path()), falls);
}

Curve read_density_curve(const FieldReader& rc, const json& dc, const Stock& stock) {
    const bool falls = density_falls_with_exposure(stock.kind);
    if (dc.contains("softplus")) return read_softplus_curve(rc.at("softplus"), dc["softplus"], falls);
    if (!dc.contains("parametric")) {
        return checked_density_curve(rc, read_curve(rc, dc, "log_h", "density", 0.0, kMaxDensity), falls);
    }
    FieldReader rp = rc.at("parametric");
    if (falls) rp.fail("the parametric form rises with exposure: give a reversal film's curve as a table or softplus");
    const json& p = dc["parametric"];
    ParametricCurve pc;
    pc.gamma = rp.at("gamma").number(rp.field(p, "gamma"), 0.01, 20.0);
    pc.d_min = rp.at("d_min").number(rp.field(p, "d_min"), 0.0, kMaxDensity);
    pc.d_max = rp.at("d_max").number(rp.field(p, "d_max"), 0.0, kMaxDensity);
    pc.toe = rp.at("toe").number(rp.field(p, "toe"), 0.001, 10.0);
    pc.shoulder = rp.at("shoulder").number(rp.field(p, "shoulder"), 0.001, 10.0);
    SpeedDefinition sd = speed_definition(stock.kind);
    if (pc.d_max <= pc.d_min + sd.density_over_fog)
        rp.at("d_max").fail("must exceed d_min + " + std::to_string(sd.density_over_fog));
    double hm = speed_point_log_h(stock);
    return checked_density_curve(
        rp, sample_parametric_curve(pc, hm, sd.density_over_fog, hm - 4.0, hm + (pc.d_max - pc.d_min) / pc.gamma + 4.0),
        false);
}

Layer read_layer(const FieldReader& r, const json& v, const Stock& stock) {
    Layer layer;
    layer.name = r.at("name").text(r.field(v, "name"));
    FieldReader rs = r.at("spectral_sensitivity");
    layer.sensitivity = peak_normalised(rs, read_spectrum(rs, r.field(v, "spectral_sensitivity"), true));
    layer.density_curve = read_density_curve(r.at("density_curve"), r.field(v, "density_curve"), stock);
    if (v.contains("dye_density")) {
        FieldReader rd = r.at("dye_density");
        layer.dye_density = peak_normalised(rd, read_spectrum(rd, v["dye_density"], false));
    }

    FieldReader rm = r.at("mtf");
    layer.mtf = read_curve(rm, r.field(v, "mtf"), "cycles_per_mm", "response", 0.0, 10.0);
    if (layer.mtf.x_min() < 0) rm.at("cycles_per_mm").fail("frequencies must be >= 0");
    // Scattering is normalised to MTF(0) = 1 (it moves light, it does not absorb it): a
    // response of 0 there leaves nothing to normalise (the kernel would be 0/0).
    if (!(layer.mtf(0.0) > 0)) rm.at("response").fail("the response at 0 cycles/mm must be above 0");

    FieldReader rg = r.at("grain");
    const json& g = r.field(v, "grain");
    layer.grain.rms_granularity = rg.at("rms_granularity").number(rg.field(g, "rms_granularity"), 0.0, 1.0);
    layer.grain.grain_size_um = rg.at("grain_size_um").number(rg.field(g, "grain_size_um"), 0.0, kMaxGrainSizeUm);
    if (g.contains("density_exponent"))
        layer.grain.density_exponent = rg.at("density_exponent").number(g["density_exponent"], 0.0, 4.0);

    if (v.contains("halation")) {
        FieldReader rh = r.at("halation");
        const json& h = v["halation"];
        layer.halation.strength = rh.at("strength").number(rh.field(h, "strength"), 0.0, 10.0);
        layer.halation.radius_um = rh.at("radius_um").number(rh.field(h, "radius_um"), 0.0, kMaxHalationRadiusUm);
    }
    return layer;
}

// A colour negative's DIR couplers: {"matrix": 3 rows (receiver layers R, G, B) of 3 donors,
// "diffusion_um"}.
DirCouplerSpec read_dir_couplers(const FieldReader& r, const json& v, const Stock& stock) {
    if (stock.kind != StockKind::negative || !stock.is_colour())
        r.fail("only colour negatives have DIR couplers (their inhibition acts between three dye layers)");
    DirCouplerSpec c;
    FieldReader rm = r.at("matrix");
    const json& rows = r.field(v, "matrix");
    if (!rows.is_array() || rows.size() != 3) rm.fail("expected 3 rows (receiver layers R, G, B) of 3 numbers");
    for (size_t i = 0; i < 3; ++i) {
        if (!rows[i].is_array() || rows[i].size() != 3) rm.at(i).fail("expected 3 numbers (donor layers R, G, B)");
        for (size_t j = 0; j < 3; ++j) c.matrix[i][j] = rm.at(i).at(j).number(rows[i][j], 0.0, kMaxDirCoupling);
    }
    c.diffusion_um = r.at("diffusion_um").number(r.field(v, "diffusion_um"), 0.0, kMaxDirDiffusionUm);
    return c;
}

const std::map<std::string, StockKind> kKindNames{
    {"negative", StockKind::negative},
    {"reversal", StockKind::reversal},
    {"paper", StockKind::paper},
    {"print-film", StockKind::print_film}};

// Colour stocks are three layers that all name their dye; black-and-white ones one layer.
void check_layers(const FieldReader& r, const json& doc, const Stock& s) {
    const json& layers = doc["layers"];
    size_t with_dye = 0;
    for (const json& l : layers) with_dye += l.contains("dye_density");
    if (with_dye == 0 && s.layers.size() == 1) return;
    if (s.layers.size() != 3)
        r.at("layers").fail("a colour stock needs exactly three layers (red-, green- and blue-sensitive), got " +
                            std::to_string(s.layers.size()));
    for (size_t i = 0; i < layers.size(); ++i)
        if (!layers[i].contains("dye_density"))
            r.at("layers").at(i).at("dye_density").fail("missing: every layer of a colour stock needs its dye");
}

}  // namespace

DirCouplerSpec default_dir_couplers() {
    // Same-layer inhibition 0.3 and between layers 0.2 log10 H per unit net density, spread
    // 15 um: the magnitude of the published fits of this model (docs/model/dir-couplers.md).
    constexpr double kSameLayer = 0.3, kBetweenLayers = 0.2;
    DirCouplerSpec c;
    for (size_t i = 0; i < 3; ++i)
        for (size_t j = 0; j < 3; ++j) c.matrix[i][j] = i == j ? kSameLayer : kBetweenLayers;
    c.diffusion_um = 15.0;
    return c;
}

DirCouplerSpec stock_dir_couplers(const Stock& stock) {
    if (stock.kind != StockKind::negative || !stock.is_colour()) return {};
    return stock.dir_couplers ? *stock.dir_couplers : default_dir_couplers();
}

std::string stock_kind_name(StockKind kind) {
    for (const auto& [name, k] : kKindNames)
        if (k == kind) return name;
    return "negative";
}

Spectrum spectral_density(const Stock& stock, const double* layer_density, const double* layer_d_min) {
    Spectrum d = stock.base_density;
    for (size_t l = 0; l < stock.layers.size(); ++l) {
        double net = layer_density[l] - (layer_d_min ? layer_d_min[l] : stock.layers[l].density_curve.y_min());
        add_scaled(d, net, stock.layers[l].dye_density);
    }
    return d;
}

Stock parse_stock_json(const std::string& text, const std::string& origin) {
    const json doc = stock_json::parse_document(text, origin);
    if (doc.is_object() && !doc.contains("format") && doc.contains("data") && doc.contains("info"))
        return stock_json::stock_from_spektrafilm(doc, origin);
    FieldReader r(origin, "");
    if (r.at("format").text(r.field(doc, "format")) != "darkroom-stock")
        r.at("format").fail("expected \"darkroom-stock\"");
    int version = (int)r.at("version").number(r.field(doc, "version"), 0, 1e9);
    if (version < 1 || version > Stock::kFormatVersion)
        r.at("version").fail("version " + std::to_string(version) + " is not supported (this build reads 1 to " +
                             std::to_string(Stock::kFormatVersion) + ")");
    Stock s;
    s.id = r.at("id").text(r.field(doc, "id"));
    if (s.id.empty()) r.at("id").fail("must not be empty");
    s.name = r.at("name").text(r.field(doc, "name"));
    std::string kind = r.at("kind").text(r.field(doc, "kind"));
    auto known_kind = kKindNames.find(kind);
    if (known_kind == kKindNames.end()) r.at("kind").fail("unknown kind '" + kind + "' (known: negative, reversal, paper, print-film)");
    s.kind = known_kind->second;
    if (doc.contains("sources")) {
        const json& src = doc["sources"];
        if (!src.is_array()) r.at("sources").fail("expected an array of strings");
        for (size_t i = 0; i < src.size(); ++i) s.sources.push_back(r.at("sources").at(i).text(src[i]));
    }
    s.iso_speed = r.at("iso_speed").number(r.field(doc, "iso_speed"), kMinIsoSpeed, kMaxIsoSpeed);
    if (doc.contains("frame_width_mm")) s.frame_width_mm = r.at("frame_width_mm").number(doc["frame_width_mm"], 0.1, 1e4);
    if (doc.contains("exposure_illuminant")) {
        s.exposure_illuminant_name = r.at("exposure_illuminant").text(doc["exposure_illuminant"]);
        s.exposure_illuminant = read_illuminant(r.at("exposure_illuminant"), s.exposure_illuminant_name);
    }
    if (doc.contains("mid_grey_aim_density"))
        s.mid_grey_aim_density = r.at("mid_grey_aim_density").number(doc["mid_grey_aim_density"], 0.01, 5.0);
    if (doc.contains("density_curve_log_h")) {
        std::string axis = r.at("density_curve_log_h").text(doc["density_curve_log_h"]);
        if (axis == "relative-to-mid-grey")
            s.curve_log_h_offset = std::log10(mid_grey_exposure_lux_s(s.iso_speed));
        else if (axis != "lux-seconds")
            r.at("density_curve_log_h").fail("unknown axis '" + axis + "' (known: lux-seconds, relative-to-mid-grey)");
    }
    const json& layers = r.field(doc, "layers");
    if (!layers.is_array() || layers.empty()) r.at("layers").fail("expected a non-empty array of layers");
    for (size_t i = 0; i < layers.size(); ++i) {
        s.layers.push_back(read_layer(r.at("layers").at(i), layers[i], s));
        for (double& x : s.layers.back().density_curve.x) x += s.curve_log_h_offset;
    }
    check_layers(r, doc, s);
    if (doc.contains("dir_couplers")) s.dir_couplers = read_dir_couplers(r.at("dir_couplers"), doc["dir_couplers"], s);
    if (doc.contains("base_density")) {
        if (!s.is_colour()) r.at("base_density").fail("only colour stocks have a spectral base density");
        s.base_density = read_spectrum(r.at("base_density"), doc["base_density"], false);
        // A negative density would transmit (or reflect) more light than falls on it.
        for (int i = 0; i < kSpectralSamples; ++i)
            if (s.base_density[i] < 0)
                r.at("base_density").fail("negative at " + std::to_string(int(wavelength_nm(i))) +
                                          " nm: a density cannot be below 0");
    } else {
        double d_min[3];
        for (size_t l = 0; l < s.layers.size(); ++l) d_min[l] = s.layers[l].density_curve.y_min();
        for (size_t l = 0; l < s.layers.size(); ++l)
            for (int i = 0; i < kSpectralSamples; ++i) s.base_density[i] += d_min[l] * s.layers[l].dye_density[i];
    }
    return s;
}

Stock load_stock_file(const std::string& path) {
    return parse_stock_json(read_json_file<StockError>(path, "stock file"), path);
}

std::string stock_to_json(const Stock& s) {
    auto table = [](const Spectrum& values) {
        std::vector<double> nm(values.size());
        for (int i = 0; i < kSpectralSamples; ++i) nm[i] = wavelength_nm(i);
        return json{{"nm", nm}, {"values", values}};
    };
    json doc = {{"format", "darkroom-stock"},
                {"version", Stock::kFormatVersion},
                {"id", s.id},
                {"name", s.name},
                {"kind", stock_kind_name(s.kind)},
                {"sources", s.sources},
                {"iso_speed", s.iso_speed},
                {"frame_width_mm", s.frame_width_mm},
                {"exposure_illuminant", s.exposure_illuminant_name},
                {"mid_grey_aim_density", s.mid_grey_aim_density}};
    if (s.is_colour()) doc["base_density"] = table(s.base_density);
    for (const Layer& l : s.layers) {
        json layer = {{"name", l.name},
                      {"spectral_sensitivity", table(l.sensitivity)},
                      {"density_curve", {{"log_h", l.density_curve.x}, {"density", l.density_curve.y}}},
                      {"mtf", {{"cycles_per_mm", l.mtf.x}, {"response", l.mtf.y}}},
                      {"grain",
                       {{"rms_granularity", l.grain.rms_granularity},
                        {"grain_size_um", l.grain.grain_size_um},
                        {"density_exponent", l.grain.density_exponent}}},
                      {"halation", {{"strength", l.halation.strength}, {"radius_um", l.halation.radius_um}}}};
        if (s.is_colour()) layer["dye_density"] = table(l.dye_density);
        doc["layers"].push_back(layer);
    }
    if (s.dir_couplers)
        doc["dir_couplers"] = {{"matrix", s.dir_couplers->matrix}, {"diffusion_um", s.dir_couplers->diffusion_um}};
    return doc.dump(2);
}

const std::vector<Stock>& builtin_stocks() {
    static const std::vector<Stock> stocks = [] {
        std::vector<Stock> out;
        for (const BuiltinStockFile& f : builtin_stock_files())
            out.push_back(parse_stock_json(f.json, std::string("built-in stock ") + f.file_name));
        return out;
    }();
    return stocks;
}

Stock find_stock(const std::string& id_or_path) {
    bool is_path = id_or_path.find('/') != std::string::npos ||
                   (id_or_path.size() > 5 && id_or_path.compare(id_or_path.size() - 5, 5, ".json") == 0);
    if (is_path) return load_stock_file(id_or_path);
    std::vector<std::string> ids;
    std::string known;
    for (const Stock& s : builtin_stocks()) {
        if (s.id == id_or_path) return s;
        ids.push_back(s.id);
        known += (known.empty() ? "" : ", ") + s.id;
    }
    const std::string suggestion = did_you_mean(id_or_path, ids);
    throw StockError("unknown stock '" + id_or_path + "'" + (suggestion.empty() ? "" : ": " + suggestion) +
                     " (built-in: " + known + "; or give a path to a .json file)");
}

}  // namespace darkroom
