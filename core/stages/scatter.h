// Internal scattering: the emulsion's MTF applied to the exposure as a convolution.
//
// The kernel is the point spread function sampled at pixel centres: the inverse DFT of
// the MTF (f in cycles/mm) periodised over the sampling frequency, truncated where its
// tail holds less than 1e-3 of its weight and normalised to unit sum (MTF(0) = 1:
// scattering moves light, it does not absorb it). Where the PSF is well sampled its
// frequency response is the MTF up to Nyquist.
#pragma once

#include <vector>

#include "core/curve.h"
#include "core/image.h"
#include "core/stages/filters.h"

namespace darkroom {

// The MTF between and beyond its samples: linear between, and past the last sample the
// log-response continues its last slope (never rising), since data sheets stop early.
double mtf_response(const Curve& mtf, double cycles_per_mm);

struct ScatterKernel {
    int radius = 0;            // taps span [-radius, radius] in x and y
    std::vector<float> taps;   // (2r+1)^2, row-major
    // The taps as a sum of separable terms weight_k e_k e_k^T (the kernel is symmetric: its
    // eigen-decomposition), kept when it reproduces every tap within kSeparableTolerance of
    // the largest and costs fewer operations than the direct sum; empty otherwise.
    std::vector<std::vector<float>> separable;  // e_k scaled by sqrt|weight_k|
    std::vector<float> separable_sign;          // sign of weight_k
    // Where the design splits a delta off the centre first (ScatterDesign::centre_term): its
    // weight, the terms then being those of taps - centre delta.
    float centre = 0;
    bool is_identity() const { return radius == 0; }
    // The separable form as a filter: none (it passes its rows through) for the identity, and
    // for a kernel summed directly, which has no terms to run.
    SeparableFilter separable_filter() const { return {separable, separable_sign, centre}; }
    // The (2r+1)^2 taps as the convolution applies them: the separable form's sum where it has
    // one, else `taps`.
    std::vector<double> applied_taps() const;
};
constexpr double kSeparableTolerance = 1e-6;

// Largest |MTF(f) - 1| for f up to the diagonal Nyquist frequency of this pitch: below
// kMtfNoOpTolerance the stage cannot visibly change the image and is skipped.
constexpr double kMtfNoOpTolerance = 1e-4;
double mtf_deviation_to_nyquist(const Curve& mtf, double pixel_pitch_um);

// How a kernel is designed (core/quality.h picks one per tier).
struct ScatterDesign {
    // 0: the PSF's own extent (until its tail holds under 1e-3 of its weight); otherwise
    // a PSF that reaches further is tapered to zero at this radius (a raised cosine over its
    // outer half), its taps then reaching this radius less one, and renormalised: a compact
    // approximation, measured by `darkroom bench`. At least 2 (at 1 it would be a delta).
    int max_radius_px = 0;
    // Split into separable terms within this fraction of the largest tap; 0: never (the
    // direct 2D sum).
    double separable_tolerance = kSeparableTolerance;
    // At most this many separable terms, kept even when the tolerance is not met (the best
    // approximation of that rank: the largest eigen-terms); 0: as many as the tolerance
    // needs, while they cost less than the direct sum.
    int max_terms = 0;
    // Split a delta off the centre tap first, of the weight that leaves the terms' residual
    // smallest, where that takes fewer terms (or, at max_terms, leaves a smaller residual):
    // a compact PSF is a sharp centre over a smooth spread, which one term fits once the
    // centre's spike is out of it, and a delta costs a multiply and an add.
    bool centre_term = false;
};

// Throws std::invalid_argument for an MTF whose response at 0 is not positive (scattering
// is normalised to MTF(0) = 1: there is nothing to normalise). Designs are kept per process
// for the frames of a sequence; the cache is emptied when it holds kMaxCachedKernels.
// Computed on `threads` threads (0: every core), the same kernel on any number.
constexpr size_t kMaxCachedKernels = 64;
ScatterKernel design_scatter_kernel(const Curve& mtf, double pixel_pitch_um, const ScatterDesign& design = {},
                                    int threads = 0);

// dst = src convolved with the kernel (through its separable terms when it has them), for
// dst.window. Reads src with coordinates clamped to `frame`; src.window must cover
// scatter_input_window(kernel, dst.window, frame).
// A kernel without separable terms is the direct 2D sum: computed by FFT from
// kMinFftRadius, the same up to rounding (scatter.cpp, scatter_by_fft), on square tiles of
// a grid of absolute coordinates, each computed whole from its kernel's reach around it, so
// that its pixels are the same bits in every window (the whole frame's).
void scatter(const Plane& src, Plane& dst, const ScatterKernel& kernel, const Window& frame, int threads);
constexpr int kMinFftRadius = 16;
// The window of src that scatter() reads for `out`: out grown by the radius, clipped to the
// frame; for a kernel summed by FFT, first grown to the whole tiles it touches (tiles of
// 2-4 kernel widths less 2r: a 16 px window of a radius-114 kernel reads 512 x 512 px,
// not 244 x 244).
Window scatter_input_window(const ScatterKernel& kernel, const Window& out, const Window& frame);
// The direct 2D sum itself, in double, on `region` of dst (empty: all of dst.window): the
// definition the FFT is tested against.
void scatter_direct(const Plane& src, Plane& dst, const ScatterKernel& kernel, const Window& frame, int threads,
                    const Window& region = {});

}  // namespace darkroom
