// A grain profile predicted from a stock and a scan: "Vision3 500T scanned at 4K".
//
// The film model's granularity (core/stages/grain.h: Selwyn-calibrated Gaussian-correlated
// density noise, growing with net density as D^exponent) is sampled at the scan's pixel
// pitch and expressed in a Cineon-style log scan, where density grain is additive:
//   code value = (95 + (D - Dmin) / 0.002) / 1023.
// One channel per emulsion layer, in the stock's layer order and named after the layers,
// with independent grain; a one-layer (black-and-white) stock gives three identical,
// fully correlated channels, as an RGB scan of it would.
#pragma once

#include "core/plate/grain_profile.h"
#include "core/stock.h"

namespace darkroom {

// Cineon-style printing-density code values, normalised to [0, 1].
constexpr double kCineonBlackCode = 95.0, kCineonDensityPerCode = 0.002, kCineonMaxCode = 1023.0;
double cineon_level_from_net_density(double net_density);

struct ScanGeometry {
    int width_px = 4096;          // pixels across the frame
    double frame_width_mm = 0;    // 0: the stock's own format
};

// Throws std::invalid_argument for a width < 1 or a stock without layers.
GrainProfile predict_grain_profile(const Stock& stock, const ScanGeometry& scan);

}  // namespace darkroom
