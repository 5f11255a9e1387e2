// Sensitometry measured on the simulation, the way a lab measures film: a step wedge for
// speed, contrast, Dmin and Dmax; a uniform patch read through a 48 um aperture for RMS
// granularity; sine targets for the MTF. Each "declared" value is read off the stock's
// own data with the same definition, so the two columns compare like with like.
#pragma once

#include <string>
#include <vector>

#include "core/develop.h"
#include "core/spectral.h"
#include "core/stock.h"

namespace darkroom {

struct Measurement {
    std::string name, unit;
    double declared = 0, measured = 0;
    double tolerance = 0;   // allowed |measured - declared| (see relative)
    bool relative = false;  // tolerance is a fraction of declared
    bool passes() const;
};

struct SensitometryReport {
    std::string stock_id;
    std::vector<Measurement> measurements;  // per layer for colour stocks (names carry the layer)
};

struct SensitometryOptions {
    uint64_t seed = 1;
    int threads = 0;
};

SensitometryReport measure_stock(const Stock& stock, const SensitometryOptions& options = {});

// The grey scale of a film printed on a paper with the automatic lights, as `settings`
// print it (their viewing, gamut and printer lights; grain, MTF and halation left out, which
// do not move a flat patch's mean): a neutral scene patch 0.18 2^ev for each ev, through the
// plan's per-pixel path at the reference tier, and how far each print is from neutral: its
// CIELAB chroma C*ab (D65 white, Y = 1 the white), sqrt(a*^2 + b*^2).
struct GreyPatch {
    double ev = 0;
    Rgb print{};        // linear Rec.709
    double chroma = 0;  // C*ab
};
std::vector<GreyPatch> print_grey_scale(const Stock& film, const Stock& paper, const DevelopSettings& settings,
                                        const std::vector<double>& evs);

// Definitions shared by the measured and declared columns.
// Slope of the steepest least-squares line through any 1.0 log-H span of the curve.
double curve_gamma(const std::vector<double>& log_h, const std::vector<double>& density);
// First frequency where the MTF falls to 0.5 (cycles/mm), from its samples (past the last
// one, along mtf_response's extrapolation).
double mtf50_cycles_per_mm(const Curve& mtf);

}  // namespace darkroom
