// How well two grain profiles match, in the terms a compositor checks.
//
// - Response error: the mean over A's levels (within the range both profiles cover) of
//   |sigma_B - sigma_A| / sigma_A, in percent.
// - NPS distance: the RMS over radial frequency bins of 10 log10(NPS_B / NPS_A), in dB,
//   over the bins where both spectra are within 20 dB of their peak (below that the
//   power is too small to matter or to be measured).
// - Half-power frequency of each radially averaged NPS (cycles per pixel).
// - Correlation difference: the largest |corr_A - corr_B| between channel pairs.
#pragma once

#include <string>
#include <vector>

#include "core/plate/grain_profile.h"
#include "core/plate/noise_spectrum.h"

namespace darkroom {

struct GrainMatchTolerance {
    double response_percent = 5.0;
    double nps_db = 1.0;
    double correlation = 0.05;
};

struct ChannelMatch {
    std::string name;
    int levels_compared = 0;
    double response_error_percent = 0;
    double nps_distance_db = 0;
    double half_power_a = 0, half_power_b = 0;  // cycles per pixel
    RadialSpectrum nps_a, nps_b;
};

struct GrainMatch {
    std::vector<ChannelMatch> channels;
    std::vector<double> correlation_difference;  // channels x channels, row-major
    double max_correlation_difference = 0;

    bool passes(const GrainMatchTolerance& tolerance = {}) const;
};

// Channels are matched by position; throws GrainProfileError if the counts differ.
GrainMatch compare_grain_profiles(const GrainProfile& a, const GrainProfile& b);

}  // namespace darkroom
