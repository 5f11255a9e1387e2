#include "core/plate/grain_synthesis.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/parallel.h"
#include "core/random.h"
#include "core/stages/filters.h"

namespace darkroom {

// Cells per segment of a response curve on average: a cell then rarely holds a level, so the
// lookup's walk from the cell's segment is mostly no step.
constexpr int kResponseCellsPerSegment = 16;

ResponseLookup::ResponseLookup(const GrainChannel& channel) {
    curve_.level = channel.level;
    curve_.sigma = channel.sigma;
    const std::vector<double>& level = curve_.level;
    if (level.size() < 2 || !(level.back() > level.front())) return;  // (a single level: its sigma everywhere)
    const size_t cells = kResponseCellsPerSegment * (level.size() - 1);
    cells_per_level_ = double(cells) / (level.back() - level.front());
    for (size_t c = 0; c < cells; ++c) {
        const double start = level.front() + double(c) / cells_per_level_;
        cell_segment_.push_back(uint32_t(std::upper_bound(level.begin(), level.end(), start) - level.begin()));
    }
}

double ResponseLookup::sigma_at(double x) const {
    const std::vector<double>& level = curve_.level;
    if (x <= level.front()) return curve_.sigma.front();
    if (x >= level.back()) return curve_.sigma.back();
    const double cell = std::min((x - level.front()) * cells_per_level_, double(cell_segment_.size() - 1));
    size_t i = cell_segment_[size_t(cell)];
    // To the first level above x, as std::upper_bound (a cell's rounded start may lie past x).
    while (i > 1 && level[i - 1] > x) --i;
    while (level[i] <= x) ++i;
    return curve_.sigma_in_segment(x, i);
}

GrainProfile adjusted_grain_profile(const GrainProfile& profile, const GrainControls& controls) {
    GrainProfile out = profile;
    for (size_t c = 0; c < out.channels.size(); ++c) {
        GrainChannel& ch = out.channels[c];
        const size_t k = std::min<size_t>(c, 2);
        const double centre = 0.5 * (ch.level.front() + ch.level.back()), range = ch.level.back() - ch.level.front();
        for (size_t i = 0; i < ch.level.size(); ++i)
            ch.sigma[i] *= controls.gain[k] * std::exp2(range > 0 ? controls.tilt * (ch.level[i] - centre) / range : 0.0);
        const double size = controls.size[k];
        if (size == 1.0 || ch.acf_radius == 0) continue;
        // rho'(d) = rho(d / size), bilinear between the original lags.
        const GrainChannel original = ch;
        ch.acf_radius = std::max(1, (int)std::ceil(original.acf_radius * size));
        ch.autocorrelation.clear();
        for (int dy = -ch.acf_radius; dy <= ch.acf_radius; ++dy)
            for (int dx = -ch.acf_radius; dx <= ch.acf_radius; ++dx) {
                const double x = dx / size, y = dy / size;
                const int x0 = (int)std::floor(x), y0 = (int)std::floor(y);
                const double tx = x - x0, ty = y - y0;
                ch.autocorrelation.push_back(
                    (1 - ty) * ((1 - tx) * original.acf(x0, y0) + tx * original.acf(x0 + 1, y0)) +
                    ty * ((1 - tx) * original.acf(x0, y0 + 1) + tx * original.acf(x0 + 1, y0 + 1)));
            }
    }
    return out;
}

GrainSynthesisPlan plan_grain_synthesis(const GrainProfile& measured, const GrainControls& controls) {
    validate_grain_profile(measured, "grain profile");
    const GrainProfile profile = adjusted_grain_profile(measured, controls);
    GrainSynthesisPlan plan;
    plan.profile = profile;
    const int n = (int)profile.channels.size();
    for (const GrainChannel& ch : profile.channels) {
        plan.responses.emplace_back(ch);
        plan.kernels.push_back(design_grain_kernel(ch));
        const GrainKernel& k = plan.kernels.back();
        plan.filters.push_back(separable_approximation(k.taps, k.radius, kGrainKernelResidualEnergy));
        plan.halo_px = std::max(plan.halo_px, k.radius);
    }
    std::vector<double> correlation((size_t)n * n), overlap((size_t)n * n);
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const GrainKernel &ka = plan.kernels[a], &kb = plan.kernels[b];
            int r = std::min(ka.radius, kb.radius);
            double sum = 0;
            for (int y = -r; y <= r; ++y)
                for (int x = -r; x <= r; ++x) sum += ka.at(x, y) * kb.at(x, y);
            overlap[(size_t)a * n + b] = sum;
            correlation[(size_t)a * n + b] = profile.correlation(a, b);
        }
    plan.mixing = white_noise_mixing(correlation, overlap, n);
    return plan;
}

void plate_grain_white_noise(uint64_t seed, int frame, int channel, int x0, int n, int y, double* out) {
    const NoiseKey key{seed, frame, kPlateGrainStream + uint32_t(channel)};
    // Pair k holds pixels 2k and 2k + 1 (k = floor(x / 2): GCC shifts negatives arithmetically).
    for (int pair = x0 >> 1; 2 * pair < x0 + n; ++pair) {
        const std::array<double, 2> normals = normal_pair(key, pair, y);
        for (int b = 0; b < 2; ++b)
            if (const int i = 2 * pair + b - x0; i >= 0 && i < n) out[i] = normals[b];
    }
}

void require_profile_fits(int profile_channels, int colour_channels) {
    if (profile_channels != colour_channels && profile_channels != 1)
        throw std::invalid_argument("the grain profile has " + std::to_string(profile_channels) + " channels, the image " +
                                    std::to_string(colour_channels) + " colour channel" + (colour_channels == 1 ? "" : "s") +
                                    " (a profile of the same channels, or a grey one, is needed)");
}

void apply_grain_profile(const GrainSynthesisPlan& plan, const ImageView& image, uint64_t seed, int frame,
                         int threads) {
    const int n = (int)plan.profile.channels.size(), colours = colour_channel_count(image);
    require_profile_fits(n, colours);
    const Window w = image.window;
    if (w.empty()) return;
    // A grey profile on a colour image: its one field on every colour channel (a black-and-white
    // plate's grain is the same silver in each), scaled at each channel's own level.
    const int channels_per_field = colours / n, halo = plan.halo_px;
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        // Each channel's white noise (plate_grain_white_noise, mixed to the profile's channel
        // correlation) through its kernel's separable terms, as the rows stream by.
        const int x0 = w.x0 - halo, padded_width = w.width() + 2 * halo;
        std::vector<std::vector<double>> white(n, std::vector<double>(size_t(padded_width)));
        SeparableStream noise(w.width(), plan.filters, w.y0 - halo, w.y1 + halo, y_end, [&](int y, float* const* padded) {
            for (int c = 0; c < n; ++c) plate_grain_white_noise(seed, frame, c, x0, padded_width, y, white[c].data());
            for (int i = 0; i < padded_width; ++i)
                for (int c = 0; c < n; ++c) {
                    double sum = 0;
                    for (int j = 0; j <= c; ++j) sum += plan.mixing[(size_t)c * n + j] * white[j][i];
                    padded[c][i] = float(sum);
                }
        });
        for (int y = y_begin; y < y_end; ++y) {
            const float* const* grain = noise.row(y);
            for (int x = w.x0; x < w.x1; ++x) {
                float* px = image.at(x, y);
                for (int f = 0; f < n; ++f)
                    for (int c = f * channels_per_field; c < (f + 1) * channels_per_field; ++c)
                        if (std::isfinite(px[c]))
                            px[c] = float(px[c] + plan.responses[f].sigma_at(px[c]) * grain[f][x - w.x0]);
            }
        }
    });
}

void apply_grain_profile(const GrainProfile& profile, const ImageView& image, uint64_t seed, int frame, int threads) {
    apply_grain_profile(plan_grain_synthesis(profile), image, seed, frame, threads);
}

}  // namespace darkroom
