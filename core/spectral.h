// Spectral quantities on one wavelength grid: colour matching functions, illuminants,
// colorimetry (XYZ, linear Rec.709, CIELAB, CIEDE2000), RGB -> spectrum upsampling,
// black-and-white emulsion sensitivities and exposure integrals.
//
// Conventions (each function below says only where it differs):
//  - The grid is 380..780 nm in 5 nm steps, 81 samples; a Spectrum holds one value
//    per sample, index i at wavelength_nm(i).
//  - Every wavelength integral is the rectangle rule on the grid,
//    sum_i f(lambda_i) * 5 nm (the summation of CIE 15:2004 section 7.1); all functions
//    here use that one rule, so results computed by different paths agree to rounding.
//  - Illuminants are relative spectral power distributions, 100 at 560 nm (the CIE
//    normalisation); only ratios of illuminant integrals are ever used.
//  - Sensitivities are relative, peak 1. Reflectances are 0..1 for real surfaces but
//    nothing here clamps them unless its name says so.
//  - XYZ is relative: a perfect white reflector under the illuminant in use has Y = 1.
//  - "Linear sRGB" means linear Rec.709 primaries with a D65 white (IEC 61966-2-1),
//    the working space of the pipeline; no transfer function is applied anywhere here.
//  - Double precision throughout. Functions marked "per pixel" neither allocate nor
//    throw; the others may throw std::invalid_argument on bad arguments.
//  - The only shared state is a table of constants (CMFs, the D65 projection, the RGB
//    basis) built once, thread-safely, on first use.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace darkroom {

// ---------------------------------------------------------------------------------------
// Wavelength grid
// ---------------------------------------------------------------------------------------
constexpr int kSpectralSamples = 81;
constexpr double kWavelengthMinNm = 380.0, kWavelengthMaxNm = 780.0, kWavelengthStepNm = 5.0;
using Spectrum = std::array<double, kSpectralSamples>;

constexpr double wavelength_nm(int i) { return kWavelengthMinNm + kWavelengthStepNm * i; }
// Index of the grid sample nearest to nm, clamped to [0, kSpectralSamples - 1].
int wavelength_index(double nm);

// A spectrum equal to value at every wavelength.
Spectrum flat_spectrum(double value);

// Linear interpolation of a tabulated function (nm strictly increasing, any spacing)
// onto the grid. Grid wavelengths outside [nm.front(), nm.back()] get fill. Values are
// not checked (a NaN value spreads to the neighbouring samples). Throws
// std::invalid_argument if the sizes differ, the table is empty, or nm is not finite and
// strictly increasing.
Spectrum resample_to_grid(const double* nm, const double* values, std::size_t count, double fill);
Spectrum resample_to_grid(const std::vector<double>& nm, const std::vector<double>& values, double fill);

// 10^x per sample; samples that are not finite (e.g. the NaN fill of resample_to_grid
// for wavelengths a log-sensitivity table does not cover) become missing_value.
// Typical use: from_log10(resample_to_grid(nm, log_s, NAN), 0.0).
Spectrum from_log10(const Spectrum& log10_values, double missing_value);

// sum += weight * term per sample (a vector of samples at a time, the same values as one at a
// time). Per pixel.
void add_scaled(Spectrum& sum, double weight, const Spectrum& term);

// 10^-density per sample: the transmittance (or reflectance) of a spectral density, within
// 1 ulp of std::exp(-ln 10 density) and the same on every processor (simd::exp_lanes, a
// vector of samples at a time). Per pixel.
Spectrum transmittance_of(const Spectrum& density);

// sum_i a_i b_i, in four interleaved partial sums so that the additions overlap instead of
// each waiting on the last (the per-pixel spectral stages are bound by that wait). Per pixel.
double dot(const Spectrum& a, const Spectrum& b);
// sum_i a_i b_i * 5 nm. Per pixel.
double integrate_product(const Spectrum& a, const Spectrum& b);

// ---------------------------------------------------------------------------------------
// CIE 1931 2-degree colour matching functions
// ---------------------------------------------------------------------------------------
// x-bar, y-bar, z-bar on the grid, from the multi-lobe piecewise-Gaussian fit of
// Wyman, Sloan & Shirley, "Simple Analytic Approximations to the CIE XYZ Color Matching
// Functions", JCGT 2(2), 2013, section 2.2 (not the CIE table itself: the fit's error is
// of the order of the differences between the CIE data sets; chromaticities of D65, D50
// and A through it are within 0.0013 of the CIE figures, see tests).
const std::array<Spectrum, 3>& cie1931_cmf();

// ---------------------------------------------------------------------------------------
// Illuminants (relative SPD, 100 at 560 nm)
// ---------------------------------------------------------------------------------------
// Planck's law at temperature kelvin (> 0) with c2 = 1.4388e-2 m K. A tungsten lamp
// (e.g. an enlarger lamp) is blackbody(3200).
Spectrum blackbody(double kelvin);
// CIE standard illuminant A from its definition (CIE 15:2004 eq. 3.1): Planck's law with
// c2 = 1.435e-2 m K at 2848 K.
Spectrum illuminant_a();
// CIE daylight of correlated colour temperature cct_kelvin in [4000, 25000]
// (CIE 15:2004 section 3.1): chromaticity x_D(T), y_D(x_D), then
// S = S0 + M1 S1 + M2 S2 with M1, M2 rounded to three decimals as the CIE prescribes.
Spectrum cie_daylight(double cct_kelvin);
// The CIE D illuminants. Their nominal temperatures are on the old c2 = 1.4380e-2 scale,
// so D65 is cie_daylight(6500 * 1.4388 / 1.4380) = 6504 K, and likewise D50, D55.
Spectrum illuminant_d50();
Spectrum illuminant_d55();
Spectrum illuminant_d65();

// ---------------------------------------------------------------------------------------
// Colorimetry
// ---------------------------------------------------------------------------------------
using Xyz = std::array<double, 3>;
using Rgb = std::array<double, 3>;  // linear sRGB (Rec.709 primaries, D65 white)
using Lab = std::array<double, 3>;  // CIELAB L*, a*, b*
using Matrix3 = std::array<std::array<double, 3>, 3>;

// IEC 61966-2-1:1999, section 5.2 (XYZ -> linear sRGB) and 5.3 (the inverse), as
// published to four decimals; their product is the identity to about 1e-4.
constexpr Matrix3 kXyzToLinearSrgb{{{3.2406, -1.5372, -0.4986}, {-0.9689, 1.8758, 0.0415}, {0.0557, -0.2040, 1.0570}}};
constexpr Matrix3 kLinearSrgbToXyz{{{0.4124, 0.3576, 0.1805}, {0.2126, 0.7152, 0.0722}, {0.0193, 0.1192, 0.9505}}};

Rgb xyz_to_linear_srgb(const Xyz& xyz);  // per pixel
Xyz linear_srgb_to_xyz(const Rgb& rgb);  // per pixel

// XYZ of a reflectance lit by illuminant, through cie1931_cmf(); a perfect white
// reflector (flat 1) has Y = 1. Per pixel.
Xyz reflectance_to_xyz(const Spectrum& reflectance, const Spectrum& illuminant);
// The illuminant's white: reflectance_to_xyz(flat 1, illuminant).
Xyz white_point_xyz(const Spectrum& illuminant);
// Chromaticity (x, y) = (X, Y) / (X + Y + Z). Per pixel.
std::array<double, 2> xy_chromaticity(const Xyz& xyz);

// CIELAB (CIE 15:2004 section 8.2.1, with its exact form of the cube-root knee) relative
// to white (white Y = 1 gives L* = 100). Per pixel.
Lab xyz_to_lab(const Xyz& xyz, const Xyz& white);
// CIEDE2000 colour difference with kL = kC = kH = 1, as written out in Sharma, Wu &
// Dalal, "The CIEDE2000 Color-Difference Formula: Implementation Notes, Supplementary
// Test Data, and Mathematical Observations", Color Res. Appl. 30(1), 2005, eqs. 1-22.
// Symmetric in its arguments. Per pixel.
double ciede2000(const Lab& lab1, const Lab& lab2);

// Linear sRGB of a reflectance under CIE D65, through cie1931_cmf(). The D65 white
// computed through the fitted CMFs differs from the IEC one by ~1e-4 in xy, so the
// matrix is kXyzToLinearSrgb with its rows rescaled so that the perfect white reflector
// gives exactly (1, 1, 1) (the same primaries with the computed white: the SMPTE RP 177
// construction). This is the exact left inverse of linear_srgb_to_spectrum. Per pixel.
Rgb reflectance_to_linear_srgb(const Spectrum& reflectance);

// Chromatic adaptation within linear sRGB: the matrix M that takes colours seen under a
// light whose white is `white` (linear sRGB, every component > 0) to the corresponding
// colours seen under D65, keeping luminance: a von Kries scaling of linear Rec.709's own
// channels, M = diag(Y / white), Y the white's luminance, so M white = (Y, Y, Y). (Scaling in
// a cone space such as Bradford's mixes the channels: it makes saturated colours negative
// sooner and a channel's grain carry its neighbours'; for the near-neutral whites of print
// bases the two agree closely.) Throws std::invalid_argument unless every component is > 0.
Matrix3 adaptation_to_d65(const Rgb& white);
Rgb multiply(const Matrix3& m, const Rgb& rgb);  // per pixel
// The luminance Y of linear sRGB (the middle row of kLinearSrgbToXyz). Per pixel.
double luminance(const Rgb& rgb);

// Gamut compression towards the neutral axis at constant luminance, for colours the
// working space cannot hold (a negative component). A colour's distance from neutral is
// d = (Y - min(r, g, b)) / Y: 0 on the neutral axis, 1 where a component reaches 0, above
// 1 outside the gamut. Up to kGamutCompressionStart the colour is unchanged; beyond, d is
// compressed smoothly (same value and slope at the start) to
//   s + (1 - s) tanh((d - s) / (1 - s)),  s = kGamutCompressionStart,
// which stays below 1, and the colour moves along its line to (Y, Y, Y) to that distance:
// luminance and the direction from neutral (hue) are kept, and no component is negative.
// Y <= 0 (no light a print can reflect) gives black. Per pixel.
constexpr double kGamutCompressionStart = 0.8;
Rgb compress_to_gamut(const Rgb& rgb);
// compress_to_gamut of n colours given as three rows (rgb[c][i]), in place, in vectors: bit
// for bit its values.
void compress_to_gamut_row(double* const* rgb, int n);

// ---------------------------------------------------------------------------------------
// RGB -> spectrum upsampling
// ---------------------------------------------------------------------------------------
// The three basis reflectances b_r, b_g, b_b of Mallett & Yuksel, "Spectral Primary
// Decomposition for Rendering with sRGB Reflectance", EGSR 2019: on every sample
// 0 <= b <= 1 and b_r + b_g + b_b = 1; reflectance_to_linear_srgb(b_c) is the unit
// primary c; among all such triples they minimise the roughness
// sum_c sum_i (b_c[i+1] - b_c[i])^2. Computed on first use by our own quadratic-program
// solver (ADMM, then an exact active-set polish), deterministic.
const std::array<Spectrum, 3>& rgb_basis_spectra();

// r b_r + g b_g + b b_b. Linear, so reflectance_to_linear_srgb(linear_srgb_to_spectrum(c))
// == c to rounding for every c, including HDR (> 1) values; a neutral (v, v, v) gives the
// flat spectrum v. A negative component (an out-of-gamut colour) can make the spectrum
// negative somewhere: spectrum_is_physical tells, and the clamped variant below exists.
// What the pipeline should do: expose through the linear path (rgb_exposure_weights,
// identical to spectral_exposure) and clamp each layer's resulting exposure at 0, so
// the fast and reference tiers stay identical; clamp spectra only where a physically
// realisable spectrum is itself needed (plots, nonlinear spectral stages). Per pixel.
Spectrum linear_srgb_to_spectrum(const Rgb& rgb);
// max(0, linear_srgb_to_spectrum(rgb)) per sample. Equal to the unclamped spectrum
// whenever that is non-negative (always for r, g, b >= 0); otherwise its colour is no
// longer exactly rgb. Per pixel.
Spectrum linear_srgb_to_spectrum_clamped(const Rgb& rgb);
// True if every sample is >= 0 and finite. Per pixel.
bool spectrum_is_physical(const Spectrum& spectrum);

// ---------------------------------------------------------------------------------------
// Black-and-white emulsion sensitivities (relative, peak 1)
// ---------------------------------------------------------------------------------------
// Smooth analytic shapes drawn after Geigel & Musgrave 1997, Fig. 3 (after Adams,
// The Negative): APPROXIMATE, for the look of each class, not any one film's data sheet.
//  - blue_sensitive: untreated silver halide; peak 430 nm, under 1% from 510 nm.
//  - orthochromatic: plus a green-sensitising dye band peaking ~550 nm, cut off by
//    ~590-600 nm.
//  - panchromatic: plus green and red bands, falling off from ~660 to ~690 nm, with the
//    typical dip near 490-500 nm between the blue and the green sensitivity.
enum class Emulsion { blue_sensitive, orthochromatic, panchromatic };
Spectrum emulsion_sensitivity(Emulsion type);

// ---------------------------------------------------------------------------------------
// Exposure integration
// ---------------------------------------------------------------------------------------
// The exposure a layer of relative sensitivity S receives from light of spectral power
// spectrum * E (a reflectance `spectrum` lit by illuminant E, or any spectral
// distribution relative to E), normalised so that spectrum == flat 1 gives 1:
//   integral(spectrum S E) / integral(S E).
// A spectrum that is 1 at sample k and 0 elsewhere gives S[k] E[k] / sum(S E), so the
// ratios over k reproduce S E (S itself under an equal-energy E). Requires
// integral(S E) > 0 (else the result is not finite). Per pixel.
double exposure_of_spectrum(const Spectrum& spectrum, const Spectrum& sensitivity, const Spectrum& illuminant);

// w_c = exposure_of_spectrum(b_c, S, E) for the three basis spectra: the exposure per
// unit of each linear sRGB component. w sums to 1, so neutral (v, v, v) gives v. Throws
// std::invalid_argument unless integral(S E) > 0 and finite.
std::array<double, 3> rgb_exposure_weights(const Spectrum& sensitivity, const Spectrum& illuminant);

// The reference per-pixel path: exposure_of_spectrum(linear_srgb_to_spectrum(rgb), S, E).
// Equal to dot(rgb_exposure_weights(S, E), rgb) to rounding (same integration rule).
// Per pixel.
double spectral_exposure(const Rgb& rgb, const Spectrum& sensitivity, const Spectrum& illuminant);

}  // namespace darkroom
