// The reference tier's grain: silver grains as random disks, a Boolean model (Newson,
// Delon & Galerne, "A Stochastic Film Grain Model for Resolution-Independent Rendering",
// Computer Graphics Forum 2017), rendered at the film's scale.
//
// Model. Grain centres are a Poisson process of intensity lambda (grains per um^2), each
// grain a disk of radius r; a point of the film is dark where any disk covers it. A pixel's
// transmittance is the uncovered indicator U(x) integrated over the pixel's footprint
//   T = integral U(x) w(x) dx,   w = box(pixel pitch) convolved with a Gaussian of std s,
// s = grain_size_um (the Gaussian truncated at 5 s), and its density is d_min - log10 T.
//
// Mean (Nutting). A point is uncovered when no centre lies within r of it:
//   E[U] = q = exp(-lambda pi r^2),   lambda pi r^2 = net ln 10,   so E[T] = 10^-net.
// Each cell's disks follow the density of the pixel it lies in, and the footprint reaches
// into the neighbouring pixels, so the integral above alone would be the image blurred by the
// footprint's Gaussian (12 % of a pixel's weight beside it at s = 1.5, p = 5 um), which the
// other tiers' grain does not do (the MTF stage is the image's blur). So each pixel keeps
// its own mean and takes the relative fluctuation: T = 10^-net (integral U w) / E, with
// E = sum over cells of (integral of w over the cell) q_cell, the integral's expectation (a
// ratio, so that T stays positive beside a lighter pixel; at least 10^-kNetCap times the
// footprint's weight, never 0). Where the neighbours' densities differ, their disks still
// reach across a pixel's edge by their radius (a spread at the grains' own scale).
// Granularity. Two points at distance h are both uncovered when no centre lies in the union
// of their disks, so the covariance of U is q^2 (exp(lambda gamma_r(h)) - 1), gamma_r the
// overlap area of two disks of radius r. Its integral is the noise power of U at low
// frequencies, W_U(0) = q^2 r^2 F(c), with c = lambda pi r^2 = net ln 10, u = h/r and
//   F(c) = integral over the plane of (exp(c g(u)/pi) - 1) du,
//   g(u) = 2 acos(u/2) - (u/2) sqrt(4 - u^2) for u < 2 (unit disks' overlap), 0 beyond.
// Density linearised about the mean (dD = -dT / (q ln 10)) has low-frequency power
//   W0 = r^2 F(c) / ln(10)^2.
// The filtered-noise model (grain.h) has sigma_48 = sqrt(W0) * aperture_rms_per_unit_noise
// (s, 48) for white noise of power W0 through the same Gaussian, so the radius that gives
// the stock's sigma_48(net) = rms_granularity * net^density_exponent is
//   r(net)^2 = ln(10)^2 (sigma_48(net) / aperture_rms_per_unit_noise(s, 48))^2 / F(net ln 10).
// This holds while the Boolean spectrum is flat over the aperture's passband (its
// covariance vanishes beyond 2 r, a few tenths of a um against the 48 um aperture: the
// relative error in sigma^2 is about (2 pi f r)^2 at f = 1/48 per um, under 1 % for r < 1.5 um)
// and the 48 um reading is small against the mean (second-order terms of the logarithm,
// (sigma_48 ln 10)^2, under 0.2 %). At high density the covered fraction's holes are small
// (F grows as e^c), so r falls quickly: for Vision3 500T's green layer (rms 0.006, 1.2 um,
// exponent 0.5) r is 0.19, 0.16, 0.10 and 0.06 um at net 0.5, 1, 2 and 3.
// Per pixel the variance is W0 times the integral of w^2, which for s well below the pitch p
// is W0 / p^2 (1 - 2 s / (sqrt(pi) p))^2: the filtered-noise model, which blurs white noise
// of variance W0 / p^2 per pixel, reads higher there (by 13 % in sigma at s = 1.2, p = 12 um)
// while both agree through the 48 um aperture and where s is a pixel or more.
//
// Limits, each documented where it applies:
// - net <= 0: no grains (T = 1 except for grains of neighbouring cells that reach in).
// - net > kNetCap (3, 0.1 % transmittance): the model is rendered at kNetCap and the rest of
//   the density added without grain. The radius falls exponentially with density and the
//   work grows as 1/r^2 (five-fold per unit of density), so this bounds it; grain beyond
//   it is in a negative's shoulder or a print's deepest black.
// - r is kept within [kMinRadiusUm, kMaxRadiusUm]; where the calibration asks for more (a
//   very small granularity, or very low density with density_exponent < 1/2) or less, the
//   mean is still exact but the granularity departs from the stock's.
//
// Rendering. The film is cut into square cells of absolute film coordinates (a pixel or
// a fraction of one; a cell takes lambda and r from the density of the pixel it lies in,
// as Newson et al. do). A cell's grain count is Poisson (products of uniforms below a mean
// of 10, Hoermann's PTRS above) and its centres uniform at 16-bit resolution, drawn from
// core/random.h's Philox keyed by (seed, frame, stream, cell). Each cell is sampled on its
// own regular raster of spacing h (uncovered or not at each sample, the coverage by its
// own and neighbouring cells' disks); each sample carries the exact integral of the pixel
// footprint w over its raster square, so the weights of a pixel sum to 1 and E[T] = q
// exactly. Point sampling aliases the disks' edges into low frequencies: by Poisson
// summation the sampled noise power is h^2 times the lattice sum of the covariance,
// against its integral for the continuous model. The spacing is chosen per density so
// that this relative error in W0 is below kAliasingPowerError: h = r/2 up to net 0.5,
// r/2.5 at net 1, r/3.75 at net 2, r/5.5 at net 3; the finest spacing any disk reaching
// the cell needs is used for the whole cell. Pixels are sums over cells in a fixed order of
// absolute cell coordinates, so any thread count, band or window gives the same bits; a
// pixel depends on the densities within halo_px pixels of it (cells beyond the plane's
// window take the nearest pixel's density), so a window equals that window of a full frame
// when the plane it is applied to covers the window grown by halo_px.
//
// Cost: about the number of disks times the raster rows each spans (2 r / h), so it grows
// with density as lambda does. A 256 x 256 flat patch at 12 um pixels of a 500-speed
// negative's grain (rms 0.006, 1.2 um) takes about 7, 19 and 100 CPU seconds at net 0.5,
// 1 and 2 (1.3e9 disks at net 2).
#pragma once

#include <vector>

#include "core/image.h"
#include "core/random.h"
#include "core/stock.h"

namespace darkroom {

struct BooleanGrain {
    static constexpr double kNetCap = 3.0;
    static constexpr double kMinRadiusUm = 0.02;
    static constexpr double kMaxRadiusUm = 3.0;
    static constexpr double kAliasingPowerError = 0.02;
    // A pixel's transmittance reads as at least this (6 above the model's net density), so a
    // footprint that disks cover entirely stays finite.
    static constexpr double kMinTransmittance = 1e-6;

    double pixel_pitch_um = 0;
    double grain_size_um = 0;       // s, the Gaussian in the footprint
    double footprint_reach_um = 0;  // 5 s
    float d_min = 0;
    NoiseKey key;
    bool noop = true;

    // Tables over net density in [0, kNetCap], node i at kNetCap * i / (nodes - 1).
    std::vector<double> radius_um;       // r(net), clamped as above
    std::vector<double> samples_per_um;  // raster samples per um the aliasing bound needs

    int cells_per_pixel = 1;    // cells across a pixel
    double cell_um = 0;         // cell side
    int grain_reach_cells = 1;  // disks reach at most this many cells beyond their own
    int halo_px = 0;            // pixels beyond a pixel whose densities it depends on

    // Same meaning as GrainModel::is_noop: true where the filtered-noise model of this spec
    // would be a no-op, or where the spec is unusable (not finite, negative size or exponent).
    bool is_noop() const { return noop; }
    // r and lambda (per um^2) at a net density (clamped to [0, kNetCap]).
    double radius_at(double net) const;
    double intensity_at(double net) const;
    // Grains whose centres fall in one pixel at a net density (intensity x pitch^2).
    double grains_per_pixel_at(double net) const { return intensity_at(net) * pixel_pitch_um * pixel_pitch_um; }
};

BooleanGrain design_boolean_grain(const GrainSpec& spec, double d_min, double pixel_pitch_um, NoiseKey key);

// Replaces each pixel's density on the plane's whole window by the density of the Boolean
// model whose mean transmittance is that pixel's: net = D - d_min, T = 10^-net. Densities
// that are NaN count as d_min; infinite ones as +-3.4e38.
void apply_boolean_grain(Plane& density, const BooleanGrain& grain, int threads);

// F(c) above (the unit-disk integral), and its lattice sum at spacing h_over_r:
// h^2 sum over n of (exp(c g(h n)/pi) - 1). Exposed for the tests.
double boolean_power_integral(double c);
double boolean_power_lattice_sum(double c, double h_over_r);

}  // namespace darkroom
