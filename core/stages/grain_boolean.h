// The reference tier's grain: silver grains as random disks, a Boolean model (Newson,
// Delon & Galerne, "A Stochastic Film Grain Model for Resolution-Independent Rendering",
// Computer Graphics Forum 2017), rendered at the film's scale. Grain centres are a Poisson
// process; each pixel integrates the uncovered area over its footprint (pixel box * the
// grain-size Gaussian), keeping the density's mean exact (10^-net) and the disks' radius set
// per density so that the 48 um RMS granularity is the stock's. Cells of absolute film
// coordinates are drawn from Philox keyed by (seed, frame, stream, cell), so any thread
// count, band or window gives the same bits. The derivation, its limits and its cost:
// docs/model/boolean-grain.md.
#pragma once

#include <cstdint>
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

// The raster of samples a cell's grain is integrated on, exposed for the tests: bit i of row j
// of an m x m raster of spacing h_um is set where a disk of radius_um centred at (x_um[k],
// y_um[k]) um from its corner covers the sample ((i + 0.5) h, (j + 0.5) h); samples 64 w to
// 64 w + 63 of row j are the bits of word [w m + j]. With skip_covered each disk is first
// checked for covering nothing new, as in dark cells (the same bits).
std::vector<uint64_t> boolean_disk_raster(const std::vector<float>& x_um, const std::vector<float>& y_um,
                                          double radius_um, double h_um, int m, bool skip_covered);

// F(c) above (the unit-disk integral), and its lattice sum at spacing h_over_r:
// h^2 sum over n of (exp(c g(h n)/pi) - 1). Exposed for the tests.
double boolean_power_integral(double c);
double boolean_power_lattice_sum(double c, double h_over_r);

}  // namespace darkroom
