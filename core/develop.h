// Developing an image: settings + stocks + frame geometry compile into a Plan, which runs
// on any window of the frame.
//
// The pipeline is the seed paper's, run twice (Geigel & Musgrave 1997, Fig. 5), per layer
// (one for black-and-white, three for colour):
//   film:  expose -> spectral sensitivity -> halation -> scatter (MTF) -> develop (H&D)
//          -> grain -> dye (the negative's spectral density)
//   print: enlarger light through the negative (stages/print.h) -> paper: the same modules
//   convert: density -> transmittance (negative), log code values (scan) or the print's
//            colour under its viewing light (print)
// A stage that cannot change the result is left out of the plan, with the reason.
//
// Input pixels are scene-linear RGB in the working space (linear Rec.709 primaries, D65)
// or, with InputUnits::lux_seconds, the exposure H itself. Treatment of bad pixels: NaN
// counts as 0 (no light), negative exposure as 0, +Inf and values above 1e30 as 1e30;
// every output is finite.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/image.h"
#include "core/quality.h"
#include "core/stages/grain.h"
#include "core/stages/grain_boolean.h"
#include "core/stages/halation.h"
#include "core/stages/print.h"
#include "core/stages/scatter.h"
#include "core/stages/tables.h"
#include "core/stock.h"

namespace darkroom {

// What a develop run writes (channels 0-2):
//  print     the print's colour, linear Rec.709 (D65), as viewed under the paper's illuminant;
//            for a reversal film, the film itself (the slide) viewed the same way, no paper
//  negative  the negative's transmittance per channel (10^-density)
//  density   the developed diffuse density per layer, as the data sheet's curves give it
//  scan      the negative as a film scanner writes it: Cineon-style log code values / 1023,
//            0.002 density per code value; balanced (DevelopSettings::scan_balance) so that a
//            normally exposed mid grey is at scan_aim_code in every channel, else 95 at each
//            layer's base+fog
//  texture   the input, scene-linear, with the film's grain, MTF and halation applied and
//            its tone and colour unchanged on average
enum class OutputMode { print, negative, density, scan, texture };
enum class InputUnits { scene_linear, lux_seconds };

// The settings' accepted ranges: Plan::compile refuses values outside them, and the look
// layer's parameter table (look/parameters.h) offers these ranges in every front end.
inline constexpr double kMaxExposureEv = 64;      // camera and print exposure, +- stops
inline constexpr double kPrinterLightsAuto = 25;  // points: the automatic light
inline constexpr double kMaxPrinterPoints = 200;  // +- points from the automatic light
inline constexpr double kMaxFiltrationCc = 1000;
inline constexpr double kMaxGrainScale = 100;     // grain amount and size multipliers
inline constexpr double kMaxGrainResponse = 4;    // the density exponent of granularity
inline constexpr double kMaxHalation = 100;       // multiplier of the stock's strength
inline constexpr double kMaxFormatMm = 1e4;       // frame and print widths
inline constexpr double kMaxDirCouplers = 3;      // multiplier of the stock's DIR couplers
inline constexpr double kMaxDirCouplerSpread = 10;  // multiplier of their inhibitor's spread
// The scan output: Cineon-style 10-bit printing-density code values (Kodak Cineon: 0.002
// density per code value, base+fog at code 95), written as code / 1023.
inline constexpr double kScanBaseCode = 95, kScanDensityPerCode = 0.002, kMaxScanCode = 1023;
inline constexpr double kLadAimCode = 445;  // the scan's mid-grey aim (Kodak's LAD)
// A layer density as the scan writes it, code value / 1023: code 95 at base_density.
inline double scan_level(double density, double base_density) {
    return (kScanBaseCode + (density - base_density) / kScanDensityPerCode) / kMaxScanCode;
}
// The density film layer `layer` scans at code 95: its base+fog, or balanced, the density
// that puts a normally exposed mid grey (0 EV at the stock's speed) at `aim_code`.
double scan_base_density(const Stock& film, size_t layer, bool balance, double aim_code);

struct DevelopSettings {
    double exposure_ev = 0.0;        // stops relative to the exposure the ISO speed implies
    double print_exposure_ev = 0.0;  // stops relative to the automatic print exposure
    OutputMode output = OutputMode::print;
    InputUnits input_units = InputUnits::scene_linear;
    bool grain = true;
    bool mtf = true;
    // Halation: multiplies each film layer's halation strength (0 = off).
    double halation = 1.0;
    // DIR couplers of a colour negative (core/stages/couplers.h): multiplies the stock's
    // inhibition matrix (0 = off, the data sheet's curves per pixel) and the spread of its
    // inhibitor on the film (0 = pointwise: interimage colour without edge effects).
    double dir_couplers = 1.0;
    double dir_coupler_spread = 1.0;
    // Per channel (R, G, B; a single-layer stock uses the first): multiplies the layer's RMS
    // granularity and grain size; a finite density_exponent replaces the stock's.
    std::array<double, 3> grain_amount{1.0, 1.0, 1.0};
    std::array<double, 3> grain_size{1.0, 1.0, 1.0};
    std::array<double, 3> grain_density_exponent{NAN, NAN, NAN};
    // Printer lights in points for the red, green and blue paper layers: 25 is the automatic
    // light (a scene mid grey prints neutral at the paper's aim density); one point adds
    // 0.025 log10 exposure to that layer, so more red light gives more cyan dye.
    std::array<double, 3> printer_lights{25.0, 25.0, 25.0};
    // Enlarger colour filtration in CC units (density x 100) of yellow, magenta and cyan
    // filters in the lamp's light, on top of the printer lights.
    std::array<double, 3> filtration_ymc{0.0, 0.0, 0.0};
    // How the print is seen (stages/print.h, PrintView) and whether colours the working space
    // cannot hold are compressed into it.
    PrintViewing print_viewing = PrintViewing::media_relative;
    bool print_gamut_compression = true;
    // The scan output balanced to an aim, as a lab balances its scans: a scene mid grey exposed
    // at the stock's speed (0 EV) lands at scan_aim_code in R, G and B (Kodak's Laboratory Aim
    // Density puts it at 445); false: each layer's base+fog at code 95.
    bool scan_balance = true;
    double scan_aim_code = kLadAimCode;
    // How each stage is computed (core/quality.h).
    Quality quality = kDefaultQuality;
    uint64_t seed = 0;
    int frame = 0;
    double frame_width_mm = 0.0;  // width of the film frame; 0 = the film stock's format
    double print_width_mm = 0.0;  // width of the print; 0 = the paper stock's format
};

// How a plan is built where the pixels are the same either way, so that tests and the
// benchmark can compare the structures: not a setting of the look.
struct PlanStructure {
    // Leave out the stages that cannot change the result (and say why in describe()).
    // false runs them with their neutral values: leaving them out changes no pixel and saves
    // their time.
    bool skip_noop_stages = true;
    // The fast tiers run every stage a row at a time, so that the frame's planes never meet in
    // memory (develop_one_pass.cpp); false runs them stage after stage over whole planes, as
    // the other tiers do: the same pixels.
    bool one_pass = true;
};

// What the full frame is: its size in pixels. Render scale is already in the size (a
// half-resolution proxy is a frame half as wide, so the pixel pitch doubles).
struct FrameGeometry {
    int width = 0, height = 0;
    // The input is grey (one colour channel): each layer's spectral exposure is then one
    // scale of it, the sum of the layer's RGB weights.
    bool monochrome = false;
    // An image that is not exactly the film frame (a file whose data window differs from its
    // display window: a CG element's bounding box, or overscan): where its first pixel sits
    // relative to the film frame's origin, and the film frame's width in pixels (0: the
    // image's width), and its height (0: the image's height; it sets the preview tier's
    // proxy factor alone: quality.h). The pixel pitch is the film frame's width over
    // film_width, and the image's pixels have absolute coordinates from (x0, y0), so grain
    // falls on the same film-frame pixels whatever part of the frame a file holds; filters
    // clamp at the image.
    int x0 = 0, y0 = 0;
    int film_width = 0;
    int film_height = 0;
    int film_width_px() const { return film_width > 0 ? film_width : width; }
    int film_height_px() const { return film_height > 0 ? film_height : height; }
};

// The preview tier's proxy factor for this frame (quality.h, proxy_factor; 1: no proxy).
int proxy_factor(const QualityTier& tier, const FrameGeometry& frame);

// The frame of the preview tier's proxy at `factor` (proxy_factor): each of its pixels a
// factor x factor block of the film frame's, blocks counted from the film frame's origin (an
// image's window grows to whole blocks), so its pixel pitch is `factor` times the frame's.
FrameGeometry proxy_geometry(const FrameGeometry& frame, int factor);

// The frame's pixels the preview's proxy reads (develop_rows.h, block_mean_row).
struct ProxyBlocks;

// One material's run of the pipeline, precomputed (core/material_stages.h: the plan's
// internals, not part of the API).
struct MaterialStages;

// The fast tiers develop and add grain in one pass over the rows (one table lookup gives a
// pixel's density and its grain amplitude), timed as one stage.
constexpr const char* kDevelopAndGrainStage = "develop + grain";

// Seconds a run spent in each stage (summed over layers), for the benchmark.
struct StageTimes {
    std::vector<std::pair<std::string, double>> seconds;  // in pipeline order
    void add(const std::string& stage, double s);
};

class Plan {
public:
    // Throws std::invalid_argument naming the problem for unusable settings. The tables a
    // plan builds (the fast tiers' print table, the folded grain) are built on `threads`
    // threads (0: every core), the budget a host or --threads gives renders too; their values
    // do not depend on how many.
    static Plan compile(const Stock& film, const Stock* paper, const DevelopSettings& settings,
                        const FrameGeometry& frame, int threads = 0, const PlanStructure& structure = {});

    // The input window needed to render `output`: grown by the halo and, where a kernel is
    // summed by FFT, to the whole tiles it computes (stages/scatter.h, scatter_input_window),
    // clipped to the frame.
    Window input_window(const Window& output) const;
    // How far the input a pixel needs reaches, in pixels (the film's and the paper's halos).
    int halo_px() const;
    // Renders `out.window` from `in`, which must cover input_window(out.window). The input
    // is grey (1 channel), grey and alpha (2), RGB (3) or RGB and alpha first of the rest
    // (4 or more). Writes channels 0-2 of `out`, and copies the input's alpha to its 4th
    // channel when both have one.
    // With `times`, adds the seconds spent in each stage.
    void run(const ConstImageView& in, const ImageView& out, int threads, StageTimes* times = nullptr) const;

    // The same plan for another frame of a sequence: only the grain's noise depends on the
    // frame, so a sequence compiles once (0.05-0.5 s) and copies the plan per frame.
    Plan for_frame(int frame) const;
    // The same plan for another image of the same film frame (a sequence whose data windows
    // differ, a CG element's bounding box per frame): only the image's window changes. The
    // film frame's width and the grey input must be the plan's, and at the preview tier the
    // film frame's proxy factor (else std::invalid_argument).
    Plan in_image(const FrameGeometry& image) const;

    // The silver grains the reference tier draws per pixel at net density 1, summed over
    // the layers it draws them for (0 at the other tiers). Its time per pixel grows with
    // them, so with the film's area a pixel covers, not with the pixel count.
    double silver_grains_per_pixel() const;
    // The silver grains it draws to render `output`, at net density 1: each layer's grains a
    // pixel over the whole window its grain is rendered on (the output's, or on the negative
    // the print's input window, each grown by the grain's halo and its footprint's reach).
    double silver_grains_drawn(const Window& output) const;

    // The stages in order and those left out, one line each, for -v.
    std::vector<std::string> describe() const;
    // The fast tiers' print table (null where the plan prints otherwise or not at all); for a
    // reversal film, its view table (the film's densities -> the slide's colour).
    const Table3D* print_table() const { return print_table_.get(); }

    // The per-pixel stages one at a time, as run() composes them without grain, MTF and
    // halation, for tools that rebuild the look from them (bake-lut's .clf); not for the
    // texture output:
    //   exposure_l = film_exposure_weights(l) . rgb   (lux-seconds; below 0 no light)
    //   density_l  = film_density(l, exposure_l)
    //   result     = result_of_negative(density)      (channels 0-2 of what run() writes)
    const Stock& film() const;
    std::array<double, 3> film_exposure_weights(size_t layer) const;
    double film_density(size_t layer, double exposure_lux_s) const;
    void result_of_negative(const double* density, double* result) const;

private:
    // The film's densities that render `output` (the paper's input window for a print).
    Window film_output_window(const Window& output) const;
    std::vector<Plane> develop_film(const ConstImageView& in, const Window& film_out, int threads,
                                    StageTimes* times) const;
    std::vector<Plane> print(std::vector<Plane> negative, const Window& out, int threads,
                             StageTimes* times) const;
    std::vector<Plane> texture(const ConstImageView& in, const Window& out, int threads, StageTimes* times) const;
    // Every stage a row at a time (develop_one_pass.cpp): whether this plan can, and the run.
    // With `blocks_of`, this is the preview's proxy and `in` the frame's pixels, read in
    // blocks (develop_rows.h, block_mean_row).
    bool runs_in_one_pass() const;
    void run_one_pass(const ConstImageView& in, const ImageView& out, const Window& out_window, int threads,
                      StageTimes* times, const ProxyBlocks* blocks_of = nullptr) const;
    // The preview tier (develop_proxy.cpp): the proxy's pixels an output window interpolates,
    // and the run: the input averaged down to the proxy, its plan, and the result upsampled.
    Window proxy_window(const Window& output) const;
    void run_proxy(const ConstImageView& in, const ImageView& out, const Window& out_window, int threads,
                   StageTimes* times) const;
    // The plan at the frame's own pixels (compile() wraps it for a proxy tier: then
    // `proxy_factor`, the proxy's pixel pitch over the frame's, sets its grain's amplitude).
    static Plan compile_pixels(const Stock& film, const Stock* paper, const DevelopSettings& settings,
                               const FrameGeometry& frame, int threads, const PlanStructure& structure,
                               int proxy_factor = 1);

    DevelopSettings settings_;
    PlanStructure structure_;
    Window frame_;
    // Shared by the plan's copies for other frames and image windows (for_frame copies the
    // film's and paper's to give their grain the frame).
    std::shared_ptr<const MaterialStages> film_stages_, paper_stages_;
    std::optional<PrintExposure> print_;     // set when the output is a print
    // The fast tiers' print of a colour negative on colour paper: the negative's densities
    // -> the print's linear Rec.709 (QualityTier::print_table_nodes, stages/tables.h). Shared by
    // the copies of a plan (one per frame and image window) and by plans whose print is the
    // same (develop.cpp, shared_print_table).
    std::shared_ptr<const Table3D> print_table_;
    // Per film layer, the density the scan writes at code 95 (convert_row): its base+fog, or
    // where the balance to the aim puts it.
    std::array<double, 3> scan_base_density_{};
    int film_width_px_ = 0;                  // the film frame's width (FrameGeometry)
    bool monochrome_ = false;                // compiled for grey input
    double film_exposure_scale_ = 1.0;       // lux-seconds per unit of input
    bool monochrome_input_ = false;          // the spectral stage is one scale per layer
    std::vector<std::string> skipped_;
    // The print of a reversal film: the film's own densities viewed (through print_table_ in
    // the fast tiers, else spectrally per pixel); no paper.
    bool views_film_ = false;
    void view_film_row(const float* const* density, float* const* rgb, int width) const;
    // The preview tier: the plan of the proxy frame (proxy_geometry), which this one upsamples;
    // null where the plan runs at the frame's pixels. (This plan's other members are the
    // proxy's, for the per-pixel stages above, which do not depend on the pitch.)
    std::shared_ptr<const Plan> proxy_;
    int proxy_factor_ = 1;  // the proxy's pixel pitch over the frame's (proxy_factor)
};

// The fast tiers' print tables and the parts they are built from (the paper's log exposures
// of a grid of negatives, the paper's view) are kept across plans, a few of each, found by
// what they read. Forgets them: the next plan builds its own afresh (tests compare the two).
void forget_print_tables();

// The reference tier's time grows with the film's area a pixel covers, not the pixel count
// (a thumbnail of a whole film frame draws millions of silver grains a pixel). Its budget,
// checked before a render starts: the estimated CPU time of rendering `out` through `plan`
// (Plan::silver_grains_drawn at kReferenceCpuSecondsPerSilverGrain). Above
// kReferenceCpuBudgetSeconds it throws std::invalid_argument, its message naming the tier,
// the window and the estimate; above kReferenceWarningCpuSeconds it returns a warning with
// the estimate; else empty. The program, the Python module and the plugin check it, each
// naming the tiers its own way: `quality_setting` + "reference" ("--quality reference",
// "Quality reference").
// Measured on the benchmark's whole 1024x683 frame at the 4K pitch: 5.3e9 grains drawn,
// about 1 270 s of CPU (0.24 us a grain; a black print's grains cost more, a light one's less).
constexpr double kReferenceCpuSecondsPerSilverGrain = 0.25e-6;
constexpr double kReferenceWarningCpuSeconds = 15 * 60.0;
constexpr double kReferenceCpuBudgetSeconds = 24 * 3600.0;  // a night on a few cores
double reference_cpu_seconds(const Plan& plan, const Window& out);
std::string check_reference_render_budget(const Plan& plan, const Window& out, const std::string& quality_setting);

}  // namespace darkroom
