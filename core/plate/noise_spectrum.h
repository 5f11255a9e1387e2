// Noise power spectra from autocorrelations (Wiener-Khinchin), radially averaged.
//
// Frequencies are in cycles per pixel (Nyquist 0.5). A channel's autocorrelation is
// normalised, so its NPS integrates to 1 over [-0.5, 0.5]^2: these spectra describe the
// shape of the grain (size, anisotropy), not its amount.
#pragma once

#include <vector>

#include "core/plate/grain_profile.h"

namespace darkroom {

// The 2D NPS on an n x n grid of frequencies (u, v) / n, u, v in [0, n), row-major: the DFT
// of the autocorrelation (real, since the autocorrelation is symmetric). n >= 4 radius.
std::vector<double> power_spectrum_2d(const GrainChannel& channel, int n);

struct RadialSpectrum {
    std::vector<double> cycles_per_px;  // bin centres, up to Nyquist
    std::vector<double> power;          // mean NPS over the annulus
};

// Annuli of width 1/n cycles per pixel; frequencies beyond Nyquist (the corners) are left out.
RadialSpectrum radial_power_spectrum(const GrainChannel& channel, int n = 64);

// The radial frequency where the radially averaged NPS first falls to half its value at 0
// (linear interpolation between bins); Nyquist (0.5) if it never does.
double half_power_frequency(const RadialSpectrum& spectrum);

// NPS at frequency 0 = sum of the autocorrelation: the area (px^2) of white noise with the
// same low-frequency power. 1 for white grain, 4 pi s^2 for Gaussian-filtered grain of std s.
double noise_equivalent_area_px2(const GrainChannel& channel);

// The zero-phase filter whose autocorrelation is the channel's: the inverse DFT of
// sqrt(NPS), cut to the smallest square radius holding 99.999 % of its energy (the tails
// carry the autocorrelation at long lags) and scaled to
// unit energy, so filtered unit white noise has unit variance. (2r+1)^2 taps, row-major.
struct GrainKernel {
    int radius = 0;
    std::vector<double> taps{1.0};
    double at(int dx, int dy) const { return taps[(size_t)(dy + radius) * (2 * radius + 1) + dx + radius]; }
};
GrainKernel design_grain_kernel(const GrainChannel& channel);

}  // namespace darkroom
