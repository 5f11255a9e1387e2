// A grain profile predicted from a stock and a scan: "Vision3 500T scanned at 4K".
//
// The film model's granularity (core/stages/grain.h: Selwyn-calibrated Gaussian-correlated
// density noise, growing with net density as D^exponent) is sampled at the scan's pixel
// pitch and expressed in a Cineon-style log scan, where density grain is additive, as the
// develop command's scan output writes it (core/develop.h, scan_level):
//   code value = (95 + (D - base) / 0.002) / 1023,
// base the layer's D-min, or balanced (the default, as the scan output's), the density that
// puts a normally exposed mid grey at the aim code (445, Kodak's LAD aim).
// One channel per emulsion layer, in the stock's layer order and named after the layers,
// with independent grain; a one-layer (black-and-white) stock gives three identical,
// fully correlated channels, as an RGB scan of it would.
#pragma once

#include "core/develop.h"
#include "core/plate/grain_profile.h"
#include "core/stock.h"

namespace darkroom {

struct ScanGeometry {
    int width_px = 4096;          // pixels across the frame
    double frame_width_mm = 0;    // 0: the stock's own format
    bool balance = true;          // the scan's balance (DevelopSettings::scan_balance)
    double aim_code = kLadAimCode;
};

// Throws std::invalid_argument for a width < 1 or a stock without layers.
GrainProfile predict_grain_profile(const Stock& stock, const ScanGeometry& scan);

}  // namespace darkroom
