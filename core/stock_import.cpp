// Importer for stock profiles in spektrafilm's JSON format (andreavolpato/spektrafilm,
// profiles v0.3): "info" names the stock and how it was measured; "data" holds on 81
// wavelengths (380-780 nm, 5 nm) the layers' log10 sensitivities and unmixed dye
// ("channel") densities and the base density, and on a shared log-exposure axis the
// three characteristic curves (net of base, red-, green-, blue-sensitive columns).
// Missing samples (null) at the ends of a spectral table are held from the nearest
// measured one; null curve samples are left out.
//
// The profiles hold no absolute exposure: their log-exposure axis is relative, 0 being the
// normal exposure of a mid grey (the profile maker places it 3 stops over the green curve's
// 0.2-over-base point for negatives, where green prints a mid grey for print materials), and
// their sensitivities are peak-normalised. In the published profiles the green curve stands
// 0.69-0.72 D over base at 0 for negatives from ISO 50 to 500 alike, while read as lux-seconds
// their speed points give ISO 12-30. So the axis is placed like the relative axis of Kodak's
// motion-picture sheets (density_curve_log_h "relative-to-mid-grey"): 0 at the exposure a mid
// grey gets at the stock's speed, which therefore cannot come from the curves; it is the box
// speed the stock's name carries (see box_speed_in_name).
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <sstream>

#include "core/stock.h"
#include "core/stock_json.h"

namespace darkroom {

using stock_json::FieldReader;
using stock_json::json;

namespace {

// The largest correction to a digitised density curve that counts as tracing noise (D).
constexpr double kMaxDigitisingDip = 0.01;

// The illuminants spektrafilm names: daylight, tungsten, and a printer's tungsten-halogen
// lamp behind a KG3 heat filter (taken as a 3200 K blackbody).
std::pair<std::string, Spectrum> reference_illuminant(const std::string& name) {
    if (name == "D50") return {"D50", illuminant_d50()};
    if (name == "D65") return {"D65", illuminant_d65()};
    if (name == "D55") return {"D55", illuminant_d55()};
    return {"3200K", blackbody(3200.0)};
}

// A sample: a number within [min, max], or NaN where the profile has none (null).
double sample_or_nan(const FieldReader& r, const json& v, double min, double max) {
    return v.is_number() ? r.number(v, min, max) : NAN;
}

// One column of an 81 x 3 table, or the whole of an 81 table (column < 0), on our grid,
// each value within [min, max].
Spectrum spectral_column(const FieldReader& r, const json& data, const std::string& key, int column, double min,
                         double max) {
    const json& table = r.field(data, key);
    if (!table.is_array() || table.size() != size_t(kSpectralSamples))
        r.at(key).fail("expected " + std::to_string(kSpectralSamples) + " rows (380-780 nm in 5 nm steps)");
    Spectrum s;
    for (int i = 0; i < kSpectralSamples; ++i) {
        const json& row = table[i];
        if (column >= 0 && (!row.is_array() || row.size() != 3)) r.at(key).at(i).fail("expected 3 columns (r, g, b)");
        FieldReader ri = column >= 0 ? r.at(key).at(i).at(column) : r.at(key).at(i);
        s[i] = sample_or_nan(ri, column >= 0 ? row[column] : row, min, max);
    }
    int first = 0, last = kSpectralSamples - 1;
    while (first < kSpectralSamples && !std::isfinite(s[first])) ++first;
    if (first == kSpectralSamples) r.at(key).fail("no values in column " + std::to_string(column));
    while (!std::isfinite(s[last])) --last;
    for (int i = 0; i < kSpectralSamples; ++i) {
        if (i < first) s[i] = s[first];
        if (i > last) s[i] = s[last];
        if (!std::isfinite(s[i])) r.at(key).at(i).fail("a missing value between measured ones");
    }
    return s;
}

// The ISO arithmetic speeds of the 1/3-stop series that film boxes are marked with (ISO 6).
constexpr std::array<int, 31> kBoxSpeeds = {6,   8,   10,  12,  16,  20,   25,   32,   40,   50,   64,
                                            80,  100, 125, 160, 200, 250,  320,  400,  500,  640,  800,
                                            1000, 1250, 1600, 2000, 2500, 3200, 4000, 5000, 6400};

// The box speed a film's name carries, as film names do ("Portra 400", "Vision3 250D",
// "C200"): the first word that is a number of the box-speed series, alone or with one letter
// before or after it; 0 if there is none. Words are split at spaces, '-' and '_'.
int box_speed_in_name(const std::string& name) {
    std::string word;
    auto speed_of = [](const std::string& w) {
        size_t first = std::isalpha((unsigned char)w.front()) ? 1 : 0;
        size_t last = std::isalpha((unsigned char)w.back()) ? w.size() - 1 : w.size();
        if (first >= last || last - first > 4) return 0;
        for (size_t i = first; i < last; ++i)
            if (!std::isdigit((unsigned char)w[i])) return 0;
        const int n = std::stoi(w.substr(first, last - first));
        return std::find(kBoxSpeeds.begin(), kBoxSpeeds.end(), n) != kBoxSpeeds.end() ? n : 0;
    };
    for (size_t i = 0; i <= name.size(); ++i) {
        if (i < name.size() && name[i] != ' ' && name[i] != '-' && name[i] != '_') {
            word += name[i];
            continue;
        }
        if (!word.empty())
            if (int speed = speed_of(word)) return speed;
        word.clear();
    }
    return 0;
}

}  // namespace

Stock import_spektrafilm_profile(const std::string& text, const std::string& origin) {
    return stock_json::stock_from_spektrafilm(stock_json::parse_document(text, origin), origin);
}

Stock stock_json::stock_from_spektrafilm(const json& doc, const std::string& origin) {
    FieldReader r(origin, "");
    const json& info = r.field(doc, "info");
    const json& data = r.field(doc, "data");
    FieldReader ri = r.at("info"), rd = r.at("data");

    Stock s;
    s.id = ri.at("stock").text(ri.field(info, "stock"));
    if (s.id.empty()) ri.at("stock").fail("must not be empty");
    s.name = ri.at("name").text(ri.field(info, "name"));
    std::string type = ri.at("type").text(ri.field(info, "type"));
    std::string support = ri.at("support").text(ri.field(info, "support"));
    std::string stage = info.contains("stage") && info["stage"].is_string() ? info["stage"].get<std::string>() : "";
    // A positive camera film is a reversal (slide) film; positive papers (direct-positive
    // prints) are not modelled.
    const bool reversal = type == "positive" && support == "film" && stage != "printing";
    if (type != "negative" && !reversal)
        ri.at("type").fail("'" + type + "' " + support + " stocks are not supported (negative-working ones and " +
                           "positive camera films are)");
    s.kind = reversal                ? StockKind::reversal
             : support == "paper"    ? StockKind::paper
             : stage == "printing"   ? StockKind::print_film
                                     : StockKind::negative;
    s.frame_width_mm = s.kind == StockKind::paper ? 254.0 : 24.89;
    std::string illuminant = info.contains("reference_illuminant") && info["reference_illuminant"].is_string()
                                 ? info["reference_illuminant"].get<std::string>()
                                 : "D55";
    std::tie(s.exposure_illuminant_name, s.exposure_illuminant) = reference_illuminant(illuminant);
    s.sources = {"imported from the spektrafilm profile " + origin +
                 " (unmixed data-sheet curves; the profile has no MTF and no granularity: flat MTF, no grain)"};
    // Print materials are exposed by the printer lights, which find their own exposure: their
    // speed is unused, 100 as the built-in papers and print films declare.
    const bool camera_film = is_camera_film(s.kind);
    const int named_speed = camera_film ? box_speed_in_name(s.name) : 0;
    s.iso_speed = named_speed > 0 ? named_speed : 100;
    s.sources.push_back(
        !camera_film ? "iso_speed 100: unused for papers and print films"
        : named_speed > 0
            ? "ISO " + std::to_string(named_speed) + ": the box speed in the stock's name (the profile's exposure axis is relative)"
            : "ISO 100 assumed: the stock's name carries no box speed and the profile's exposure axis is relative; "
              "the speed only labels the stock, a mid grey lands at the profile's normal exposure whatever it is");
    s.curve_log_h_offset = std::log10(mid_grey_exposure_lux_s(s.iso_speed));

    auto log_h = rd.at("log_exposure").numbers(rd.field(data, "log_exposure"), -20.0, 20.0);
    // 0 is the normal exposure of a mid grey: an axis that misses it is not a profile's.
    if (log_h.empty() || *std::min_element(log_h.begin(), log_h.end()) > 0 ||
        *std::max_element(log_h.begin(), log_h.end()) < 0)
        rd.at("log_exposure").fail("must span 0, the normal exposure of a mid grey on the profile's relative axis");
    const json& curves = rd.field(data, "density_curves");
    if (!curves.is_array() || curves.size() != log_h.size())
        rd.at("density_curves").fail("expected one row of 3 densities per log_exposure value (" +
                                     std::to_string(log_h.size()) + ")");
    const char* names[3] = {"red", "green", "blue"};
    for (int c = 0; c < 3; ++c) {
        Layer layer;
        layer.name = names[c];
        Spectrum log_s = spectral_column(rd, data, "log_sensitivity", c, -stock_json::kMaxLog10Sensitivity,
                                         stock_json::kMaxLog10Sensitivity);
        for (int i = 0; i < kSpectralSamples; ++i) layer.sensitivity[i] = std::pow(10.0, log_s[i]);
        Spectrum dye = spectral_column(rd, data, "channel_density", c, -stock_json::kHuge, stock_json::kHuge);
        double peak_s = *std::max_element(layer.sensitivity.begin(), layer.sensitivity.end());
        double peak_d = *std::max_element(dye.begin(), dye.end());
        if (!(peak_s > 0) || !(peak_d > 0)) rd.fail(std::string("the ") + names[c] + " layer has no sensitivity or dye");
        for (int i = 0; i < kSpectralSamples; ++i) {
            layer.sensitivity[i] /= peak_s;
            layer.dye_density[i] = std::max(0.0, dye[i] / peak_d);
        }
        std::vector<double> xs, ys;
        for (size_t i = 0; i < log_h.size(); ++i) {
            const json& row = curves[i];
            // Densities net of base, within [0, kMaxDensity]: negative ones are held at 0.
            double d = row.is_array() && row.size() == 3
                           ? sample_or_nan(rd.at("density_curves").at(i).at(c), row[c], -stock_json::kHuge,
                                           stock_json::kMaxDensity)
                           : NAN;
            if (std::isfinite(d)) xs.push_back(log_h[i] + s.curve_log_h_offset), ys.push_back(std::max(0.0, d));
        }
        try {
            layer.density_curve = make_curve(xs, ys, origin + ": data.density_curves");
        } catch (const std::invalid_argument& e) {
            throw StockError(e.what());
        }
        // Digitised curves dip where the trace is flat (by at most 1e-3 D in the published
        // profiles); darkroom-stock files may not fall (a reversal film's not rise), so the
        // import smooths dips up to kMaxDigitisingDip away and refuses a curve that turns further.
        Curve& dc = layer.density_curve;
        const double sign = reversal ? -1.0 : 1.0;  // a falling curve is a rising one mirrored
        std::vector<double> mirrored = dc.y;
        for (double& v : mirrored) v *= sign;
        std::vector<double> monotone = nearest_non_decreasing(mirrored);
        for (size_t i = 0; i < dc.y.size(); ++i) {
            monotone[i] *= sign;
            if (std::abs(monotone[i] - dc.y[i]) > kMaxDigitisingDip)
                rd.at("density_curves").fail(std::string("the ") + names[c] + " curve " +
                                             (reversal ? "rises" : "falls") + " at log H " +
                                             std::to_string(dc.x[i] - s.curve_log_h_offset) +
                                             (reversal ? ": a reversal film's density must not increase with exposure"
                                                       : ": density must not decrease with exposure"));
        }
        dc.y = monotone;
        // As a stock file's curves must (a flat curve has no speed and prints every pixel alike).
        if (!(dc.y_max() - dc.y_min() >= stock_json::kMinDensityRise)) {
            std::ostringstream problem;
            problem << "the " << names[c] << " curve " << (reversal ? "falls " : "rises ") << dc.y_max() - dc.y_min()
                    << " D: a film's density must " << (reversal ? "fall" : "rise") << " with exposure, by at least "
                    << stock_json::kMinDensityRise << " D";
            rd.at("density_curves").fail(problem.str());
        }
        layer.mtf = make_curve({0.0, 1000.0}, {1.0, 1.0}, "flat MTF");
        s.layers.push_back(layer);
    }
    // A negative density would transmit more light than falls on it.
    s.base_density = spectral_column(rd, data, "base_density", -1, 0.0, stock_json::kHuge);

    return s;
}

}  // namespace darkroom
