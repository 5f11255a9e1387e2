// Film and paper stocks: the sensitometric data the model runs on.
//
// A stock is a list of emulsion layers (one for black-and-white, three for colour: red-,
// green- and blue-sensitive, in that order), each with its spectral sensitivity,
// characteristic (H&D) curve, MTF, granularity and halation, and for colour its dye's
// spectral density; plus the stock's ISO speed, the illuminant it is balanced for and its
// base density. Stocks are data: versioned JSON files (format in docs/reference/stocks.md),
// with the built-in presets compiled in from core/stocks/*.json. Profiles in spektrafilm's
// JSON format are imported too (import_spektrafilm_profile).
#pragma once

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/curve.h"
#include "core/spectral.h"

namespace darkroom {

enum class StockKind {
    negative,    // camera negative film, read by transmission
    paper,       // photographic paper, read by reflection
    print_film,  // print film (e.g. Kodak 2383), printed like paper, projected
    reversal,    // camera reversal (slide) film: a positive on the film itself, projected or scanned
};

// Films a camera exposes (negative or reversal), as opposed to the materials they print on.
inline bool is_camera_film(StockKind kind) { return kind == StockKind::negative || kind == StockKind::reversal; }
// A reversal film's density falls as exposure rises; every other kind's rises.
inline bool density_falls_with_exposure(StockKind kind) { return kind == StockKind::reversal; }

struct GrainSpec {
    // Diffuse RMS granularity: the standard deviation of density read through a 48 um
    // circular aperture at a net diffuse density of 1.0 (Kodak's convention; data sheets
    // print it times 1000, so "17" is 0.017).
    double rms_granularity = 0.0;
    // Standard deviation, in um on the film, of the Gaussian that correlates the density
    // fluctuation (the size of the grain clumps). Data sheets do not publish it.
    double grain_size_um = 0.0;
    // Granularity grows with net density as D^exponent; the seed paper cites the cube root.
    double density_exponent = 1.0 / 3.0;
};

// Light that passes the emulsion, reflects off the film base and exposes it again.
struct HalationSpec {
    double strength = 0.0;   // fraction of the layer's exposure added back, spread out
    double radius_um = 0.0;  // standard deviation of the (Gaussian) spread on the film
};

// DIR (development-inhibitor-releasing) couplers: as a layer develops, its couplers release
// an inhibitor that diffuses through the emulsion and slows development in the same layer
// and the others (docs/model/dir-couplers.md). Inhibition acts as a shift of log exposure:
// receiver layer i develops as if its log10 H were lowered by sum_j matrix[i][j] times the
// net density of donor layer j, blurred by a Gaussian of standard deviation diffusion_um.
struct DirCouplerSpec {
    std::array<std::array<double, 3>, 3> matrix{};  // [receiver][donor], log10 H per unit net density
    double diffusion_um = 0.0;
    bool operator==(const DirCouplerSpec& o) const { return matrix == o.matrix && diffusion_um == o.diffusion_um; }
    bool operator!=(const DirCouplerSpec& o) const { return !(*this == o); }
};

// The default of a colour negative whose file gives no couplers (docs/model/dir-couplers.md:
// the magnitude of published model fits, one value on the diagonal and one off it).
DirCouplerSpec default_dir_couplers();

struct Layer {
    std::string name;
    Spectrum sensitivity{};  // relative spectral sensitivity, peak 1
    Curve density_curve;     // log10 exposure (lux-seconds) -> diffuse density
    // Spectral density of the layer's dye per unit of net density (density above the
    // curve's minimum), peak 1. Black-and-white silver is spectrally flat: all ones.
    Spectrum dye_density = flat_spectrum(1.0);
    Curve mtf;               // cycles per mm on the material -> modulation response
    GrainSpec grain;
    HalationSpec halation;
};

struct Stock {
    static constexpr int kFormatVersion = 2;  // written; versions 1 and 2 are read

    std::string id, name;
    StockKind kind = StockKind::negative;
    std::vector<std::string> sources;  // data sheets the numbers come from
    // ISO speed as the standards define it: negative films 0.8/Hm with Hm the exposure for
    // 0.1 over base+fog (ISO 6); reversal films 10/Hm with Hm the geometric mean of the
    // exposures at 0.2 and 2.0 over D-min (ISO 2240); papers 1000/Hm at 0.6 over base+fog
    // (ISO 6846).
    double iso_speed = 100.0;
    double frame_width_mm = 36.0;  // the format the stock is usually shot or printed on
    // The light the stock is balanced for: the scene light for films, the printer lamp for
    // papers and print films. A neutral scene under it exposes every layer equally.
    std::string exposure_illuminant_name = "D65";
    Spectrum exposure_illuminant = illuminant_d65();
    // Papers and print films: the visual density at which a scene mid grey prints, neutral.
    double mid_grey_aim_density = 0.7447;  // 18 % reflectance
    // Spectral density of the base plus fog (a colour negative's orange mask). The
    // material's spectral density is base + sum over layers of net density x dye density.
    // Black-and-white: flat, the layers' minimum densities.
    Spectrum base_density = flat_spectrum(0.0);
    // Where the data sheet's log H axis starts: 0 for lux-seconds; for sheets that plot log
    // exposure relative to the normal exposure of a mid grey (Kodak's motion-picture
    // sheets), log10 of that exposure at the stock's speed, added to every curve's log H.
    double curve_log_h_offset = 0.0;
    std::vector<Layer> layers;
    // Colour negatives: the couplers the file gives (none: default_dir_couplers()).
    std::optional<DirCouplerSpec> dir_couplers;

    bool is_colour() const { return layers.size() == 3; }
};

// The couplers a stock develops with: a colour negative's own, else the default; other
// stocks (black-and-white, papers, print films) none (a zero matrix).
DirCouplerSpec stock_dir_couplers(const Stock& stock);

// The spectral density of a developed material from its layers' densities (one per layer):
// base + sum_l (D_l - d_min_l) dye_l. Per pixel; layer_d_min, when given, are the layers'
// minimum densities cached by the caller (else each curve's is found again).
Spectrum spectral_density(const Stock& stock, const double* layer_density, const double* layer_d_min = nullptr);

// "negative", "reversal", "paper" or "print-film", as stock files spell the kind.
std::string stock_kind_name(StockKind kind);

// The constants of the speed definition for a kind of material (seed paper, eq. 5).
struct SpeedDefinition {
    double k;                       // speed = k / Hm
    double density_over_fog;        // Hm is the exposure for this density above base+fog
    // Reversal films (ISO 2240): Hm is the geometric mean of the exposure at
    // density_over_fog above D-min (the highlight point) and the exposure at this density
    // above D-min (the shadow point); 0 for the other kinds.
    double shadow_density_over_fog = 0;
};
SpeedDefinition speed_definition(StockKind kind);
// log10 Hm of a characteristic curve by its kind's speed definition (D-min the curve's
// least density); false where the curve never reaches the speed point's densities.
bool curve_speed_point_log_h(const Curve& curve, StockKind kind, double* log_hm);
// Exposure (lux-seconds) a scene mid grey (reflectance 0.18) receives at the stock's speed:
// ISO 2720's reflected-light meter equation, H = q K / S with K = 12.5 and q = 0.65.
double mid_grey_exposure_lux_s(double iso_speed);
// log10 of the exposure Hm (lux-seconds) that the stock's ISO speed implies.
double speed_point_log_h(const Stock& stock);

// A stock file that cannot be used: the message names the file, the field and the problem.
struct StockError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Parses a stock from JSON text (darkroom-stock versions 1 and 2, or a spektrafilm
// profile); `origin` names the file in error messages.
Stock parse_stock_json(const std::string& text, const std::string& origin);
// A spektrafilm profile (its JSON: data.wavelengths, log_sensitivity, channel_density,
// base_density, log_exposure, density_curves). Such profiles hold no MTF and no
// granularity: the stock gets a flat MTF and no grain, and says so in its sources.
Stock import_spektrafilm_profile(const std::string& text, const std::string& origin);
Stock load_stock_file(const std::string& path);
std::string stock_to_json(const Stock& stock);

// Built-in presets, in a stable order.
const std::vector<Stock>& builtin_stocks();
// A built-in id, or a path to a stock file (anything containing '/' or ending in .json).
// Throws StockError listing the built-in ids when neither fits.
Stock find_stock(const std::string& id_or_path);

}  // namespace darkroom
