// Baking a per-pixel look into a LUT file that OCIO 2.1 (and so oiiotool
// --ociofiletransform, Nuke, Resolve, ...) applies.
//
// The look is any function on RGB; Darkroom passes the deterministic per-pixel part of
// develop (no grain, MTF or halation) followed by the conversion to the output colour
// space or display. bake_lut samples a function of the file's input; bake_look takes a
// look on the working space and handles the input colour space itself (below), and with
// a LayeredLook (the look as a film composes it) writes a .clf of its stages instead: an
// exposure matrix, log10, a dense 1D curve per channel and, only where the look is
// genuinely 3D (a colour print from the negative's densities), a 3D LUT. A sampled file
// holds a 3D LUT, and for scene-linear input a 1D shaper in front of it so that the
// lattice is spaced evenly in stops:
//
// Shaper (scene-linear input): s(x) = k (log2(x / x_lo) + 1/ln 2) for x >= x_lo, and its
//   tangent line k x / (x_lo ln 2) below x_lo, so s(0) = 0 and the shaper is C1. With
//   x_lo = grey 2^-stops_below and x_hi = grey 2^+stops_above, k = 1 / (stops_below +
//   stops_above + 1/ln 2) makes s(x_hi) = 1. Default grey 0.18 and 8 stops each way:
//   0 .. 46.08 linear, lattice evenly spaced in log2 from 0.000703 up, linear below.
//   Beyond the range, inputs clamp: negative -> the look of 0; above x_hi -> the look of
//   x_hi. Encoded input (log, video: 0..1) needs no shaper; it clamps to 0..1.
//
// Formats (chosen by the file's extension):
//   .clf  Academy/ASC Common LUT Format v3, written by OCIO itself: a Log node
//         (cameraLinToLog, exactly the shaper above) then a LUT3D (tetrahedral); or a
//         LayeredLook's stages (Matrix, Log, LUT1D, LUT3D, Exponent: see LayeredLook).
//   .cube Resolve .cube: LUT_1D_SIZE + LUT_1D_INPUT_RANGE 0 x_hi (the shaper sampled
//         evenly in linear, 16384 points by default) then LUT_3D_SIZE. OCIO 2.1's Resolve
//         reader applies the 1D part as a shaper before the 3D part. The lattice is placed
//         through the sampled (piecewise-linear) shaper exactly as the reader applies it,
//         so the only error is the 3D interpolation. Readers that know only IRIDAS .cube
//         (no 1D part) cannot read such a file; baked from encoded input it is a plain 3D
//         .cube that every reader takes.
// Baking gives the file's text; the program writes it (cli/atomic_file.h).
//
// Pictures in another colour space (bake_look): a .clf starts with the exact OCIO
// operations from that space to the working space (matrices, log curves: no sampling),
// then the shaper and the LUT, so only the look is sampled. A .cube cannot hold them: the
// conversion is folded into the sampled function, through the shaper for scene-linear
// spaces, or directly on the encoded values for log and video spaces.
//
// Accuracy of Darkroom's looks (bake-lut through oiiotool against develop, sRGB display,
// colours over -8 .. +8 stops up to 16 stops apart; docs/development/luts.md): the colour
// print (250D on 2383) as a layered .clf max 9e-6, sampled (.cube) max 0.058, 99th
// percentile 0.0052; a black-and-white print 1e-6 and 0.00066.
// Accuracy of sampling (tests/ocio, "[.lut-accuracy]"): a smooth print-like look to sRGB
// display code values, full scale 1, tetrahedral, 16384 test colours over -9 .. +8 stops:
//   lattice          17^3    33^3    48^3    65^3 (default)
//   working space   0.016   0.0042  0.0019  0.0010   max error, .clf and .cube alike
//                   0.0026  0.00066 0.00031 0.00017  mean error
//   ACEScct, .clf   0.011   0.0029  0.0013  0.0007   max (exact decode in the file)
//   ACEScct, .cube  0.16    0.031   0.015   0.0095   max (AP1 -> Rec.709 sampled on a
//                                                     log lattice curves the function)
// At 65^3 with other inputs (bake_look, in-gamut colours -7 .. +6 stops): .clf max 0.0007
// for ACEScg, LogC3, S-Log3, Cineon and sRGB alike; .cube max 0.011 (ACEScg), 0.0057
// (LogC3), 0.0068 (S-Log3), 0.0011 (Cineon), 0.0002 (sRGB - Texture): for wide-gamut
// pictures prefer .clf. oiiotool --ociofiletransform gives the same numbers as OCIO
// in-process. A .cube shaper of 4096 points costs 0.0017 max at 65^3. Clips inside the
// look (min/max) are kinks, interpolated with an error of about the slope times one cell
// (a hard clip at 1 gave 0.012 at 65^3). 65^3 files are about 8 MB (.cube) and 9.5 MB
// (.clf); 33^3 about 1.2 MB.
//
// Applying them: `oiiotool --colorconfig CONFIG in.exr --ociofiletransform look.cube -o
// out.exr`. oiiotool 2.4 with OCIO 2.1 refuses --ociofiletransform when no config is
// active ($OCIO unset), so give it one: any config works, e.g. the embedded config written
// out (embedded_config_yaml(), `darkroom colorconfig -o FILE`).
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <string>

#include "ocio/config.h"
#include "ocio/transform.h"

namespace darkroom::ocio {

// Maps n packed RGB triplets, in place, from the LUT's input to its output.
using PixelFunction = std::function<void(float* rgb, std::size_t n_pixels)>;

enum class LutFormat { cube, clf };

// What the LUT's input signal is.
enum class LutInput {
    scene_linear,  // HDR scene-linear: log2 shaper in front of the 3D LUT
    encoded,       // already in 0..1 (log or video encoded): 3D LUT only
};

// The log2 shaper with a linear toe described above.
struct LogShaper {
    double mid_grey = 0.18;
    double stops_below = 8.0;
    double stops_above = 8.0;

    double toe_break() const;  // x_lo
    double lin_max() const;    // x_hi
    double slope() const;      // k: shaper units per stop
    double to_shaper(double linear) const;
    double from_shaper(double s) const;
};

struct LutBakeSettings {
    int cube_size = 65;              // lattice points per axis (2..129)
    int cube_shaper_size = 16384;    // .cube only: entries of the sampled 1D shaper
    int curve_size = 16384;          // .clf of a LayeredLook: entries of its Lut1D curves
    LutInput input = LutInput::scene_linear;
    LogShaper shaper;
    std::string title;               // a one-line name for the LUT (CLF name, .cube comment)
    std::string description;         // free text; each line becomes a comment / Description
    // .clf only: exact OCIO operations written before the shaper, from the file's input to
    // the look's input (bake_look fills it in). Null: none.
    OCIO::ConstGroupTransformRcPtr clf_prefix;
};

// A look as a film composes it, for a .clf that holds its stages as they are (bake_look):
//   exposure_c = row c of exposure_matrix . rgb    Matrix (the layers' spectral sensitivities)
//   e_c        = log10 exposure_c                  Log, onto the curves' domain
//   v_c        = channel c of curves(e_c)          Lut1D of curve_size entries (each layer's
//                                                  own curve; beyond the domain, its ends)
//   out        = table(v), where there is one      Lut3D of table_size^3 on the box the curves'
//                                                  values span (tetrahedral), holding the
//                                                  cube roots of table() when table_cube_root,
//                                                  then an Exponent of 3
//   then the output conversion's exact operations.
// Only what the model itself interpolates or what is genuinely 3D is sampled coarsely.
struct LayeredLook {
    std::array<std::array<double, 3>, 3> exposure_matrix{};  // row c: channel c's exposure per unit input
    double log10_exposure_lo = 0, log10_exposure_hi = 0;     // the curves' domain
    // The three channels' curves at one log10 exposure.
    std::function<void(double log10_exposure, double* values)> curves;
    // The 3D stage on the curves' values (null: none), the box it spans per axis (values
    // beyond clamp to it), and whether it is interpolated in cube roots (values spanning
    // decades, such as a print's light).
    std::function<void(const double* values, double* out)> table;
    std::array<double, 3> table_lo{}, table_hi{};
    int table_size = 0;  // lattice points per axis; 0: the settings' cube_size
    bool table_cube_root = false;
    OCIO::ConstProcessorRcPtr output;  // the output conversion after; null: none
    // Names of the file's nodes, saying what each stage is.
    std::string exposure_name = "exposure", curves_name = "curves", table_name = "table";
};

// A baked LUT: the file's text, to be written by the caller (the program writes every output
// through one atomic writer, cli/atomic_file.h).
struct BakedLut {
    LutFormat format = LutFormat::clf;
    std::string summary;  // one line: sizes, shaper and input range
    std::string text;     // the .cube or .clf file
};

// .cube or .clf by the path's extension (case-insensitive); throws OcioError otherwise.
LutFormat lut_format_for_path(const std::string& path);

// Samples `look` on the lattice (one call with every lattice point) into a LUT file's text.
// Throws OcioError for bad settings or a look that returns non-finite values.
BakedLut bake_lut(const PixelFunction& look, const LutBakeSettings& settings, LutFormat format);

// Bakes a look defined on the working space for pictures in `input_space` of the
// converter's config (empty: the working space itself): the LUT's input is
// `input_space`, its output whatever `look_from_working` gives. Chooses the layout described
// above; `settings.input` and `clf_prefix` are set here. With `layered` (the same look as its
// stages compose it) a .clf holds those stages, where the input and output conversions are
// exact OCIO operations; otherwise, and in a .cube, `look_from_working` is sampled.
BakedLut bake_look(const ColorConverter& converter, const std::string& input_space,
                   const PixelFunction& look_from_working, LutBakeSettings settings, LutFormat format,
                   const LayeredLook* layered = nullptr);

}  // namespace darkroom::ocio
