// Sensitometry measured on the simulation, the way a lab measures film: a step wedge for
// speed, contrast, Dmin and Dmax; a uniform patch read through a 48 um aperture for RMS
// granularity; sine targets for the MTF. Each "declared" value is read off the stock's
// own data with the same definition, so the two columns compare like with like.
#pragma once

#include <string>
#include <vector>

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

// Definitions shared by the measured and declared columns.
// Slope of the steepest least-squares line through any 1.0 log-H span of the curve.
double curve_gamma(const std::vector<double>& log_h, const std::vector<double>& density);
// First frequency where the MTF falls to 0.5 (cycles/mm), from its samples (past the last
// one, along mtf_response's extrapolation).
double mtf50_cycles_per_mm(const Curve& mtf);

}  // namespace darkroom
