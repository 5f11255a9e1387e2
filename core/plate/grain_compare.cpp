#include "core/plate/grain_compare.h"

#include <algorithm>
#include <cmath>

namespace darkroom {

namespace {

constexpr double kSpectrumFloor = 0.01;  // -20 dB from the peak

double response_error_percent(const GrainChannel& a, const GrainChannel& b, int& compared) {
    double sum = 0;
    compared = 0;
    for (size_t i = 0; i < a.level.size(); ++i) {
        if (a.level[i] < b.level.front() || a.level[i] > b.level.back() || a.sigma[i] <= 0) continue;
        sum += std::abs(b.sigma_at(a.level[i]) - a.sigma[i]) / a.sigma[i];
        ++compared;
    }
    return compared ? 100.0 * sum / compared : NAN;
}

double spectrum_distance_db(const RadialSpectrum& a, const RadialSpectrum& b) {
    double peak = std::max(*std::max_element(a.power.begin(), a.power.end()),
                           *std::max_element(b.power.begin(), b.power.end()));
    double sum = 0;
    int bins = 0;
    for (size_t i = 0; i < std::min(a.power.size(), b.power.size()); ++i) {
        if (a.power[i] < kSpectrumFloor * peak || b.power[i] < kSpectrumFloor * peak) continue;
        double db = 10.0 * std::log10(b.power[i] / a.power[i]);
        sum += db * db;
        ++bins;
    }
    return bins ? std::sqrt(sum / bins) : NAN;
}

}  // namespace

bool GrainMatch::passes(const GrainMatchTolerance& t) const {
    for (const ChannelMatch& c : channels)
        if (!(c.response_error_percent <= t.response_percent) || !(c.nps_distance_db <= t.nps_db)) return false;
    return max_correlation_difference <= t.correlation;
}

GrainMatch compare_grain_profiles(const GrainProfile& a, const GrainProfile& b) {
    const size_t n = a.channels.size();
    if (b.channels.size() != n)
        throw GrainProfileError("cannot compare grain of " + std::to_string(n) + " channels with grain of " +
                                std::to_string(b.channels.size()));
    GrainMatch match;
    // One frequency grid for both, fine enough for the larger autocorrelation.
    int grid = 64;
    for (size_t c = 0; c < n; ++c)
        while (grid < 4 * std::max(a.channels[c].acf_radius, b.channels[c].acf_radius)) grid *= 2;
    for (size_t c = 0; c < n; ++c) {
        ChannelMatch m;
        m.name = a.channels[c].name;
        m.response_error_percent = response_error_percent(a.channels[c], b.channels[c], m.levels_compared);
        m.nps_a = radial_power_spectrum(a.channels[c], grid);
        m.nps_b = radial_power_spectrum(b.channels[c], grid);
        m.nps_distance_db = spectrum_distance_db(m.nps_a, m.nps_b);
        m.half_power_a = half_power_frequency(m.nps_a);
        m.half_power_b = half_power_frequency(m.nps_b);
        match.channels.push_back(std::move(m));
    }
    match.correlation_difference.resize(n * n);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double d = std::abs(a.correlation((int)i, (int)j) - b.correlation((int)i, (int)j));
            match.correlation_difference[i * n + j] = d;
            match.max_correlation_difference = std::max(match.max_correlation_difference, d);
        }
    return match;
}

}  // namespace darkroom
