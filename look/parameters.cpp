#include "look/parameters.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/did_you_mean.h"
#include "core/json_message.h"
#include "core/plate/grain_synthesis.h"
#include "look/user_error.h"

namespace darkroom {

namespace {

using nlohmann::json;

// The groups, in the plugin's order.
constexpr const char* kStocks = "Stocks";
constexpr const char* kExposure = "Exposure and printing";
constexpr const char* kGrain = "Grain";
constexpr const char* kDevelopment = "Development";
constexpr const char* kOptics = "Optics and format";
constexpr const char* kColour = "Colour management (OCIO)";

const std::array<std::string, 3> kRGB{"R", "G", "B"};

// A row whose value is the field `field` returns a reference to (a captureless lambda).
template <typename T, typename Field>
Parameter row(const std::string& key, ParameterType type, Field field) {
    Parameter p;
    p.key = key;
    p.type = type;
    p.get = [field](const Look& look) { return json(field(const_cast<Look&>(look))); };
    p.set = [field](Look& look, const json& value) { field(look) = value.get<T>(); };
    return p;
}

void set_range(Parameter& p, double min, double max, double display_min, double display_max) {
    p.min = min, p.max = max, p.display_min = display_min, p.display_max = display_max;
}

template <typename Field>
Parameter number(const std::string& key, Field field, double min, double max, double display_min, double display_max) {
    Parameter p = row<double>(key, ParameterType::number, field);
    set_range(p, min, max, display_min, display_max);
    return p;
}

// Per-channel values; NaN stands for the stock's own value (null in look files).
template <typename Field>
Parameter per_channel(const std::string& key, Field field, double min, double max, double display_min,
                      double display_max) {
    Parameter p;
    set_range(p, min, max, display_min, display_max);
    p.key = key;
    p.type = ParameterType::per_channel;
    p.channel_names = kRGB;
    p.get = [field](const Look& look) {
        const std::array<double, 3>& v = field(const_cast<Look&>(look));
        return std::isnan(v[0]) ? json(nullptr) : json(v);
    };
    p.set = [field](Look& look, const json& value) {
        field(look) = value.is_null() ? std::array<double, 3>{NAN, NAN, NAN} : value.get<std::array<double, 3>>();
    };
    return p;
}

// A choice of an enumeration's values, by name.
template <typename Enum, typename Field>
Parameter choice(const std::string& key, Field field, const std::vector<std::pair<Choice, Enum>>& options) {
    Parameter p;
    p.key = key;
    p.type = ParameterType::choice;
    for (const auto& o : options) p.choices.push_back(o.first);
    p.get = [field, options](const Look& look) {
        for (const auto& [c, e] : options)
            if (e == field(const_cast<Look&>(look))) return json(c.name);
        return json(nullptr);
    };
    p.set = [field, options](Look& look, const json& value) {
        for (const auto& [c, e] : options)
            if (c.name == value.get<std::string>()) field(look) = e;
    };
    return p;
}

std::vector<std::pair<Choice, Quality>> quality_choices() {
    std::vector<std::pair<Choice, Quality>> out;
    for (Quality q : kQualities) out.push_back({{quality_name(q), quality_name(q)}, q});
    return out;
}

std::vector<Parameter> make_table() {
    std::vector<Parameter> t;
    auto add = [&t](Parameter p, const char* group, const char* label, const char* ofx_name, const char* unit,
                    const char* help) -> Parameter& {
        p.group = group, p.label = label, p.ofx_name = ofx_name, p.unit = unit, p.help = help;
        t.push_back(std::move(p));
        return t.back();
    };

    // Stocks and what to write.
    Parameter film = row<std::string>("film", ParameterType::stock, [](Look& l) -> auto& { return l.film; });
    film.stock_kinds = {StockKind::negative, StockKind::reversal};
    add(film, kStocks, "Film", "film", "",
        "The camera film, negative or reversal: a built-in stock id (see 'darkroom stocks') or a stock file (.json)")
        .per_pixel = true;
    Parameter paper = row<std::string>("paper", ParameterType::stock, [](Look& l) -> auto& { return l.paper; });
    paper.stock_kinds = {StockKind::print_film, StockKind::paper};
    add(paper, kStocks, "Paper", "paper", "",
        "What the negative is printed on: a print film or paper id, a stock file, or 'none' to stop at the "
        "negative (the negative, density, scan and texture outputs need none; a reversal film is its own print and "
        "uses none)")
        .per_pixel = true;
    add(choice<OutputMode>("output", [](Look& l) -> auto& { return l.settings.output; },
                           {{{"print", "Print"}, OutputMode::print},
                            {{"negative", "Negative"}, OutputMode::negative},
                            {{"density", "Density"}, OutputMode::density},
                            {{"scan", "Scan"}, OutputMode::scan},
                            {{"texture", "Texture"}, OutputMode::texture}}),
        kStocks, "Output", "output", "",
        "What to write: print (the print's colour), negative (its transmittance), density (per layer), scan "
        "(Cineon log code values / 1023), texture (the input with the film's grain, MTF and halation only)")
        .per_pixel = true;
    add(choice<Quality>("quality", [](Look& l) -> auto& { return l.settings.quality; }, quality_choices()), kStocks,
        "Quality", "quality", "",
        "How each stage is computed: reference (from its definition; slow), high, fast, or preview (fast on a "
        "proxy of about 1 MP, upsampled: for interactive work); 'darkroom bench' measures each against the "
        "reference")
        .per_pixel = true;
    add(choice<InputUnits>("input-units", [](Look& l) -> auto& { return l.settings.input_units; },
                           {{{"scene-linear", "Scene-linear"}, InputUnits::scene_linear},
                            {{"lux-seconds", "Lux seconds"}, InputUnits::lux_seconds}}),
        kStocks, "Input units", "inputUnits", "",
        "scene-linear (metered so that 0.18 is mid grey) or lux-seconds (the pixels are the exposure H)")
        .per_pixel = true;

    // Exposure and printing.
    Parameter& exposure = add(number("exposure", [](Look& l) -> auto& { return l.settings.exposure_ev; },
                                     -kMaxExposureEv, kMaxExposureEv, -6, 6),
                              kExposure, "Exposure (EV)", "exposure", "EV",
                              "Camera exposure in stops relative to the stock's ISO speed (at 0 a scene-linear 0.18 "
                              "gets the mid-grey exposure)");
    exposure.animatable = exposure.per_pixel = true;
    Parameter& print_exposure =
        add(number("print-exposure", [](Look& l) -> auto& { return l.settings.print_exposure_ev; }, -kMaxExposureEv,
                   kMaxExposureEv, -4, 4),
            kExposure, "Print exposure (EV)", "printExposure", "EV",
            "Print exposure in stops relative to the automatic one");
    print_exposure.animatable = print_exposure.per_pixel = true;
    Parameter& lights = add(per_channel("printer-lights", [](Look& l) -> auto& { return l.settings.printer_lights; },
                                        kPrinterLightsAuto - kMaxPrinterPoints, kPrinterLightsAuto + kMaxPrinterPoints,
                                        0, 50),
                            kExposure, "Printer lights", "printerLights", "points",
                            "Printer lights R,G,B in points: 25 is the automatic light (mid grey prints neutral); one "
                            "point adds 0.025 log exposure to that paper layer (more red light: more cyan dye)");
    lights.animatable = lights.per_pixel = true;
    Parameter& filtration =
        add(per_channel("filtration", [](Look& l) -> auto& { return l.settings.filtration_ymc; }, 0, kMaxFiltrationCc, 0,
                        100),
            kExposure, "Filtration (CC)", "filtration", "CC",
            "Enlarger filters Y,M,C in colour-compensating units (density x 100), on top of the printer lights");
    filtration.channel_names = {"Y", "M", "C"};
    filtration.animatable = filtration.per_pixel = true;

    add(choice<PrintViewing>("print-viewing", [](Look& l) -> auto& { return l.settings.print_viewing; },
                             {{{"media-relative", "Media relative"}, PrintViewing::media_relative},
                              {{"absolute", "Absolute"}, PrintViewing::absolute}}),
        kExposure, "Print viewing", "printViewing", "",
        "How the print is seen: media-relative (adapted to the print's own white, as a viewer's eye is, with the "
        "automatic print of a scene mid grey at 0.18 on every paper) or absolute (its colorimetry under D65, the "
        "base's colour included; mid grey at 10^-aim density)")
        .per_pixel = true;
    add(choice<bool>("print-gamut", [](Look& l) -> auto& { return l.settings.print_gamut_compression; },
                     {{{"compress", "Compress"}, true}, {{"keep", "Keep"}, false}}),
        kExposure, "Print gamut", "printGamut", "",
        "Print colours outside linear Rec.709: compress (towards neutral at constant luminance, no negative "
        "component) or keep (as computed, negative components included)")
        .per_pixel = true;
    add(choice<bool>("scan-balance", [](Look& l) -> auto& { return l.settings.scan_balance; },
                     {{{"aim", "Aim"}, true}, {{"none", "None"}, false}}),
        kExposure, "Scan balance", "scanBalance", "",
        "The scan output: aim (balanced, a normally exposed mid grey at the scan aim in R, G and B) or none (each "
        "layer's base+fog at code 95)")
        .per_pixel = true;
    add(number("scan-aim", [](Look& l) -> auto& { return l.settings.scan_aim_code; }, 0, kMaxScanCode, 95, 700),
        kExposure, "Scan aim (code)", "scanAim", "",
        "The Cineon code value a normally exposed mid grey scans at when balanced (Kodak's LAD aim: 445)")
        .per_pixel = true;

    // Grain.
    add(row<bool>("grain", ParameterType::on_off, [](Look& l) -> auto& { return l.settings.grain; }), kGrain, "Grain",
        "grain", "", "Granularity (off: no grain)");
    add(per_channel("grain-amount", [](Look& l) -> auto& { return l.settings.grain_amount; }, 0, kMaxGrainScale, 0, 3),
        kGrain, "Amount", "grainAmount", "",
        "Multiplies each layer's RMS granularity (R, G, B layers; a black-and-white film uses R)")
        .animatable = true;
    add(per_channel("grain-size", [](Look& l) -> auto& { return l.settings.grain_size; }, 0, kMaxGrainScale, 0.25, 4),
        kGrain, "Size", "grainSize", "", "Multiplies each layer's grain size")
        .animatable = true;
    Parameter& response =
        add(per_channel("grain-response", [](Look& l) -> auto& { return l.settings.grain_density_exponent; }, 0,
                        kMaxGrainResponse, 0, 1),
            kGrain, "Response", "grainResponse", "",
            "Replaces the stock's exponent of the grain's growth with net density, D^x (unset: the stock's; the seed "
            "paper cites 1/3)");
    response.stock_default = response.animatable = true;
    response.override_start = 1.0 / 3.0;  // the seed paper's exponent
    add(row<std::string>("grain-profile", ParameterType::file, [](Look& l) -> auto& { return l.grain_profile; }),
        kGrain, "Grain profile", "grainProfile", "",
        "A plate's grain profile (.json from 'darkroom grain analyze' or 'predict'): replaces the stock's grain, added "
        "to the result in the output colour space (which should be the plate's)");
    add(per_channel("grain-profile-gain", [](Look& l) -> auto& { return l.grain_profile_gain; }, 0, kMaxGrainScale, 0, 3),
        kGrain, "Profile gain", "grainProfileGain", "", "Multiplies the grain profile's sigma per channel")
        .animatable = true;
    add(per_channel("grain-profile-size", [](Look& l) -> auto& { return l.grain_profile_size; }, kMinGrainSizeScale,
                    kMaxGrainSizeScale, 0.5, 2),
        kGrain, "Profile size", "grainProfileSize", "", "Multiplies the grain profile's grain size per channel")
        .animatable = true;
    add(number("grain-profile-tilt", [](Look& l) -> auto& { return l.grain_profile_tilt; }, -kMaxResponseTilt,
               kMaxResponseTilt, -2, 2),
        kGrain, "Profile tilt", "grainProfileTilt", "",
        "Tilts the grain profile's response: stops more sigma at its highest level than at its lowest")
        .animatable = true;
    add(row<uint64_t>("seed", ParameterType::seed, [](Look& l) -> auto& { return l.settings.seed; }), kGrain, "Seed",
        "seed", "", "Grain seed: the grain is a function of (seed, frame, layer, pixel)");

    // Development.
    Parameter& couplers =
        add(number("dir-couplers", [](Look& l) -> auto& { return l.settings.dir_couplers; }, 0, kMaxDirCouplers, 0, 2),
            kDevelopment, "DIR couplers", "dirCouplers", "",
            "Multiplies the colour negative's DIR couplers: development inhibited by the density around, in its own "
            "and the other layers (interimage colour and edge effects; 0 = off, the data sheet's curves per pixel)");
    couplers.animatable = couplers.per_pixel = true;  // (a LUT holds their colour, spread 0)
    add(number("dir-coupler-spread", [](Look& l) -> auto& { return l.settings.dir_coupler_spread; }, 0,
               kMaxDirCouplerSpread, 0, 4),
        kDevelopment, "Inhibitor spread", "dirCouplerSpread", "",
        "Multiplies how far the DIR couplers' inhibitor diffuses on the film (0 = pointwise: no edge effects)")
        .animatable = true;

    // Optics and format.
    add(row<bool>("mtf", ParameterType::on_off, [](Look& l) -> auto& { return l.settings.mtf; }), kOptics, "MTF",
        "mtf", "", "Internal scattering in the emulsion, the stock's MTF (off: none)");
    add(number("halation", [](Look& l) -> auto& { return l.settings.halation; }, 0, kMaxHalation, 0, 4), kOptics,
        "Halation", "halation", "", "Multiplies each film layer's halation strength (0 = off)")
        .animatable = true;
    add(number("frame-width-mm", [](Look& l) -> auto& { return l.settings.frame_width_mm; }, 0, kMaxFormatMm, 0, 70),
        kOptics, "Frame width (mm)", "frameWidthMm", "mm",
        "Width of the film frame; with the image's width it sets the pixel pitch (0 = the stock's format)");
    add(number("print-width-mm", [](Look& l) -> auto& { return l.settings.print_width_mm; }, 0, kMaxFormatMm, 0, 500),
        kOptics, "Print width (mm)", "printWidthMm", "mm", "Width of the print (0 = the paper's format)");

    // Colour management.
    add(row<std::string>("colorconfig", ParameterType::file, [](Look& l) -> auto& { return l.colour.config_path; }),
        kColour, "OCIO config", "ocioConfig", "", "OCIO config file (empty: $OCIO, else the embedded config)")
        .per_pixel = true;
    add(row<std::string>("iscolorspace", ParameterType::text, [](Look& l) -> auto& { return l.colour.input_space; }),
        kColour, "Input colour space", "inputColorspace", "",
        "Colour space of the input (empty: the config's scene_linear role; the embedded config's is the working "
        "space, linear Rec.709)")
        .per_pixel = true;
    add(row<std::string>("tocolorspace", ParameterType::text, [](Look& l) -> auto& { return l.colour.output_space; }),
        kColour, "Output colour space", "outputColorspace", "",
        "Convert the result to this colour space (empty: the config's scene_linear role for the print, negative "
        "and texture; the scan stays Cineon log code values and densities are data, never converted)")
        .per_pixel = true;
    Parameter display = row<std::vector<std::string>>("ociodisplay", ParameterType::display_view,
                                                      [](Look& l) -> auto& { return l.colour.display_view; });
    display.get = [](const Look& l) { return l.colour.display_view.empty() ? json(nullptr) : json(l.colour.display_view); };
    display.set = [](Look& l, const json& v) {
        l.colour.display_view = v.is_null() ? std::vector<std::string>{} : v.get<std::vector<std::string>>();
    };
    add(display, kColour, "Display and view", "", "",
        "Convert the result to this OCIO display and view (\"\" for the config's defaults)")
        .per_pixel = true;
    return t;
}

std::string number_text(double v) {
    std::ostringstream s;
    s.precision(10);
    s << v;
    return s.str();
}

[[noreturn]] void must_be(const std::string& what, const json& value) {
    // (JSON writes an infinity or NaN as null.)
    const std::string given = value.is_number_float() ? number_text(value.get<double>()) : json_for_message(value);
    throw UserError("must be " + what + ", not " + given);
}

double checked_number(const Parameter& p, const json& value) {
    const std::string range = "a number from " + number_text(p.min) + " to " + number_text(p.max);
    if (!value.is_number()) must_be(range, value);
    const double v = value.get<double>();
    if (!(v >= p.min && v <= p.max)) must_be(range, value);
    return v;
}

}  // namespace

std::string Parameter::python_keyword() const {
    std::string k = key;
    std::replace(k.begin(), k.end(), '-', '_');
    return k;
}

const std::vector<Parameter>& parameters() {
    static const std::vector<Parameter> table = make_table();
    return table;
}

const Parameter* find_parameter(const std::string& key) {
    for (const Parameter& p : parameters())
        if (p.key == key) return &p;
    return nullptr;
}

const Parameter& parameter(const std::string& key) {
    const Parameter* p = find_parameter(key);
    if (!p) throw std::logic_error("no look parameter '" + key + "'");
    return *p;
}

json check_value(const Parameter& p, const json& value) {
    switch (p.type) {
        case ParameterType::stock:
        case ParameterType::text:
        case ParameterType::file:
            if (value.is_null()) return "";
            if (!value.is_string()) must_be("a string", value);
            return value;
        case ParameterType::number: return checked_number(p, value);
        case ParameterType::per_channel: {
            if (value.is_null() && p.stock_default) return nullptr;
            const json values = value.is_array() ? value : json::array({value});
            if (values.size() != 1 && values.size() != 3)
                must_be("one number for every channel or three (" + p.channel_names[0] + ", " + p.channel_names[1] +
                            ", " + p.channel_names[2] + ")",
                        value);
            json out = json::array();
            for (int c = 0; c < 3; ++c) out.push_back(checked_number(p, values[values.size() == 1 ? 0 : c]));
            return out;
        }
        case ParameterType::on_off:
            // (Hand-written look files have said "false"; the flags' parser took it.)
            if (value == "true" || value == "false") return value == "true";
            if (!value.is_boolean()) must_be("true or false", value);
            return value;
        case ParameterType::choice: {
            std::string names;
            for (const Choice& c : p.choices) {
                names += (names.empty() ? "" : ", ") + c.name;
                if (value.is_string()) {
                    std::string given = value.get<std::string>();
                    std::transform(given.begin(), given.end(), given.begin(), ::tolower);
                    if (given == c.name) return c.name;
                }
            }
            must_be("one of " + names, value);
        }
        case ParameterType::seed:
            // Exact: a seed saved as a double would lose its low bits above 2^53.
            if (!value.is_number_integer() || (value.is_number_integer() && !value.is_number_unsigned() &&
                                               value.get<long long>() < 0))
                must_be("a whole number from 0 to 18446744073709551615", value);
            return value.get<uint64_t>();
        case ParameterType::display_view:
            if (value.is_null()) return nullptr;
            if (!value.is_array() || value.size() != 2 || !value[0].is_string() || !value[1].is_string())
                must_be("a display and a view (two strings; \"\" for the config's defaults)", value);
            return value;
    }
    throw std::logic_error("unknown parameter type");
}

void set_value(Look& look, const Parameter& p, const json& value) { p.set(look, check_value(p, value)); }

std::string output_name(OutputMode mode) {
    Look look;
    look.settings.output = mode;
    return parameter("output").get(look).get<std::string>();
}

std::string flag_name(const Parameter& p) { return p.cli_flag(); }
std::string ofx_label(const Parameter& p) { return p.label; }
std::string python_name(const Parameter& p) { return p.python_keyword() + "="; }
std::string look_file_key(const Parameter& p) { return "'" + p.key + "'"; }

namespace {

// A reversal film is its own print (no paper); a film that cannot be found is left to the
// render to name.
bool is_reversal_film(const std::string& id_or_path) {
    try {
        return find_stock(id_or_path).kind == StockKind::reversal;
    } catch (const StockError&) {
        return false;
    }
}

}  // namespace

void validate(const Look& look, const Naming& name) {
    const DevelopSettings& s = look.settings;
    const Parameter &paper = parameter("paper"), &output = parameter("output");
    if (look.film.empty()) throw UserError(name(parameter("film")) + " is empty: name a film stock");
    if (s.output == OutputMode::print && (look.paper == "none" || look.paper.empty()) && !is_reversal_film(look.film))
        throw UserError(name(output) + " print needs a paper, and " + name(paper) +
                        " is none (stop at the negative): choose a paper or print film, a reversal film (its own "
                        "print), or the negative, density, scan or texture output");
    const bool to_display = !look.colour.display_view.empty();
    if (to_display && !look.colour.output_space.empty())
        throw UserError(name(parameter("ociodisplay")) + " and " + name(parameter("tocolorspace")) +
                        " both say where the result goes: give one");
    if (s.output == OutputMode::density && (to_display || !look.colour.output_space.empty()))
        throw UserError(name(output) + " density writes densities, which are data, not colours: " +
                        name(parameter(to_display ? "ociodisplay" : "tocolorspace")) + " cannot convert them");
}

std::string closest_key(const std::string& key) {
    std::vector<std::string> keys;
    for (const Parameter& p : parameters()) {
        // A key with words added or left off ("halation-strength") is its row's.
        if (key.size() >= 4 && p.key.size() >= 4 && (key.rfind(p.key, 0) == 0 || p.key.rfind(key, 0) == 0))
            return p.key;
        keys.push_back(p.key);
    }
    const std::vector<std::string> near = close_names(key, keys);
    return near.empty() ? "" : near.front();
}

}  // namespace darkroom
