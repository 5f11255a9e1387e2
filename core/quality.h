// Quality tiers: one definition of how each stage is computed at each tier, shared by the
// command line, the plugin, the Python module and the benchmark.
//
//   reference  each stage from its definition: per-pixel spectral printing in double
//              precision, the MTF's full point spread function as a direct 2D sum (summed
//              by FFT in double, the same up to rounding: stages/scatter.h),
//              halation as its exact Gaussian, grain as silver disks (a Boolean model,
//              Newson et al. 2017) rendered at the film's scale
//   high       the same spectral printing; the PSF as a sum of separable terms (every tap
//              within 1e-6 of the largest); grain as filtered Gaussian noise
//   fast       the print of a colour negative as one 3D table from the negative's densities
//              to the print's colour, the paper's MTF applied to the negative's densities
//              and its grain folded into the film's; the PSF tapered to a compact kernel (a
//              centre delta and separable terms), halation on an 8x coarser grid, the DIR
//              couplers on a grid up to 1.25 times their inhibitor's standard deviation
//              (its spread, the donors and the inhibition's factors there), tabulated
//              H&D curves, grain from hashed noise (sums of uniform bytes: core/random.h)
//              through a kernel without its negligible outer taps
//   preview    as fast, on a proxy of the frame whose pixels are NxN blocks of the frame's
//              (N times the pixel pitch: grain, MTF and halation keep their size on the
//              film), averaged down from the frame's pixels and its result upsampled
//              bilinearly: N is the smallest factor from 2 that leaves the proxy at most
//              2^20 pixels (about 1 MP: HD and 2K at half resolution, 4096x2160 at a third,
//              larger frames coarser), so its stages cost about the same at any frame size,
//              for scrubbing and dragging sliders
//
// Every tier is measured against the reference by `darkroom bench`.
#pragma once

#include <optional>
#include <string>

#include "core/stages/scatter.h"

namespace darkroom {

enum class Quality { reference, high, fast, preview };

enum class GrainMethod {
    boolean_model,   // silver disks (stages/grain_boolean.h)
    filtered_noise,  // Gaussian noise (Philox, Box-Muller) filtered to the grain's spectrum
    hashed_noise,    // the same spectrum from hashed byte sums and a tabulated amplitude
};

struct QualityTier {
    Quality quality;
    const char* name;
    ScatterDesign scatter;    // the MTF's kernel (stages/scatter.h)
    int halation_decimation;  // halation on a grid this many times coarser (1: the pixels)
    // The DIR couplers' inhibitor spread on a grid up to this many times coarser (1: the
    // pixels), its spacing at most 1.25 of the Gaussian's standard deviations, the donors and
    // the inhibition's factors evaluated there too (stages/couplers.h).
    int coupler_decimation;
    GrainMethod grain;
    // Printing a colour negative on colour paper: 0 = per-pixel spectral integration in
    // double; otherwise one 3D table of this many nodes per axis from the negative's densities
    // to the print's linear Rec.709 (held as cube roots): the enlarger, the paper's H&D curves
    // and the viewing composed, which needs the paper's stages between them to be pointwise.
    // So the paper's MTF is applied before, to the negative's densities (as accurate as on
    // its transmittance against the reference, measured, and two passes cheaper), the paper's
    // grain is folded into the film's (develop.cpp, fold_paper_grain), and its halation is
    // left out.
    int print_table_nodes;
    // H&D curves: 0 = evaluated per pixel; otherwise a table with 2^bits samples per
    // octave of exposure (stages/tables.h).
    int curve_table_bits;
    // 0: every stage at the frame's pixels; otherwise on a proxy of at most this many pixels
    // (proxy_factor), with the settings above, its result upsampled to the frame's pixels
    // (core/develop_proxy.cpp).
    long long proxy_pixel_budget;
};

// The proxy's pixel pitch over the frame's for a film frame of this many pixels: 1 where the
// tier has no proxy, else the smallest integer N >= 2 whose proxy frame (ceil(width / N) x
// ceil(height / N) pixels, blocks counted from the film frame's origin) holds at most
// tier.proxy_pixel_budget pixels. It depends on the film frame alone, never on an image's
// window, a tile or the threads, so every render of a frame reads the same proxy.
int proxy_factor(const QualityTier& tier, int film_width_px, int film_height_px);

// The default of the command line, the plugin and the Python module: the fastest tier
// within the product's colour budget (mean CIEDE2000 <= 0.5 against the reference), from the
// benchmark's Pareto table (docs/development/quality-tiers.md).
constexpr Quality kDefaultQuality = Quality::fast;

const QualityTier& quality_tier(Quality q);
const char* quality_name(Quality q);
std::optional<Quality> parse_quality(const std::string& name);
// The tiers in order, reference first.
constexpr Quality kQualities[] = {Quality::reference, Quality::high, Quality::fast, Quality::preview};

}  // namespace darkroom
