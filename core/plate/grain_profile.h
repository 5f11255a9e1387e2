// A plate's grain, measured or predicted: the "darkroom-grain-profile" file format.
//
// Conventions for all of core/plate/:
// - Grain is additive in the plate's own encoding (`encoding`: linear, log or display
//   code values), so `level` and `sigma` are in the same units as the plate's pixels.
// - Per channel: the response curve (standard deviation of the grain against the local
//   signal level), and the spatial structure as the normalised autocorrelation of the
//   grain on lags |dx|, |dy| <= radius (value 1 at lag 0). Its 2D DFT is the noise power
//   spectrum (NPS) shape; the amount lives in the response curve.
// - Between channels: the correlation coefficient of the grain at lag 0.
// - Everything is in pixels of the plate: a profile belongs to a scan resolution.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace darkroom {

enum class SignalEncoding { linear, log, display };
const char* encoding_name(SignalEncoding encoding);
// The encoding a colour-space name implies ("ACEScct", "Cineon": log; "sRGB": display;
// "ACEScg": linear); `fallback` when the name says nothing.
SignalEncoding encoding_of_colorspace(const std::string& colorspace, SignalEncoding fallback);

struct GrainChannel {
    std::string name;
    // Response curve: grain standard deviation at each signal level (sorted ascending).
    std::vector<double> level, sigma;
    // Pixels behind each level, and the relative standard error of its sigma as the level
    // measures it alone (the analysis' confidence; the response pools each level with its
    // neighbours); empty for a predicted profile.
    std::vector<long long> samples;
    std::vector<double> sigma_error;
    // Pixels of the plate at each level, grain-only or not (the trust verdict weighs levels
    // by them); empty for a predicted profile.
    std::vector<long long> plate_samples;
    // The plate's pixels in blocks left out as clipped (holding the channel's lowest or highest
    // value on the plate); 0 for a predicted profile.
    long long clipped_samples = 0;
    // Normalised autocorrelation, (2 radius + 1)^2 values, row-major from (-r, -r).
    int acf_radius = 0;
    std::vector<double> autocorrelation{1.0};

    // Linear interpolation in level, held constant beyond the measured range.
    double sigma_at(double level) const;
    // The same within the curve's segment i, level[i - 1] <= x < level[i] (x inside the range).
    double sigma_in_segment(double level, size_t i) const;
    double acf(int dx, int dy) const;
};

// A level the analysis saw but could not estimate (too few grain-only samples).
struct SparseLevel {
    std::string channel;
    double level = 0;
    long long samples = 0;
    long long plate_samples = 0;  // the plate's pixels at the level, grain-only or not
};

struct GrainProfile {
    static constexpr int kFormatVersion = 1;

    std::string colorspace;  // the plate's colour space as the user named it ("" if unknown)
    SignalEncoding encoding = SignalEncoding::linear;
    std::vector<std::string> sources;  // plates analysed, or the stock and scan predicted from
    std::vector<GrainChannel> channels;
    // channels x channels, row-major, symmetric with a unit diagonal.
    std::vector<double> channel_correlation{1.0};
    // How it was measured (0 and empty for a predicted profile).
    int block_size_px = 0;
    long long blocks_used = 0;
    std::vector<SparseLevel> sparse_levels;

    double correlation(int a, int b) const { return channel_correlation[(size_t)a * channels.size() + b]; }
};

// A profile that cannot be used: the message names the file, the field and the problem.
struct GrainProfileError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// The largest |level| a profile may hold (a linear plate's brightest highlights are far below).
constexpr double kMaxGrainLevel = 1e6;

// Checks the invariants above and the physical ranges (levels within kMaxGrainLevel, sigma no
// larger than the signal range); throws GrainProfileError naming `origin` and the field.
void validate_grain_profile(const GrainProfile& profile, const std::string& origin);

GrainProfile parse_grain_profile_json(const std::string& text, const std::string& origin);
GrainProfile load_grain_profile_file(const std::string& path);
// Also writes derived, informative fields (noise-equivalent area, half-power frequency)
// that parsing ignores.
std::string grain_profile_to_json(const GrainProfile& profile);

}  // namespace darkroom
