// Measuring a plate's grain: the inverse of grain_synthesis.
//
// The plate is cut into square blocks. In each block a least-squares quadratic surface
// stands in for the picture (shading, gentle gradients), and the residual is grain plus
// whatever the surface cannot follow (edges, texture). Blocks are binned by their level;
// a block is kept only while it looks like grain alone:
// - its residual variance is within 3.5 standard deviations (those of the fit residual's
//   sum of squares for grain of the measured autocorrelation: block_surface.h) of the
//   response curve at its level,
// - its own autocorrelation at a few short lags is typical of the kept blocks,
// - its four quadrants' variances agree (stationary), and
// - its gradient covariance's largest eigenvalue is within what grain of the curve's sigma
//   and the measured autocorrelation gives (weak texture, after Liu, Tanaka and Okutomi),
// - the power of its residual's means over an 8 x 8 grid of cells (its low frequencies:
//   gradients and soft shapes a few pixels across) is within what that grain gives, a
//   chi-square test as libaom's noise model makes of block spectra;
//   the curve and these two selections are iterated until the curve settles.
// From the kept blocks:
// - a block's variance: residual sum of squares / (N - tr(P R)), the exact expectation of a
//   fit residual for grain with autocorrelation R (P projects onto the surface); the curve
//   the blocks are selected by is a low quantile of these per level;
// - sigma per level (the response reported): from the 5 x 5 patches of the level's blocks,
//   the mean of the smallest eigenvalues of their covariance whitened by R (picture content
//   is low-rank among patches, after Liu, Tanaka and Okutomi; which eigenvalues are the
//   grain's, after Chen, Zhu and Heng), divided by the same statistic of synthetic grain of
//   that R in as many blocks (its small-sample bias);
// - the autocorrelation: residual products at each lag of the kept blocks in the quieter
//   half of the neighbourhoods (content is spatially coherent, grain is not), normalised by
//   sigma^2 and corrected for the fit the same way (a linear solve, the correction being
//   linear in R);
// - the channel correlation: the pooled correlation of the residuals at lag 0 of the blocks
//   kept in every channel, in the quieter half of the neighbourhoods, each block's normalised
//   by the selection curve.
// Limits: a plate textured alike everywhere cannot be told from coarse grain this way.
// Several frames pool their blocks.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/plate/grain_profile.h"

namespace darkroom {

struct GrainAnalysisSettings {
    int channels = 0;            // channels to analyse (the first ones); 0 = all
    std::vector<std::string> channel_names;  // default R, G, B, then C3, C4, ...
    int block_size_px = 0;       // 0: from the grain's measured correlation (16 to 64 px)
    int level_bins = 16;         // equal-width bins between the lowest and highest block level
    int min_blocks_per_level = 4;  // fewer grain-only blocks: the level is reported as sparse
    std::string colorspace;
    SignalEncoding encoding = SignalEncoding::linear;
    int threads = 0;
};

// A plate that cannot be analysed; the message says what was missing (size, flat areas,
// which channels and levels).
struct GrainAnalysisError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Each view is one frame (or the region of it to analyse).
GrainProfile analyze_grain(const std::vector<ConstImageView>& frames, const GrainAnalysisSettings& settings);

// How far a measured profile can be trusted, from its levels' counts and errors:
// - good: every channel measured at 4 or more levels within 10 % (relative standard error
//   of sigma), levels that hold over half the plate's pixels;
// - usable: every channel at 2 or more levels within 25 %, holding over a quarter of them;
// - unreliable: less (the rest of the plate holds picture content or too few flat blocks).
// A profile without the plate's pixel counts per level weighs its levels alike.
// A profile without samples (predicted) is good. `reason` names the weakest channel.
enum class ProfileQuality { good, usable, unreliable };
struct ProfileAssessment {
    ProfileQuality quality = ProfileQuality::good;
    std::string reason;
};
const char* quality_name(ProfileQuality quality);
ProfileAssessment assess_grain_profile(const GrainProfile& profile);

}  // namespace darkroom
