#include "ocio/config.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <sstream>

namespace darkroom::ocio {

namespace {

namespace fs = std::filesystem;

// ---- Building blocks of the embedded config ----

OCIO::TransformRcPtr builtin(const char* style, OCIO::TransformDirection direction = OCIO::TRANSFORM_DIR_FORWARD) {
    OCIO::BuiltinTransformRcPtr t = OCIO::BuiltinTransform::Create();
    t->setStyle(style);
    t->setDirection(direction);
    return t;
}

OCIO::GroupTransformRcPtr group(std::initializer_list<OCIO::TransformRcPtr> steps) {
    OCIO::GroupTransformRcPtr g = OCIO::GroupTransform::Create();
    for (const OCIO::TransformRcPtr& step : steps) g->appendTransform(step);
    return g;
}

// Encoded -> linear for a power law with a linear toe:
// ((v + offset) / (1 + offset))^exponent above the break.
OCIO::TransformRcPtr power_decode(double exponent, double offset) {
    OCIO::ExponentWithLinearTransformRcPtr t = OCIO::ExponentWithLinearTransform::Create();
    t->setGamma({exponent, exponent, exponent, 1.0});
    t->setOffset({offset, offset, offset, 0.0});
    return t;
}

}  // namespace

// Cineon printing-density log -> linear (Kodak constants, see config.h). As a
// LogAffineTransform (lin -> log): v = (300/1023) log10((1 - b) lin + b) + 685/1023,
// since 0.002 density per code value / 0.6 negative gamma = 1/300 log10 per code value.
OCIO::TransformRcPtr cineon_log_to_lin_rec709() {
    const double code_white = 685.0, code_black = 95.0, code_max = 1023.0;
    const double codes_per_decade = 0.6 / 0.002;  // 300
    const double black = std::pow(10.0, (code_black - code_white) / codes_per_decade);
    OCIO::LogAffineTransformRcPtr t = OCIO::LogAffineTransform::Create();
    t->setBase(10.0);
    const double log_slope = codes_per_decade / code_max, log_offset = code_white / code_max;
    t->setLogSideSlopeValue({log_slope, log_slope, log_slope});
    t->setLogSideOffsetValue({log_offset, log_offset, log_offset});
    t->setLinSideSlopeValue({1.0 - black, 1.0 - black, 1.0 - black});
    t->setLinSideOffsetValue({black, black, black});
    t->setDirection(OCIO::TRANSFORM_DIR_INVERSE);
    return t;
}

namespace {

struct SpaceSpec {
    const char* name;
    std::initializer_list<const char*> aliases;
    const char* family;
    const char* encoding;  // OCIO 2.1 encodings: scene-linear, log, sdr-video, data, ...
    const char* description;
};

OCIO::ColorSpaceRcPtr scene_space(const SpaceSpec& spec, OCIO::TransformRcPtr to_reference) {
    OCIO::ColorSpaceRcPtr cs = OCIO::ColorSpace::Create(OCIO::REFERENCE_SPACE_SCENE);
    cs->setName(spec.name);
    for (const char* alias : spec.aliases) cs->addAlias(alias);
    cs->setFamily(spec.family);
    cs->setEncoding(spec.encoding);
    cs->setDescription(spec.description);
    cs->setBitDepth(OCIO::BIT_DEPTH_F32);
    if (to_reference) cs->setTransform(to_reference, OCIO::COLORSPACE_DIR_TO_REFERENCE);
    return cs;
}

OCIO::ColorSpaceRcPtr display_space(const SpaceSpec& spec, OCIO::TransformRcPtr from_reference) {
    OCIO::ColorSpaceRcPtr cs = OCIO::ColorSpace::Create(OCIO::REFERENCE_SPACE_DISPLAY);
    cs->setName(spec.name);
    for (const char* alias : spec.aliases) cs->addAlias(alias);
    cs->setFamily(spec.family);
    cs->setEncoding(spec.encoding);
    cs->setDescription(spec.description);
    cs->setBitDepth(OCIO::BIT_DEPTH_F32);
    if (from_reference) cs->setTransform(from_reference, OCIO::COLORSPACE_DIR_FROM_REFERENCE);
    return cs;
}

// A camera log space: OCIO 2.1 has its "to ACES2065-1" as one built-in.
void add_camera_space(OCIO::Config& config, const SpaceSpec& spec, const char* builtin_style) {
    config.addColorSpace(scene_space(spec, builtin(builtin_style)));
}

OCIO::ConstConfigRcPtr build_embedded_config() {
    OCIO::ConfigRcPtr config = OCIO::Config::Create();
    config->setVersion(2, 1);
    config->setName("darkroom-embedded-v1");
    config->setDescription(
        "Darkroom's embedded config: OCIO 2.1 built-in transforms only, no LUT files. Scene reference "
        "ACES2065-1, display reference CIE XYZ D65. Working space lin_rec709.");

    // ACES spaces.
    config->addColorSpace(scene_space({"ACES2065-1", {"aces2065_1", "ACES - ACES2065-1", "lin_ap0"}, "ACES",
                                       "scene-linear", "ACES2065-1: AP0 primaries, ACES white; the scene reference"},
                                      nullptr));
    config->addColorSpace(scene_space({"ACEScg", {"ACES - ACEScg", "lin_ap1"}, "ACES", "scene-linear",
                                       "ACEScg: scene-linear, AP1 primaries"},
                                      builtin("ACEScg_to_ACES2065-1")));
    config->addColorSpace(scene_space({"ACEScct", {"ACES - ACEScct", "acescct_ap1"}, "ACES", "log",
                                       "ACEScct: log with a linear toe, AP1 primaries"},
                                      builtin("ACEScct_to_ACES2065-1")));
    config->addColorSpace(scene_space({"ACEScc", {"ACES - ACEScc", "acescc_ap1"}, "ACES", "log",
                                       "ACEScc: pure log, AP1 primaries"},
                                      builtin("ACEScc_to_ACES2065-1")));

    // The working space and its encodings.
    config->addColorSpace(scene_space(
        {kWorkingSpaceName,
         {"Linear Rec.709 (sRGB)", "lin_rec709_srgb", "Linear Rec.709", "lin_srgb", "Utility - Linear - sRGB",
          "linear"},
         "Utility", "scene-linear", "Scene-linear, Rec.709 primaries, D65 white: Darkroom's working space"},
        lin_rec709_to_aces2065_1()));
    config->addColorSpace(scene_space(
        {"sRGB - Texture", {"sRGB", "srgb_tx", "srgb_texture", "Utility - sRGB - Texture"}, "Utility", "sdr-video",
         "lin_rec709 encoded with the sRGB piecewise curve (IEC 61966-2-1)"},
        group({power_decode(2.4, 0.055), lin_rec709_to_aces2065_1()})));
    config->addColorSpace(scene_space(
        {"Rec.709 - Camera", {"rec709", "bt709_oetf", "Utility - Rec.709 - Camera"}, "Utility", "sdr-video",
         "lin_rec709 encoded with the ITU-R BT.709 camera OETF"},
        group({power_decode(1.0 / 0.45, 0.099), lin_rec709_to_aces2065_1()})));

    // Camera log spaces OCIO 2.1 has built in.
    add_camera_space(*config,
                     {"ARRI LogC3 (EI800) - AWG",
                      {"logc3", "arri_logc3_ei800_awg", "Input - ARRI - V3 LogC (EI800) - Wide Gamut"},
                      "Camera/ARRI", "log", "ARRI ALEXA LogC v3 at EI 800, ALEXA Wide Gamut"},
                     "ARRI_ALEXA-LOGC-EI800-AWG_to_ACES2065-1");
    add_camera_space(*config,
                     {"Sony S-Log3 - S-Gamut3", {"slog3_sgamut3"}, "Camera/Sony", "log", "Sony S-Log3, S-Gamut3"},
                     "SONY_SLOG3-SGAMUT3_to_ACES2065-1");
    add_camera_space(*config,
                     {"Sony S-Log3 - S-Gamut3.Cine", {"slog3_sgamut3cine"}, "Camera/Sony", "log",
                      "Sony S-Log3, S-Gamut3.Cine"},
                     "SONY_SLOG3-SGAMUT3.CINE_to_ACES2065-1");
    add_camera_space(*config,
                     {"Sony S-Log3 - Venice S-Gamut3", {"slog3_venice_sgamut3"}, "Camera/Sony", "log",
                      "Sony S-Log3, S-Gamut3 of the Venice camera"},
                     "SONY_SLOG3-SGAMUT3-VENICE_to_ACES2065-1");
    add_camera_space(*config,
                     {"Sony S-Log3 - Venice S-Gamut3.Cine", {"slog3_venice_sgamut3cine"}, "Camera/Sony", "log",
                      "Sony S-Log3, S-Gamut3.Cine of the Venice camera"},
                     "SONY_SLOG3-SGAMUT3.CINE-VENICE_to_ACES2065-1");
    add_camera_space(*config,
                     {"RED Log3G10 - REDWideGamutRGB", {"log3g10", "log3g10_rwg"}, "Camera/RED", "log",
                      "RED Log3G10, REDWideGamutRGB"},
                     "RED_LOG3G10-RWG_to_ACES2065-1");
    add_camera_space(*config,
                     {"RED REDLogFilm - REDWideGamutRGB", {"redlogfilm_rwg"}, "Camera/RED", "log",
                      "RED REDLogFilm (Cineon-like), REDWideGamutRGB"},
                     "RED_REDLOGFILM-RWG_to_ACES2065-1");
    add_camera_space(*config,
                     {"Canon Log 2 - Cinema Gamut", {"clog2_cgamut"}, "Camera/Canon", "log",
                      "Canon Log 2, Cinema Gamut (D55)"},
                     "CANON_CLOG2-CGAMUT_to_ACES2065-1");
    add_camera_space(*config,
                     {"Canon Log 3 - Cinema Gamut", {"clog3_cgamut"}, "Camera/Canon", "log",
                      "Canon Log 3, Cinema Gamut (D55)"},
                     "CANON_CLOG3-CGAMUT_to_ACES2065-1");
    add_camera_space(*config,
                     {"Panasonic V-Log - V-Gamut", {"vlog", "vlog_vgamut"}, "Camera/Panasonic", "log",
                      "Panasonic V-Log, V-Gamut"},
                     "PANASONIC_VLOG-VGAMUT_to_ACES2065-1");

    // Film scans.
    add_camera_space(*config,
                     {"ADX10", {"adx10"}, "Film", "log", "Academy Density Exchange, 10-bit scaling (film scans)"},
                     "ADX10_to_ACES2065-1");
    add_camera_space(*config,
                     {"ADX16", {"adx16"}, "Film", "log", "Academy Density Exchange, 16-bit scaling (film scans)"},
                     "ADX16_to_ACES2065-1");
    config->addColorSpace(scene_space(
        {"Cineon Log", {"cineon", "lg10", "KodakLog"}, "Film", "log",  // (KodakLog: OpenImageIO's tag of a log DPX)
         "Kodak Cineon printing-density log (white 685, black 95, 0.002 D/code, gamma 0.6), Rec.709 primaries assumed"},
        group({cineon_log_to_lin_rec709(), lin_rec709_to_aces2065_1()})));

    OCIO::ColorSpaceRcPtr raw = scene_space({"Raw", {"raw", "Utility - Raw"}, "Utility", "data",
                                             "Data: never colour-converted"},
                                            nullptr);
    raw->setIsData(true);
    config->addColorSpace(raw);

    // Display-referred spaces.
    config->addColorSpace(display_space({"CIE-XYZ-D65", {"cie_xyz_d65"}, "Display", "display-linear",
                                         "CIE XYZ, D65 white: the display reference"},
                                        nullptr));
    config->addColorSpace(display_space({"sRGB - Display", {"srgb_display"}, "Display", "sdr-video",
                                         "sRGB monitor: Rec.709 primaries, piecewise sRGB encoding"},
                                        builtin("DISPLAY - CIE-XYZ-D65_to_sRGB")));
    config->addColorSpace(display_space({"Rec.1886 Rec.709 - Display", {"rec1886_rec709_display"}, "Display",
                                         "sdr-video", "HD video monitor: Rec.709 primaries, Rec.1886 (gamma 2.4)"},
                                        builtin("DISPLAY - CIE-XYZ-D65_to_REC.1886-REC.709")));

    // View transforms: scene reference -> display reference.
    OCIO::ViewTransformRcPtr untone = OCIO::ViewTransform::Create(OCIO::REFERENCE_SPACE_SCENE);
    untone->setName("Un-tone-mapped");
    untone->setDescription("Scene-linear values shown as they are (no tone scale): the film print is the tone scale");
    untone->setTransform(builtin("UTILITY - ACES-AP0_to_CIE-XYZ-D65_BFD"), OCIO::VIEWTRANSFORM_DIR_FROM_REFERENCE);
    config->addViewTransform(untone);
    OCIO::ViewTransformRcPtr aces_sdr = OCIO::ViewTransform::Create(OCIO::REFERENCE_SPACE_SCENE);
    aces_sdr->setName("ACES 1.0 - SDR Video");
    aces_sdr->setDescription("ACES 1.0 Output Transform (RRT + ODT) for SDR video, D65");
    aces_sdr->setTransform(builtin("ACES-OUTPUT - ACES2065-1_to_CIE-XYZ-D65 - SDR-VIDEO_1.0"),
                           OCIO::VIEWTRANSFORM_DIR_FROM_REFERENCE);
    config->addViewTransform(aces_sdr);

    for (const char* display : {"sRGB", "Rec.1886 Rec.709"}) {
        const std::string display_cs = std::string(display) + " - Display";
        config->addDisplayView(display, "Standard", "Un-tone-mapped", display_cs.c_str(), "", "", "");
        config->addDisplayView(display, "ACES 1.0 - SDR Video", "ACES 1.0 - SDR Video", display_cs.c_str(), "", "", "");
        config->addDisplayView(display, "Raw", "", "Raw", "", "", "");
    }

    config->setRole(OCIO::ROLE_SCENE_LINEAR, kWorkingSpaceName);
    config->setRole(OCIO::ROLE_DEFAULT, kWorkingSpaceName);
    config->setRole(OCIO::ROLE_RENDERING, kWorkingSpaceName);
    config->setRole(OCIO::ROLE_REFERENCE, "ACES2065-1");
    config->setRole(OCIO::ROLE_INTERCHANGE_SCENE, "ACES2065-1");
    config->setRole(OCIO::ROLE_INTERCHANGE_DISPLAY, "CIE-XYZ-D65");
    config->setRole(OCIO::ROLE_COLOR_TIMING, "ACEScct");
    config->setRole(OCIO::ROLE_COMPOSITING_LOG, "ACEScct");
    config->setRole(OCIO::ROLE_COLOR_PICKING, "sRGB - Texture");
    config->setRole(OCIO::ROLE_TEXTURE_PAINT, "sRGB - Texture");
    config->setRole(OCIO::ROLE_MATTE_PAINT, "sRGB - Texture");
    config->setRole(OCIO::ROLE_DATA, "Raw");

    config->validate();
    return config;
}

std::string config_cache_id(const OCIO::ConstConfigRcPtr& config) {
    try {
        return config->getCacheID();
    } catch (const OCIO::Exception&) {
        // A context variable it cannot resolve: fall back to the contents alone.
        return config->getCacheID(nullptr);
    }
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

// OCIO 2.2 and later name the configs built into them so ("ocio://default"); they are no files.
bool is_builtin_config_name(const std::string& path) { return path.rfind("ocio://", 0) == 0; }

// OCIO's own validation, with the commonest problem said in plain words first.
void validate_config(const ActiveConfig& active, const std::string& hint) {
    if (active.config->getNumDisplays() == 0)
        throw ConfigError(active.name() + " defines no displays, so it has no default display" + hint);
    try {
        active.config->validate();
    } catch (const OCIO::Exception& e) {
        throw ConfigError(active.name() + " is not a valid config: " + e.what() + hint);
    }
}

}  // namespace

// Rec.709 -> AP1 (Bradford D65 -> ACES white) is the inverse of OCIO's AP1 -> Rec.709
// utility; then ACEScg -> ACES2065-1.
OCIO::GroupTransformRcPtr lin_rec709_to_aces2065_1() {
    return group({builtin("UTILITY - ACES-AP1_to_LINEAR-REC709_BFD", OCIO::TRANSFORM_DIR_INVERSE),
                  builtin("ACEScg_to_ACES2065-1")});
}

std::string ActiveConfig::name() const {
    switch (source) {
        case ConfigSource::embedded: return "the embedded Darkroom config";
        case ConfigSource::host_config: return "the OCIO config from " + origin;
        case ConfigSource::explicit_file:
        case ConfigSource::environment: break;
    }
    return "OCIO config " + quoted(path) + " (from " + origin + ")";
}

std::string ActiveConfig::describe() const {
    const std::string which = path.empty() ? name() : "OCIO config " + quoted(path);
    return "colour: " + which + " (" + reason + ")";
}

ActiveConfig load_config_file(const std::string& path, ConfigSource source, const std::string& origin) {
    ActiveConfig active;
    active.source = source;
    active.path = path;
    active.origin = origin;
    const std::string hint =
        source == ConfigSource::environment ? " (unset OCIO, or name a config file, to use another one)" : "";

    std::error_code ec;
    if (!is_builtin_config_name(path)) {
        if (!fs::exists(path, ec)) throw ConfigError(active.name() + " does not exist" + hint);
        if (fs::is_directory(path, ec)) throw ConfigError(active.name() + " is a directory, not a config file" + hint);
    }

    try {
        active.config = OCIO::Config::CreateFromFile(path.c_str());
    } catch (const OCIO::Exception& e) {
        throw ConfigError(active.name() + " cannot be read: " + e.what() + hint);
    }
    validate_config(active, hint);
    active.cache_id = config_cache_id(active.config);
    return active;
}

ActiveConfig from_host_config(OCIO::ConstConfigRcPtr config, const std::string& origin) {
    ActiveConfig active;
    active.source = ConfigSource::host_config;
    active.origin = origin;
    active.reason = "it was given by " + origin;
    if (!config) throw ConfigError(origin + " gave no OCIO config");
    active.config = std::move(config);
    validate_config(active, "");
    active.cache_id = config_cache_id(active.config);
    return active;
}

namespace {

// The config `path` names, active for `reason`. A built-in config name this OCIO cannot load
// (hosts set $OCIO=ocio://default for OCIO 2.2 and later) gives the embedded config instead,
// which serves as well as any for the film model; a file that fails stays an error.
ActiveConfig load_named_config(const std::string& path, ConfigSource source, const std::string& origin,
                               const std::string& reason) {
    try {
        ActiveConfig active = load_config_file(path, source, origin);
        active.reason = reason;
        return active;
    } catch (const ConfigError&) {
        if (!is_builtin_config_name(path)) throw;
    }
    const std::string why = origin + " names " + quoted(path) +
                            ", a config built into OCIO 2.2 and later, which OCIO " + OCIO::GetVersion() +
                            " cannot load";
    ActiveConfig active = embedded_active_config(why);
    active.warning = why + ": using the embedded Darkroom config instead";
    return active;
}

}  // namespace

ActiveConfig resolve_config(const std::string& explicit_path, const std::string& explicit_origin) {
    if (!explicit_path.empty())
        return load_named_config(explicit_path, ConfigSource::explicit_file, explicit_origin,
                                 "given by " + explicit_origin);
    const char* env = std::getenv("OCIO");
    if (env && *env)
        return load_named_config(env, ConfigSource::environment, "$OCIO",
                                 "$OCIO names it and no " + explicit_origin + " was given");
    return embedded_active_config("no " + explicit_origin + " was given and $OCIO is not set");
}

OCIO::ConstConfigRcPtr embedded_config() {
    static const OCIO::ConstConfigRcPtr config = build_embedded_config();
    return config;
}

ActiveConfig embedded_active_config(const std::string& reason) {
    ActiveConfig active;
    active.config = embedded_config();
    active.source = ConfigSource::embedded;
    active.origin = "Darkroom";
    active.reason = reason;
    active.cache_id = config_cache_id(active.config);
    return active;
}

std::string embedded_config_yaml() {
    std::ostringstream yaml;
    embedded_config()->serialize(yaml);
    return yaml.str();
}

std::vector<std::string> color_space_names(const OCIO::Config& config) {
    std::vector<std::string> names;
    // Scene-referred spaces first: they are what pictures come in as.
    for (auto type : {OCIO::SEARCH_REFERENCE_SPACE_SCENE, OCIO::SEARCH_REFERENCE_SPACE_DISPLAY}) {
        const int n = config.getNumColorSpaces(type, OCIO::COLORSPACE_ACTIVE);
        for (int i = 0; i < n; ++i)
            names.emplace_back(config.getColorSpaceNameByIndex(type, OCIO::COLORSPACE_ACTIVE, i));
    }
    return names;
}

std::vector<std::string> display_names(const OCIO::Config& config) {
    std::vector<std::string> names;
    for (int i = 0; i < config.getNumDisplays(); ++i) names.emplace_back(config.getDisplay(i));
    return names;
}

std::vector<std::string> view_names(const OCIO::Config& config, const std::string& display) {
    std::vector<std::string> names;
    for (int i = 0; i < config.getNumViews(display.c_str()); ++i)
        names.emplace_back(config.getView(display.c_str(), i));
    return names;
}

std::string join_names(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + quoted(n);
    return out.empty() ? "(none)" : out;
}

}  // namespace darkroom::ocio
