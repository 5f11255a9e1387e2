// Granularity: a spatially correlated density fluctuation, calibrated by Selwyn's law.
//
// The fluctuation is white noise of spectral density W0 (density^2 um^2) filtered by a
// Gaussian of standard deviation `grain_size_um`, so its noise power spectrum is
//   W(f) = W0 exp(-4 pi^2 s^2 f^2).
// W0 is set so that the RMS density read through a 48 um circular aperture at net density
// 1.0 equals the data sheet's RMS granularity:
//   sigma_48^2 = W0 * integral 2 pi f exp(-4 pi^2 s^2 f^2) [2 J1(pi d f)/(pi d f)]^2 df,
// which for s -> 0 is Selwyn's sigma^2 A = W0 (seed paper eq. 8). On the pixel grid the
// white noise has standard deviation sqrt(W0)/pitch per pixel, filtered by the kernel
// whose autocorrelation is that of the field averaged over each pixel (grain.cpp), so the
// per-pixel variance is W0 times the integral of the pixel window squared, as in the
// Boolean model (grain_boolean.h), not W0/pitch^2; scaled with net density as
// (D - Dmin)^exponent.
// The noise is keyed on (seed, frame, layer, absolute pixel), so any window agrees.
#pragma once

#include <memory>
#include <vector>

#include "core/image.h"
#include "core/random.h"
#include "core/stages/filters.h"
#include "core/stages/tables.h"
#include "core/stock.h"

namespace darkroom {

constexpr double kGranularityApertureUm = 48.0;
constexpr double kFastGrainCorrelationTolerance = 0.01;

// sigma_48 / sqrt(W0) for a Gaussian grain of this size: the aperture integral above.
double aperture_rms_per_unit_noise(double grain_size_um, double aperture_diameter_um);

struct GrainModel {
    double sigma_per_pixel = 0;    // sqrt(W0)/pitch: density std of the unfiltered white noise
    std::vector<float> kernel;     // 1D separable filter, 2*radius+1 taps
    int radius = 0;
    float d_min = 0;               // net density is measured from here (as stored in planes)
    double density_exponent = 1.0 / 3.0;
    NoiseKey key;
    // The fast tiers: noise from hashed_noise_run (core/random.h) instead of Philox and
    // Box-Muller (and the amplitude from the H&D table: develop_with_grain), and the kernel's
    // outer taps dropped where the field's correlation at every lag (over its variance)
    // moves by at most kFastGrainCorrelationTolerance (they are a few thousandths of the
    // centre at film pitches: 3 taps of 5).
    bool fast = false;
    // Where a print's paper grain is folded into the film's (fold_paper_grain, develop.cpp):
    // the white noise this layer filters is a weighted sum of the film layers' white noises,
    // the weights' squares summing to 1 (unit variance still), which correlates the layers'
    // grains as the print's channels need. Empty: its own key's noise alone. (Hashed noise
    // only: the fold's tiers are the fast ones.)
    struct NoiseTerm {
        NoiseKey key;
        float weight = 0;
    };
    std::vector<NoiseTerm> mixed_noise;

    // Below this standard deviation (in density) at net density 1 the stage is skipped:
    // it would change transmittance by less than 2.3e-6 relative.
    static constexpr double kNoOpSigma = 1e-6;
    bool is_noop() const;
    // The standard deviation of the filtered field per pixel at net density 1.
    double pixel_sigma_at_unit_density() const;
    // The standard deviation per pixel of unit white noise through the kernel in x and y: the
    // sum of the 1D kernel's squares (the 2D kernel's squares sum to its square).
    double field_sigma() const;
    // The correlation of the filtered field between neighbouring pixels along x (or y).
    double lag1_correlation() const;
    // What the unit noise is scaled by at a developed density: sigma_per_pixel (D - d_min)^exponent.
    double amplitude_at(double density) const;
};

GrainModel design_grain(const GrainSpec& spec, double d_min, double pixel_pitch_um, NoiseKey key, bool fast = false);

// The filtered noise of several grains down the rows of `w`, for one thread: white noise at
// absolute pixels (hashed_noise_run where the grain is fast, else Philox and Box-Muller; its
// mixed_noise's sum where it has one) through each grain's kernel in x and y, so any window
// and any first row agree.
class GrainNoiseStream {
public:
    GrainNoiseStream(const std::vector<const GrainModel*>& grains, const Window& w);
    // Each grain's filtered noise at row y of w (y never decreasing), w's width each, valid
    // until the next call.
    const float* const* row(int y) { return stream_->row(y); }

private:
    std::unique_ptr<SeparableStream> stream_;
};

// The filtered noise field on a window: standard normal noise at absolute pixels,
// convolved with the grain kernel. Its standard deviation per pixel is sum(kernel^2).
Plane grain_field(const GrainModel& grain, const Window& window, int threads);

// The standard deviation (density) the grain adds at a developed density. Per pixel.
double grain_sigma_at(const GrainModel& grain, double density);

// Adds grain to a density plane (its whole window):
// D += amplitude_at(D) * field, never below d_min.
void apply_grain(Plane& density, const GrainModel& grain, int threads);
// The fast tiers' develop and grain in one pass over the rows: `plane` holds exposures and
// becomes densities, D = curve(H) and its amplitude from one lookup of `develop` (built with
// the grain's amplitude_at, tables.h), then grain as apply_grain adds it.
void develop_with_grain(Plane& plane, const LogAxisTable& develop, const GrainModel& grain, int threads);
// One row of it: width exposures to densities (`density` may be `exposure`), with `noise` the
// grain's filtered noise there.
void develop_row_with_grain(const LogAxisTable& develop, const GrainModel& grain, const float* noise, int width,
                            const float* exposure, float* density);

}  // namespace darkroom
