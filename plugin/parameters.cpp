#include "plugin/parameters.h"

#include <array>
#include <cmath>
#include <iterator>
#include <vector>

#include "plugin/ofx_host.h"

namespace darkroom::ofx {

namespace {

// Script names of the parameters (what a host's scripting and saved projects use).
constexpr const char* kFilm = "film";
constexpr const char* kFilmFile = "filmFile";
constexpr const char* kPaper = "paper";
constexpr const char* kPaperFile = "paperFile";
// Hidden: the id of the option each stock choice is set to (stock_options), so that a saved
// node keeps its stocks when a later version's lists put them at other indices.
constexpr const char* kFilmStock = "filmStock";
constexpr const char* kPaperStock = "paperStock";
constexpr const char* kOutput = "output";
constexpr const char* kQuality = "quality";
constexpr const char* kExposure = "exposure";
constexpr const char* kPrintExposure = "printExposure";
constexpr const char* kPrinterLights = "printerLights";
constexpr const char* kFiltration = "filtration";
constexpr const char* kGrain = "grain";
constexpr const char* kGrainAmount = "grainAmount";
constexpr const char* kGrainSize = "grainSize";
constexpr const char* kGrainResponseOverride = "grainResponseOverride";
constexpr const char* kGrainResponse = "grainResponse";
constexpr const char* kGrainProfile = "grainProfile";
constexpr const char* kSeed = "seed";
constexpr const char* kStaticGrain = "staticGrain";
constexpr const char* kHalation = "halation";
constexpr const char* kMtf = "mtf";
constexpr const char* kFrameWidth = "frameWidthMm";
constexpr const char* kPrintWidth = "printWidthMm";
constexpr const char* kFilmFrame = "filmFrame";
constexpr const char* kOcioConfig = "ocioConfig";
constexpr const char* kInputSpace = "inputColorspace";
constexpr const char* kOutputSpace = "outputColorspace";

// Output modes in the order of the choice parameter.
const std::array<std::pair<const char*, OutputMode>, 5> kOutputs{{{"Print", OutputMode::print},
                                                                  {"Negative", OutputMode::negative},
                                                                  {"Density", OutputMode::density},
                                                                  {"Scan", OutputMode::scan},
                                                                  {"Texture", OutputMode::texture}}};

// An option of a stock choice: what it stands for (a built-in stock's id, or one of the
// two below) and what the user sees.
struct StockOption {
    std::string id, label;
};
constexpr const char* kStockFileId = "file";
constexpr const char* kNoPaperId = "none";

// Film choice: the built-in films, then a stock file. Paper: built-in papers, none, a file.
std::vector<StockOption> stock_options(StockKind kind) {
    std::vector<StockOption> options;
    for (const Stock& s : builtin_stocks())
        if (s.kind == kind) options.push_back({s.id, s.name});
    if (kind == StockKind::paper) options.push_back({kNoPaperId, "None (stop at the negative)"});
    options.push_back({kStockFileId, "Stock file..."});
    return options;
}

int option_index(const std::vector<StockOption>& options, const std::string& id) {
    for (size_t i = 0; i < options.size(); ++i)
        if (options[i].id == id) return int(i);
    return -1;
}

std::vector<std::string> labels(const std::vector<StockOption>& options) {
    std::vector<std::string> out;
    for (const StockOption& o : options) out.push_back(o.label);
    return out;
}

// A stock choice, its hidden id parameter and the options it offers.
struct StockChoice {
    const char* choice;
    const char* id;
    StockKind kind;
};
const std::array<StockChoice, 2> kStockChoices{{{kFilm, kFilmStock, StockKind::negative},
                                                {kPaper, kPaperStock, StockKind::paper}}};

Props define(OfxParamSetHandle params, const char* type, const char* name, const char* label, const char* hint,
             const char* parent) {
    OfxPropertySetHandle h = nullptr;
    check(suites.param->paramDefine(params, type, name, &h), (std::string("defining parameter ") + name).c_str());
    Props p(h);
    p.set(kOfxPropLabel, label);
    p.set(kOfxParamPropScriptName, name);
    if (hint) p.set(kOfxParamPropHint, hint);
    if (parent) p.set(kOfxParamPropParent, parent);
    return p;
}

void define_group(OfxParamSetHandle params, const char* name, const char* label, bool open) {
    Props g = define(params, kOfxParamTypeGroup, name, label, nullptr, nullptr);
    g.set(kOfxParamPropGroupOpen, open ? 1 : 0);
}

Props define_double(OfxParamSetHandle params, const char* name, const char* label, const char* hint,
                    const char* parent, double def, double min, double max, double display_min, double display_max) {
    Props p = define(params, kOfxParamTypeDouble, name, label, hint, parent);
    p.set(kOfxParamPropDoubleType, kOfxParamDoubleTypePlain);
    p.set(kOfxParamPropDefault, def);
    p.set(kOfxParamPropMin, min);
    p.set(kOfxParamPropMax, max);
    p.set(kOfxParamPropDisplayMin, display_min);
    p.set(kOfxParamPropDisplayMax, display_max);
    p.set(kOfxParamPropAnimates, 1);
    return p;
}

// Three values, one per channel or filter; labels name the dimensions.
Props define_double3(OfxParamSetHandle params, const char* name, const char* label, const char* hint,
                     const char* parent, double def, double min, double max, double display_min, double display_max,
                     const std::array<const char*, 3>& dimension_labels) {
    Props p = define(params, kOfxParamTypeDouble3D, name, label, hint, parent);
    p.set(kOfxParamPropDoubleType, kOfxParamDoubleTypePlain);
    for (int i = 0; i < 3; ++i) {
        p.set(kOfxParamPropDefault, def, i);
        p.set(kOfxParamPropMin, min, i);
        p.set(kOfxParamPropMax, max, i);
        p.set(kOfxParamPropDisplayMin, display_min, i);
        p.set(kOfxParamPropDisplayMax, display_max, i);
        p.set(kOfxParamPropDimensionLabel, dimension_labels[i], i);
    }
    p.set(kOfxParamPropAnimates, 1);
    return p;
}

void define_bool(OfxParamSetHandle params, const char* name, const char* label, const char* hint, const char* parent,
                 bool def) {
    Props p = define(params, kOfxParamTypeBoolean, name, label, hint, parent);
    p.set(kOfxParamPropDefault, def ? 1 : 0);
    p.set(kOfxParamPropAnimates, 0);
}

void define_choice(OfxParamSetHandle params, const char* name, const char* label, const char* hint, const char* parent,
                   const std::vector<std::string>& options, int def) {
    Props p = define(params, kOfxParamTypeChoice, name, label, hint, parent);
    p.set(kOfxParamPropChoiceOption, options);
    p.set(kOfxParamPropDefault, def);
    p.set(kOfxParamPropAnimates, 0);
}

Props define_string(OfxParamSetHandle params, const char* name, const char* label, const char* hint, const char* parent,
                    const char* def, bool file_path) {
    Props p = define(params, kOfxParamTypeString, name, label, hint, parent);
    p.set(kOfxParamPropDefault, def);
    p.set(kOfxParamPropStringMode, file_path ? kOfxParamStringIsFilePath : kOfxParamStringIsSingleLine);
    if (file_path) p.set(kOfxParamPropStringFilePathExists, 1);
    p.set(kOfxParamPropAnimates, 0);
    return p;
}

// Reading values from an instance.
class Reader {
public:
    Reader(OfxImageEffectHandle instance, OfxTime time) : time_(time) {
        check(suites.effect->getParamSet(instance, &params_), "getting the parameter set");
    }

    double get_double(const char* name) const {
        double v = 0;
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v), name);
        return v;
    }
    std::array<double, 3> get_double3(const char* name) const {
        std::array<double, 3> v{};
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v[0], &v[1], &v[2]), name);
        return v;
    }
    int get_int(const char* name) const {
        int v = 0;
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v), name);
        return v;
    }
    bool get_bool(const char* name) const { return get_int(name) != 0; }
    std::string get_string(const char* name) const {
        char* v = nullptr;
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v), name);
        return v ? v : "";
    }
    // The label the user sees, for messages.
    std::string label(const char* name) const {
        OfxPropertySetHandle props = nullptr;
        OfxParamHandle h = nullptr;
        if (suites.param->paramGetHandle(params_, name, &h, &props) != kOfxStatOK || !props) return name;
        return Props(props).get_string_or(kOfxPropLabel, name);
    }

    // A value that must be finite and within [min, max].
    double checked(const char* name, double v, double min, double max) const {
        if (!std::isfinite(v) || v < min || v > max)
            throw ParameterError(label(name) + " is " + std::to_string(v) + ": it must be a number from " +
                                 trimmed(min) + " to " + trimmed(max));
        return v;
    }
    double checked_double(const char* name, double min, double max) const { return checked(name, get_double(name), min, max); }
    std::array<double, 3> checked_double3(const char* name, double min, double max) const {
        std::array<double, 3> v = get_double3(name);
        for (double& c : v) checked(name, c, min, max);
        return v;
    }
    int checked_choice(const char* name, int option_count) const {
        int v = get_int(name);
        if (v < 0 || v >= option_count)
            throw ParameterError(label(name) + " is option " + std::to_string(v) + ", which does not exist (0 to " +
                                 std::to_string(option_count - 1) + ")");
        return v;
    }
    // The id of the option a stock choice is set to. A node saved with a stock this version
    // does not have keeps that stock's id (restore_stock_choices) until the user chooses.
    std::string stock_choice(const StockChoice& c) const {
        const auto options = stock_options(c.kind);
        const std::string saved = get_string(c.id);
        if (!saved.empty() && option_index(options, saved) < 0)
            throw ParameterError(label(c.choice) + ": this node was saved with the stock '" + saved +
                                 "', which this version of Darkroom does not have; choose another");
        return options[size_t(checked_choice(c.choice, int(options.size())))].id;
    }

    // A parameter's handle (also for setting its value).
    OfxParamHandle handle(const char* name) const {
        OfxParamHandle h = nullptr;
        check(suites.param->paramGetHandle(params_, name, &h, nullptr), name);
        return h;
    }

private:
    static std::string trimmed(double v) {
        std::string s = std::to_string(v);
        s.erase(s.find_last_not_of('0') + 1);
        if (!s.empty() && s.back() == '.') s.pop_back();
        return s;
    }

    OfxParamSetHandle params_ = nullptr;
    OfxTime time_;
};

// The path in a stock-file parameter, which must be given when its choice asks for a file.
std::string stock_file(const Reader& r, const char* choice, const char* file) {
    std::string path = r.get_string(file);
    if (path.empty())
        throw ParameterError(r.label(choice) + " is set to a stock file, but " + r.label(file) + " is empty");
    return path;
}

}  // namespace

void define_parameters(OfxParamSetHandle params) {
    const char* stocks = "stocksGroup";
    define_group(params, stocks, "Stocks", true);
    const auto films = stock_options(StockKind::negative), papers = stock_options(StockKind::paper);
    define_choice(params, kFilm, "Film", "The camera negative: a built-in stock, or a stock file (below)", stocks,
                  labels(films), option_index(films, "kodak-tri-x-400"));
    define_string(params, kFilmFile, "Film stock file", "A Darkroom stock file (.json) used when Film is 'Stock file'",
                  stocks, "", true);
    define_choice(params, kPaper, "Paper",
                  "The print paper: a built-in stock, none (only for the negative, density and scan outputs), or a "
                  "stock file",
                  stocks, labels(papers), option_index(papers, "vdr-paper-grade-2"));
    define_string(params, kPaperFile, "Paper stock file", "A Darkroom stock file (.json) used when Paper is 'Stock file'",
                  stocks, "", true);
    // Empty until the node is created (restore_stock_choices), as in nodes saved before them.
    for (const StockChoice& c : kStockChoices)
        define_string(params, c.id, c.id, "The id of the stock chosen above, saved with the node", stocks, "", false)
            .set(kOfxParamPropSecret, 1);
    std::vector<std::string> outputs;
    for (const auto& o : kOutputs) outputs.push_back(o.first);
    define_choice(params, kOutput, "Output",
                  "Print: the print's colour (linear Rec.709). Negative: the negative's transmittance. Density: the "
                  "developed density per layer. Scan: Cineon-style log code values / 1023. Texture: the input with "
                  "the film's grain, MTF and halation only",
                  stocks, outputs, 0);
    std::vector<std::string> qualities;
    for (Quality q : kQualities) qualities.push_back(quality_name(q));
    define_choice(params, kQuality, "Quality",
                  "How each stage is computed: reference (from its definition; slow), high, fast or preview; "
                  "darkroom bench measures each against the reference",
                  stocks, qualities, int(DevelopSettings{}.quality));

    const char* exposure = "exposureGroup";
    define_group(params, exposure, "Exposure and printing", true);
    define_double(params, kExposure, "Exposure (EV)",
                  "Camera exposure in stops; at 0 a scene-linear 0.18 gets the mid-grey exposure the film's ISO speed "
                  "implies",
                  exposure, 0, -64, 64, -6, 6);
    define_double(params, kPrintExposure, "Print exposure (EV)", "Print exposure in stops relative to the automatic one",
                  exposure, 0, -64, 64, -4, 4);
    define_double3(params, kPrinterLights, "Printer lights",
                   "Printer points for the red, green and blue light: 25 is the automatic light; one point is 0.025 "
                   "log exposure, so more red light gives more cyan dye",
                   exposure, 25, 0, 100, 0, 50, {"R", "G", "B"});
    define_double3(params, kFiltration, "Filtration (CC)",
                   "Enlarger filters in colour-compensating units (density x 100) of yellow, magenta and cyan", exposure,
                   0, 0, 300, 0, 100, {"Y", "M", "C"});

    const char* grain = "grainGroup";
    define_group(params, grain, "Grain", true);
    define_bool(params, kGrain, "Grain", "Simulate granularity", grain, true);
    define_double3(params, kGrainAmount, "Amount",
                   "Multiplies each layer's RMS granularity (red, green and blue layers; a black-and-white film uses R)",
                   grain, 1, 0, 10, 0, 3, {"R", "G", "B"});
    define_double3(params, kGrainSize, "Size", "Multiplies each layer's grain size", grain, 1, 0.05, 20, 0.25, 4,
                   {"R", "G", "B"});
    define_bool(params, kGrainResponseOverride, "Override response",
                "Replace the stock's density exponent of granularity by Response", grain, false);
    define_double3(params, kGrainResponse, "Response",
                   "Granularity grows with net density as D^response (the seed paper cites 1/3)", grain, 1.0 / 3.0, 0,
                   3, 0, 1, {"R", "G", "B"});
    define_string(params, kGrainProfile, "Grain profile",
                  "A plate's grain profile (.json from darkroom grain analyze or predict): replaces the stock's grain "
                  "and is added in the output colour space, which should be the plate's",
                  grain, "", true);
    Props seed = define(params, kOfxParamTypeInteger, kSeed, "Seed",
                        "Grain seed: the grain is a function of (seed, frame, layer, pixel)", grain);
    seed.set(kOfxParamPropDefault, 0);
    seed.set(kOfxParamPropMin, 0);
    seed.set(kOfxParamPropMax, INT_MAX);
    seed.set(kOfxParamPropDisplayMin, 0);
    seed.set(kOfxParamPropDisplayMax, 1000);
    seed.set(kOfxParamPropAnimates, 0);
    define_bool(params, kStaticGrain, "Static grain", "The same grain on every frame (frame 0's)", grain, false);

    const char* optics = "opticsGroup";
    define_group(params, optics, "Optics and format", false);
    define_double(params, kHalation, "Halation", "Multiplies each film layer's halation strength (0 = off)", optics, 1,
                  0, 10, 0, 4);
    define_bool(params, kMtf, "MTF", "Internal scattering in the emulsion (the stock's MTF)", optics, true);
    // The format does not change during a shot.
    define_double(params, kFrameWidth, "Frame width (mm)",
                  "Width of the film frame; with the image width it sets the pixel pitch (0 = the stock's format)",
                  optics, 0, 0, 10000, 0, 70)
        .set(kOfxParamPropAnimates, 0);
    define_double(params, kPrintWidth, "Print width (mm)", "Width of the print (0 = the paper's format)", optics, 0, 0,
                  10000, 0, 500)
        .set(kOfxParamPropAnimates, 0);
    define_choice(params, kFilmFrame, "Film frame",
                  "What the frame width spans: the project's format (a CG element's bounding box or overscan is that "
                  "part of the frame), or the Source image itself (a plate whose format differs from the project's)",
                  optics, {"Project format", "Source image"}, 0);

    const char* colour = "colourGroup";
    define_group(params, colour, "Colour management (OCIO)", false);
    define_string(params, kOcioConfig, "OCIO config",
                  "An OCIO config file; empty uses $OCIO, else Darkroom's embedded config", colour, "", true);
    define_string(params, kInputSpace, "Input colour space", "The colour space of the input pixels", colour,
                  "scene_linear", false);
    define_string(params, kOutputSpace, "Output colour space",
                  "The colour space of the print, negative and texture outputs (density and scan are data, never "
                  "converted)",
                  colour, "scene_linear", false);
}

NodeSettings read_parameters(OfxImageEffectHandle instance, OfxTime time) {
    Reader r(instance, time);
    NodeSettings n;
    DevelopSettings& s = n.develop;

    const std::string film = r.stock_choice(kStockChoices[0]);
    n.film_from_file = film == kStockFileId;
    n.film = n.film_from_file ? stock_file(r, kFilm, kFilmFile) : film;
    s.output = kOutputs[r.checked_choice(kOutput, (int)kOutputs.size())].second;
    s.quality = kQualities[r.checked_choice(kQuality, int(std::size(kQualities)))];
    // Only the print output uses a paper (and only then is its choice checked).
    if (s.output == OutputMode::print) {
        const std::string paper = r.stock_choice(kStockChoices[1]);
        if (paper == kNoPaperId)
            throw ParameterError("the Print output needs a paper: choose one, or the Negative, Density or Scan output");
        n.paper_from_file = paper == kStockFileId;
        n.paper = n.paper_from_file ? stock_file(r, kPaper, kPaperFile) : paper;
    }

    s.exposure_ev = r.checked_double(kExposure, -64, 64);
    s.print_exposure_ev = r.checked_double(kPrintExposure, -64, 64);
    s.printer_lights = r.checked_double3(kPrinterLights, 0, 100);
    s.filtration_ymc = r.checked_double3(kFiltration, 0, 300);

    s.grain = r.get_bool(kGrain);
    s.grain_amount = r.checked_double3(kGrainAmount, 0, 10);
    s.grain_size = r.checked_double3(kGrainSize, 0.05, 20);
    if (r.get_bool(kGrainResponseOverride)) s.grain_density_exponent = r.checked_double3(kGrainResponse, 0, 3);
    int seed = r.get_int(kSeed);
    if (seed < 0) throw ParameterError(r.label(kSeed) + " is " + std::to_string(seed) + ": it must be 0 or more");
    s.seed = (uint64_t)seed;
    // Grain belongs to whole frames: a fractional (motion-blur) time uses its nearest frame.
    if (!std::isfinite(time) || std::abs(time) > 1e9) throw ParameterError("the host asked for time " + std::to_string(time));
    s.frame = r.get_bool(kStaticGrain) ? 0 : (int)std::lround(time);

    s.halation = r.checked_double(kHalation, 0, 10);
    s.mtf = r.get_bool(kMtf);
    s.frame_width_mm = r.checked_double(kFrameWidth, 0, 10000);
    s.print_width_mm = r.checked_double(kPrintWidth, 0, 10000);
    n.film_frame_is_source = r.checked_choice(kFilmFrame, 2) == 1;

    n.grain_profile = r.get_string(kGrainProfile);
    if (!n.grain_profile.empty()) s.grain = false;  // the plate's grain replaces the stock's

    n.ocio_config = r.get_string(kOcioConfig);
    n.input_space = r.get_string(kInputSpace);
    n.output_space = r.get_string(kOutputSpace);
    if (n.input_space.empty()) throw ParameterError(r.label(kInputSpace) + " is empty: name a colour space of the config");
    if (n.output_space.empty()) throw ParameterError(r.label(kOutputSpace) + " is empty: name a colour space of the config");
    return n;
}

namespace {

// The choice set to the option with this id, when one has it.
void set_choice_to(OfxImageEffectHandle instance, const StockChoice& c, const std::string& id) {
    const int index = option_index(stock_options(c.kind), id);
    const Reader r(instance, 0);
    if (index >= 0 && r.get_int(c.choice) != index)
        check(suites.param->paramSetValue(r.handle(c.choice), index), c.choice);
}

// The id parameter set to the option the choice shows.
void record_choice(OfxImageEffectHandle instance, const StockChoice& c) {
    const auto options = stock_options(c.kind);
    const Reader r(instance, 0);
    const int index = r.get_int(c.choice);
    if (index < 0 || index >= int(options.size())) return;  // read_parameters reports it
    check(suites.param->paramSetValue(r.handle(c.id), options[size_t(index)].id.c_str()), c.id);
}

}  // namespace

void restore_stock_choices(OfxImageEffectHandle instance) {
    for (const StockChoice& c : kStockChoices) {
        const std::string saved = Reader(instance, 0).get_string(c.id);
        if (saved.empty())
            record_choice(instance, c);  // a new node, or one saved before the ids were
        else
            set_choice_to(instance, c, saved);  // (an unknown stock stays, for read_parameters to report)
    }
}

void follow_stock_choice(OfxImageEffectHandle instance, const std::string& param, const std::string& reason) {
    for (const StockChoice& c : kStockChoices) {
        if (param == c.choice && reason == kOfxChangeUserEdited) record_choice(instance, c);
        // A host that sets the saved id after creating the node (or a script that sets it).
        if (param == c.id && reason != kOfxChangePluginEdited) set_choice_to(instance, c, Reader(instance, 0).get_string(c.id));
    }
}

}  // namespace darkroom::ofx
