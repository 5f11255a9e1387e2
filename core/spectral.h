// Spectral quantities on a 380-780 nm grid at 5 nm: colour matching functions,
// illuminants, emulsion sensitivities and RGB -> spectrum upsampling.
#pragma once

#include <array>

namespace darkroom {

constexpr int kSpectralSamples = 81;
constexpr double kWavelengthMinNm = 380.0, kWavelengthMaxNm = 780.0, kWavelengthStepNm = 5.0;
using Spectrum = std::array<double, kSpectralSamples>;

inline double wavelength_nm(int i) { return kWavelengthMinNm + kWavelengthStepNm * i; }
inline int wavelength_index(double nm) { return int((nm - kWavelengthMinNm) / kWavelengthStepNm + 0.5); }

// CIE 1931 2-degree colour matching functions x, y, z.
std::array<Spectrum, 3> cie1931_cmf();

Spectrum blackbody(double kelvin);  // relative, 1 at 560 nm
Spectrum illuminant_d65();

// Black-and-white emulsion types of the seed paper's Fig. 3.
enum class Emulsion { blue_sensitive, orthochromatic, panchromatic };
Spectrum emulsion_sensitivity(Emulsion type);  // relative, peak 1

// The reflectance spectrum of a linear Rec.709 RGB is r b_r + g b_g + b b_b.
const std::array<Spectrum, 3>& rgb_basis_spectra();

// Exposure per unit of each RGB component for a layer of sensitivity S under light E,
// normalised so that neutral RGB (1, 1, 1) gives exposure 1.
std::array<double, 3> rgb_exposure_weights(const Spectrum& sensitivity, const Spectrum& illuminant);

}  // namespace darkroom
