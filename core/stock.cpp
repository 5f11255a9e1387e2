#include "core/stock.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/builtin_stock_data.h"

namespace darkroom {

using nlohmann::json;

SpeedDefinition speed_definition(StockKind kind) {
    return kind == StockKind::paper ? SpeedDefinition{1000.0, 0.6} : SpeedDefinition{0.8, 0.1};
}

double speed_point_log_h(const Stock& stock) {
    return std::log10(speed_definition(stock.kind).k / stock.iso_speed);
}

namespace {

// Reads fields of a JSON document, naming the file and the field path in every error.
class FieldReader {
public:
    FieldReader(std::string origin, std::string path) : origin_(std::move(origin)), path_(std::move(path)) {}

    [[noreturn]] void fail(const std::string& problem) const {
        throw StockError(origin_ + ": field '" + path_ + "': " + problem);
    }
    FieldReader at(const std::string& key) const { return {origin_, path_.empty() ? key : path_ + "." + key}; }
    FieldReader at(size_t i) const { return {origin_, path_ + "[" + std::to_string(i) + "]"}; }

    const json& field(const json& obj, const std::string& key) const {
        if (!obj.is_object()) fail("expected an object");
        auto it = obj.find(key);
        if (it == obj.end()) at(key).fail("missing");
        return *it;
    }
    double number(const json& v, double min, double max) const {
        if (!v.is_number()) fail("expected a number, got " + v.dump());
        double d = v.get<double>();
        if (!std::isfinite(d) || d < min || d > max) {
            std::ostringstream s;
            s << "value " << d << " is outside [" << min << ", " << max << "]";
            fail(s.str());
        }
        return d;
    }
    std::string text(const json& v) const {
        if (!v.is_string()) fail("expected a string, got " + v.dump());
        return v.get<std::string>();
    }
    std::vector<double> numbers(const json& v, double min, double max) const {
        if (!v.is_array() || v.empty()) fail("expected a non-empty array of numbers");
        std::vector<double> out;
        for (size_t i = 0; i < v.size(); ++i) out.push_back(at(i).number(v[i], min, max));
        return out;
    }
    const std::string& path() const { return path_; }

private:
    std::string origin_, path_;
};

constexpr double kHuge = 1e30;

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

Spectrum read_sensitivity(const FieldReader& r, const json& v) {
    if (v.contains("emulsion")) {
        std::string type = r.at("emulsion").text(v["emulsion"]);
        if (type == "panchromatic") return emulsion_sensitivity(Emulsion::panchromatic);
        if (type == "orthochromatic") return emulsion_sensitivity(Emulsion::orthochromatic);
        if (type == "blue-sensitive") return emulsion_sensitivity(Emulsion::blue_sensitive);
        r.at("emulsion").fail("unknown emulsion '" + type + "' (known: panchromatic, orthochromatic, blue-sensitive)");
    }
    auto nm = r.at("nm").numbers(r.field(v, "nm"), 200.0, 1200.0);
    bool is_log = v.contains("log10_sensitivity");
    const char* key = is_log ? "log10_sensitivity" : "relative";
    auto values = r.at(key).numbers(r.field(v, key), is_log ? -30.0 : 0.0, is_log ? 30.0 : kHuge);
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
    double peak = 0;
    for (int i = 0; i < kSpectralSamples; ++i) {
        double nm_i = wavelength_nm(i);
        s[i] = (nm_i < c.x_min() || nm_i > c.x_max()) ? 0.0 : c(nm_i);
        peak = std::max(peak, s[i]);
    }
    if (!(peak > 0)) r.fail("the sensitivity is zero everywhere on 380-780 nm");
    for (double& x : s) x /= peak;
    return s;
}

Layer read_layer(const FieldReader& r, const json& v, const Stock& stock) {
    Layer layer;
    layer.name = r.at("name").text(r.field(v, "name"));
    layer.sensitivity = read_sensitivity(r.at("spectral_sensitivity"), r.field(v, "spectral_sensitivity"));

    FieldReader rc = r.at("density_curve");
    const json& dc = r.field(v, "density_curve");
    if (dc.contains("parametric")) {
        FieldReader rp = rc.at("parametric");
        const json& p = dc["parametric"];
        ParametricCurve pc;
        pc.gamma = rp.at("gamma").number(rp.field(p, "gamma"), 0.01, 20.0);
        pc.d_min = rp.at("d_min").number(rp.field(p, "d_min"), 0.0, 10.0);
        pc.d_max = rp.at("d_max").number(rp.field(p, "d_max"), 0.0, 10.0);
        pc.toe = rp.at("toe").number(rp.field(p, "toe"), 0.001, 10.0);
        pc.shoulder = rp.at("shoulder").number(rp.field(p, "shoulder"), 0.001, 10.0);
        SpeedDefinition sd = speed_definition(stock.kind);
        if (pc.d_max <= pc.d_min + sd.density_over_fog)
            rp.at("d_max").fail("must exceed d_min + " + std::to_string(sd.density_over_fog));
        double hm = speed_point_log_h(stock);
        layer.density_curve = sample_parametric_curve(pc, hm, sd.density_over_fog, hm - 4.0,
                                                      hm + (pc.d_max - pc.d_min) / pc.gamma + 4.0);
    } else {
        layer.density_curve = read_curve(rc, dc, "log_h", "density", 0.0, 10.0);
    }

    FieldReader rm = r.at("mtf");
    layer.mtf = read_curve(rm, r.field(v, "mtf"), "cycles_per_mm", "response", 0.0, 10.0);
    if (layer.mtf.x_min() < 0) rm.at("cycles_per_mm").fail("frequencies must be >= 0");

    FieldReader rg = r.at("grain");
    const json& g = r.field(v, "grain");
    layer.grain.rms_granularity = rg.at("rms_granularity").number(rg.field(g, "rms_granularity"), 0.0, 1.0);
    layer.grain.grain_size_um = rg.at("grain_size_um").number(rg.field(g, "grain_size_um"), 0.0, 1000.0);
    if (g.contains("density_exponent"))
        layer.grain.density_exponent = rg.at("density_exponent").number(g["density_exponent"], 0.0, 4.0);
    return layer;
}

}  // namespace

Stock parse_stock_json(const std::string& text, const std::string& origin) {
    json doc;
    try {
        doc = json::parse(text);
    } catch (const json::parse_error& e) {
        throw StockError(origin + ": not valid JSON: " + e.what());
    }
    FieldReader r(origin, "");
    if (r.at("format").text(r.field(doc, "format")) != "darkroom-stock")
        r.at("format").fail("expected \"darkroom-stock\"");
    int version = (int)r.at("version").number(r.field(doc, "version"), 0, 1e9);
    if (version != Stock::kFormatVersion)
        r.at("version").fail("version " + std::to_string(version) + " is not supported (this build reads " +
                             std::to_string(Stock::kFormatVersion) + ")");
    Stock s;
    s.id = r.at("id").text(r.field(doc, "id"));
    if (s.id.empty()) r.at("id").fail("must not be empty");
    s.name = r.at("name").text(r.field(doc, "name"));
    std::string kind = r.at("kind").text(r.field(doc, "kind"));
    if (kind == "negative")
        s.kind = StockKind::negative;
    else if (kind == "paper")
        s.kind = StockKind::paper;
    else
        r.at("kind").fail("unknown kind '" + kind + "' (known: negative, paper)");
    if (doc.contains("sources")) {
        const json& src = doc["sources"];
        if (!src.is_array()) r.at("sources").fail("expected an array of strings");
        for (size_t i = 0; i < src.size(); ++i) s.sources.push_back(r.at("sources").at(i).text(src[i]));
    }
    s.iso_speed = r.at("iso_speed").number(r.field(doc, "iso_speed"), 1e-6, 1e9);
    if (doc.contains("frame_width_mm")) s.frame_width_mm = r.at("frame_width_mm").number(doc["frame_width_mm"], 0.1, 1e4);
    const json& layers = r.field(doc, "layers");
    if (!layers.is_array() || layers.empty()) r.at("layers").fail("expected a non-empty array of layers");
    for (size_t i = 0; i < layers.size(); ++i) s.layers.push_back(read_layer(r.at("layers").at(i), layers[i], s));
    return s;
}

Stock load_stock_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw StockError(path + ": cannot open stock file");
    std::stringstream buffer;
    buffer << in.rdbuf();
    return parse_stock_json(buffer.str(), path);
}

std::string stock_to_json(const Stock& s) {
    json doc = {{"format", "darkroom-stock"}, {"version", Stock::kFormatVersion},
                {"id", s.id},                 {"name", s.name},
                {"kind", s.kind == StockKind::paper ? "paper" : "negative"},
                {"sources", s.sources},       {"iso_speed", s.iso_speed},
                {"frame_width_mm", s.frame_width_mm}};
    for (const Layer& l : s.layers) {
        std::vector<double> nm, rel;
        for (int i = 0; i < kSpectralSamples; ++i) {
            nm.push_back(wavelength_nm(i));
            rel.push_back(l.sensitivity[i]);
        }
        doc["layers"].push_back({{"name", l.name},
                                 {"spectral_sensitivity", {{"nm", nm}, {"relative", rel}}},
                                 {"density_curve", {{"log_h", l.density_curve.x}, {"density", l.density_curve.y}}},
                                 {"mtf", {{"cycles_per_mm", l.mtf.x}, {"response", l.mtf.y}}},
                                 {"grain",
                                  {{"rms_granularity", l.grain.rms_granularity},
                                   {"grain_size_um", l.grain.grain_size_um},
                                   {"density_exponent", l.grain.density_exponent}}}});
    }
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
    std::string known;
    for (const Stock& s : builtin_stocks()) {
        if (s.id == id_or_path) return s;
        known += (known.empty() ? "" : ", ") + s.id;
    }
    throw StockError("unknown stock '" + id_or_path + "' (built-in: " + known + "; or give a path to a .json file)");
}

}  // namespace darkroom
