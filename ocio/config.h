// OpenColorIO configs: which one is active, and the embedded one.
//
// Colour management in Darkroom
// -----------------------------
// The film model works in one scene-linear space: Rec.709 primaries, D65 white
// ("lin_rec709"). Pictures come in from any colour space the active OCIO config knows
// and the model's results (print reflectance, negative transmittance, which are linear
// Rec.709 values too) go out to a colour space or to a (display, view).
//
// Which config is active, in this order:
//   1. one given explicitly: `--colorconfig FILE`, or the OFX host's config;
//   2. the file named by `$OCIO`;
//   3. the embedded config below, built in code from OCIO 2.1 built-in transforms.
// A config that is named (1 or 2) but missing or invalid is an error naming the file and
// the problem: the embedded config is never silently substituted for it. The one exception
// is a config built into OCIO 2.2 and later ("ocio://default"), which hosts set $OCIO to
// and OCIO 2.1 cannot load: the embedded config stands in for it, with a warning.
//
// In a config of the user's, the working space is the first of these colour space names
// (or aliases) that it defines: "lin_rec709", "Linear Rec.709 (sRGB)", "lin_rec709_srgb",
// "Utility - Linear - sRGB", "Linear Rec.709", "lin_srgb"; failing those, linear Rec.709
// is reached through the config's `aces_interchange` role (ACES2065-1) with the same
// built-in transforms the embedded config uses.
//
// The embedded config (OCIO config version 2.1; needs no LUT files)
// ---------------------------------------------------------------
// Scene reference: ACES2065-1. Display reference: CIE XYZ with a D65 white.
// "builtin X" is OCIO's BuiltinTransform style X, as OCIO 2.1.2 names it.
//
// | colour space (main aliases)                 | to the scene reference                           |
// |---------------------------------------------|--------------------------------------------------|
// | ACES2065-1 (aces2065_1, lin_ap0)            | the reference                                    |
// | ACEScg (lin_ap1)                            | builtin ACEScg_to_ACES2065-1                     |
// | ACEScct (acescct_ap1)                       | builtin ACEScct_to_ACES2065-1                    |
// | ACEScc (acescc_ap1)                         | builtin ACEScc_to_ACES2065-1                     |
// | lin_rec709 (Linear Rec.709 (sRGB), lin_srgb,| inverse of builtin UTILITY - ACES-AP1_to_LINEAR- |
// |   linear, Utility - Linear - sRGB)          |   REC709_BFD, then ACEScg_to_ACES2065-1          |
// | sRGB - Texture (sRGB, srgb_tx)              | sRGB piecewise decode (IEC 61966-2-1: exponent   |
// |                                             |   2.4, offset 0.055), then as lin_rec709         |
// | Rec.709 - Camera (rec709, bt709_oetf)       | inverse of the BT.709 camera OETF (exponent      |
// |                                             |   1/0.45, offset 0.099), then as lin_rec709      |
// | ARRI LogC3 (EI800) - AWG (logc3)            | builtin ARRI_ALEXA-LOGC-EI800-AWG_to_ACES2065-1  |
// | Sony S-Log3 - S-Gamut3 / S-Gamut3.Cine,     | builtin SONY_SLOG3-SGAMUT3[.CINE][-VENICE]_to_   |
// |   and the Venice variants                   |   ACES2065-1                                     |
// | RED Log3G10 - REDWideGamutRGB (log3g10)     | builtin RED_LOG3G10-RWG_to_ACES2065-1            |
// | RED REDLogFilm - REDWideGamutRGB            | builtin RED_REDLOGFILM-RWG_to_ACES2065-1         |
// | Canon Log 2 / Canon Log 3 - Cinema Gamut    | builtin CANON_CLOG2/CLOG3-CGAMUT_to_ACES2065-1   |
// | Panasonic V-Log - V-Gamut (vlog)            | builtin PANASONIC_VLOG-VGAMUT_to_ACES2065-1      |
// | ADX10, ADX16 (Academy Density Exchange)     | builtin ADX10/ADX16_to_ACES2065-1                |
// | Cineon Log (cineon, lg10, KodakLog)         | Kodak Cineon printing-density log (below), then  |
// |                                             |   as lin_rec709                                  |
// | Raw (raw, data)                             | none: data, never converted                      |
// | CIE-XYZ-D65 (display-referred)              | the display reference                            |
// | sRGB - Display                              | builtin DISPLAY - CIE-XYZ-D65_to_sRGB            |
// | Rec.1886 Rec.709 - Display                  | builtin DISPLAY - CIE-XYZ-D65_to_REC.1886-REC.709|
//
// Cineon Log follows Kodak's Cineon conversion ("Conversion of 10-bit Log Film Data to
// 8-bit Linear or Video Data for The Cineon Digital Film System", Kodak, 1995): 0.002
// density per 10-bit code value, negative gamma 0.6, reference white at code 685 -> 1.0,
// reference black at code 95 -> 0.0, i.e. with v = code / 1023 and b = 10^((95 - 685) *
// 0.002 / 0.6): lin = (10^((1023 v - 685) * 0.002 / 0.6) - b) / (1 - b), written as an
// OCIO LogAffineTransform. Cineon defines no primaries: Rec.709 is assumed (as Nuke does).
//
// Displays and views (both displays have the same three views; sRGB is the default):
//   sRGB, Rec.1886 Rec.709 -> "Standard": view transform "Un-tone-mapped" (builtin
//   UTILITY - ACES-AP0_to_CIE-XYZ-D65_BFD), i.e. the display's encoding of scene-linear
//   values with no tone scale, because the film print is the tone scale (0.18 linear ->
//   0.4613 on sRGB); "ACES 1.0 - SDR Video": builtin ACES-OUTPUT - ACES2065-1_to_CIE-
//   XYZ-D65 - SDR-VIDEO_1.0, for looking at scene-linear pictures without film; "Raw".
// Roles: scene_linear, default, rendering -> lin_rec709; reference, aces_interchange ->
//   ACES2065-1; cie_xyz_d65_interchange -> CIE-XYZ-D65; color_timing, compositing_log ->
//   ACEScct; color_picking, texture_paint, matte_paint -> sRGB - Texture; data -> Raw.
#pragma once

#include <OpenColorIO/OpenColorIO.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace darkroom::ocio {

namespace OCIO = OCIO_NAMESPACE;

// The model's working space in the embedded config.
inline constexpr const char* kWorkingSpaceName = "lin_rec709";

// Every error this library throws for input the user can fix.
struct OcioError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
// A config file that is missing, unreadable, invalid, or lacks what is asked of it. The
// message names the file (and where its name came from) and the problem.
struct ConfigError : OcioError {
    using OcioError::OcioError;
};
// A colour space, display or view the config does not define. The message lists the
// names the config does define.
struct UnknownNameError : OcioError {
    using OcioError::OcioError;
};

enum class ConfigSource {
    explicit_file,  // --colorconfig, or a config file named by an OFX host
    host_config,    // a config object handed over by a host
    environment,    // $OCIO
    embedded,       // built in code, see above
};

// The config in use, with where it came from, for -v and for error messages.
struct ActiveConfig {
    OCIO::ConstConfigRcPtr config;
    ConfigSource source = ConfigSource::embedded;
    std::string path;      // the file (explicit_file, environment); empty otherwise
    std::string origin;    // who named it: "--colorconfig", "$OCIO", "the OFX host", ...
    std::string reason;    // why this one is active, one sentence
    std::string cache_id;  // OCIO's id of the config's contents; keys the processor cache
    // For the user, when the config named could not be loaded and another stands in for it
    // (a built-in config this OCIO lacks); empty otherwise.
    std::string warning;

    // "OCIO config '/show/config.ocio' (from $OCIO)" or "the embedded Darkroom config".
    std::string name() const;
    // One line for -v, e.g. "colour: OCIO config '/show/config.ocio' (given by
    // --colorconfig)" or "colour: the embedded Darkroom config (no --colorconfig was given
    // and $OCIO is not set)".
    std::string describe() const;
};

// Chooses the active config: `explicit_path` if not empty (named by `explicit_origin`),
// else $OCIO if set and not empty, else the embedded config. Throws ConfigError when the
// named file is missing or invalid; a built-in config name ("ocio://...") this OCIO cannot
// load gives the embedded config, with its `warning` set.
ActiveConfig resolve_config(const std::string& explicit_path = "",
                            const std::string& explicit_origin = "--colorconfig");

// Loads and validates one config file (or OCIO built-in config name, "ocio://..."); throws
// ConfigError naming it and `origin`.
ActiveConfig load_config_file(const std::string& path, ConfigSource source, const std::string& origin);

// Wraps a config object a host already holds (validated here; ConfigError if invalid).
ActiveConfig from_host_config(OCIO::ConstConfigRcPtr config, const std::string& origin);

// The embedded config, built once (thread-safe) and validated.
OCIO::ConstConfigRcPtr embedded_config();
ActiveConfig embedded_active_config(const std::string& reason = "no config was given");
// The embedded config as .ocio YAML, e.g. to start a show config from.
std::string embedded_config_yaml();

// Linear Rec.709 (D65) -> ACES2065-1 from OCIO built-in transforms alone (the inverse
// of UTILITY - ACES-AP1_to_LINEAR-REC709_BFD, then ACEScg_to_ACES2065-1): valid in any
// OCIO 2.1 config. A fresh transform each call, so callers may change its direction.
OCIO::GroupTransformRcPtr lin_rec709_to_aces2065_1();

// Cineon log code values / 1023 -> linear Rec.709 (D65), Kodak's constants as above: the
// "Cineon Log" space of the embedded config, and how the model's scan output is read
// whatever config is active. Valid in any OCIO 2.1 config.
OCIO::TransformRcPtr cineon_log_to_lin_rec709();

// Names the config defines, in its order (active colour spaces: scene-referred, then
// display-referred).
std::vector<std::string> color_space_names(const OCIO::Config& config);
std::vector<std::string> display_names(const OCIO::Config& config);
std::vector<std::string> view_names(const OCIO::Config& config, const std::string& display);

// "a, b, c" (for error messages).
std::string join_names(const std::vector<std::string>& names);

}  // namespace darkroom::ocio
