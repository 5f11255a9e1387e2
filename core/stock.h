// Film and paper stocks: the sensitometric data the model runs on.
//
// A stock is a list of emulsion layers (one for black-and-white, three for colour), each
// with its spectral sensitivity, characteristic (H&D) curve, MTF and granularity, plus
// the stock's ISO speed. Stocks are data: versioned JSON files (see docs/stock-format.md),
// with the built-in presets compiled in from core/stocks/*.json.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/curve.h"
#include "core/spectral.h"

namespace darkroom {

enum class StockKind {
    negative,  // camera negative film, read by transmission
    paper,     // photographic paper, read by reflection
};

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

struct Layer {
    std::string name;
    Spectrum sensitivity{};  // relative spectral sensitivity, peak 1
    Curve density_curve;     // log10 exposure (lux-seconds) -> diffuse density
    Curve mtf;               // cycles per mm on the material -> modulation response
    GrainSpec grain;
};

struct Stock {
    static constexpr int kFormatVersion = 1;

    std::string id, name;
    StockKind kind = StockKind::negative;
    std::vector<std::string> sources;  // data sheets the numbers come from
    // ISO speed as the standards define it: films 0.8/Hm with Hm the exposure for 0.1
    // over base+fog (ISO 6); papers 1000/Hm at 0.6 over base+fog (ISO 6846).
    double iso_speed = 100.0;
    double frame_width_mm = 36.0;  // the format the stock is usually shot or printed on
    std::vector<Layer> layers;
};

// The constants of the speed definition for a kind of material (seed paper, eq. 5).
struct SpeedDefinition {
    double k;                       // speed = k / Hm
    double density_over_fog;        // Hm is the exposure for this density above base+fog
};
SpeedDefinition speed_definition(StockKind kind);
// log10 of the exposure Hm (lux-seconds) that the stock's ISO speed implies.
double speed_point_log_h(const Stock& stock);

// A stock file that cannot be used: the message names the file, the field and the problem.
struct StockError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Parses a stock from JSON text; `origin` names the file in error messages.
Stock parse_stock_json(const std::string& text, const std::string& origin);
Stock load_stock_file(const std::string& path);
std::string stock_to_json(const Stock& stock);

// Built-in presets, in a stable order.
const std::vector<Stock>& builtin_stocks();
// A built-in id, or a path to a stock file (anything containing '/' or ending in .json).
// Throws StockError listing the built-in ids when neither fits.
Stock find_stock(const std::string& id_or_path);

}  // namespace darkroom
