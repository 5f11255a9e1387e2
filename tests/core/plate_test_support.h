// Fixtures for the plate-matching tests: grain profiles with known statistics and plates
// (flat patches, ramps, pictures with edges and texture) to put their grain on.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/plate/grain_profile.h"

namespace darkroom::test {

// A known grain: per channel sigma(level) = a + b * level^power and Gaussian-correlated
// grain of size s px (autocorrelation exp(-d^2 / (4 s^2)), that of white noise through a
// Gaussian of std s; s = 0 is white).
struct KnownChannel {
    double a, b, power, size_px;
};

inline GrainProfile known_profile(const std::vector<KnownChannel>& channels, const std::vector<double>& correlation,
                                  SignalEncoding encoding, double level_lo, double level_hi) {
    GrainProfile p;
    p.encoding = encoding;
    const char* names[3] = {"R", "G", "B"};
    for (size_t c = 0; c < channels.size(); ++c) {
        const KnownChannel& k = channels[c];
        GrainChannel ch;
        ch.name = names[c % 3];
        for (int i = 0; i <= 20; ++i) {
            double level = level_lo + (level_hi - level_lo) * i / 20.0;
            ch.level.push_back(level);
            ch.sigma.push_back(k.a + k.b * std::pow(level, k.power));
        }
        ch.acf_radius = k.size_px > 0 ? (int)std::ceil(5.0 * k.size_px) : 0;
        ch.autocorrelation.clear();
        for (int dy = -ch.acf_radius; dy <= ch.acf_radius; ++dy)
            for (int dx = -ch.acf_radius; dx <= ch.acf_radius; ++dx)
                ch.autocorrelation.push_back(k.size_px > 0 ? std::exp(-(dx * dx + dy * dy) / (4.0 * k.size_px * k.size_px))
                                                           : 1.0);
        p.channels.push_back(ch);
    }
    p.channel_correlation = correlation;
    return p;
}

// The grain of the sum of two independent grains, as analysed: per channel the variances add
// at each of a's levels; the autocorrelation and channel correlation are the variance-weighted
// mix of the two, with each channel's weight of a averaged over b's levels (the analysis pools
// blocks of every level into one autocorrelation).
inline GrainProfile sum_of_grains(const GrainProfile& a, const GrainProfile& b) {
    GrainProfile out = a;
    const size_t n = a.channels.size();
    std::vector<double> weight_a(n);
    for (size_t c = 0; c < n; ++c) {
        GrainChannel& ch = out.channels[c];
        const GrainChannel &ca = a.channels[c], &cb = b.channels[c];
        for (size_t i = 0; i < ch.level.size(); ++i) ch.sigma[i] = std::hypot(ca.sigma[i], cb.sigma_at(ca.level[i]));
        double sum = 0;
        for (double level : cb.level) {
            const double va = std::pow(ca.sigma_at(level), 2), vb = std::pow(cb.sigma_at(level), 2);
            sum += va / (va + vb);
        }
        weight_a[c] = sum / cb.level.size();
        ch.acf_radius = std::max(ca.acf_radius, cb.acf_radius);
        ch.autocorrelation.clear();
        for (int dy = -ch.acf_radius; dy <= ch.acf_radius; ++dy)
            for (int dx = -ch.acf_radius; dx <= ch.acf_radius; ++dx)
                ch.autocorrelation.push_back(weight_a[c] * ca.acf(dx, dy) + (1 - weight_a[c]) * cb.acf(dx, dy));
    }
    for (size_t x = 0; x < n; ++x)
        for (size_t y = 0; y < n; ++y)
            if (x != y)
                out.channel_correlation[x * n + y] = std::sqrt(weight_a[x] * weight_a[y]) * a.correlation(x, y) +
                                                     std::sqrt((1 - weight_a[x]) * (1 - weight_a[y])) * b.correlation(x, y);
    return out;
}

// Square patches of levels spread over [lo, hi], each `patch` px wide.
inline Image flat_patches(int width, int height, int channels, double lo, double hi, int patch = 128) {
    Image img(width, height, channels);
    int across = (width + patch - 1) / patch, down = (height + patch - 1) / patch;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            int index = (y / patch) * across + x / patch;
            double t = double(index) / std::max(1, across * down - 1);
            for (int c = 0; c < channels; ++c) img.at(x, y)[c] = float(lo + (hi - lo) * std::fmod(t + 0.37 * c, 1.0));
        }
    return img;
}

// A horizontal ramp from lo to hi, each channel with its own phase.
inline Image ramp(int width, int height, int channels, double lo, double hi) {
    Image img(width, height, channels);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < channels; ++c) {
                double t = std::fmod(double(x) / (width - 1) + 0.3 * c * (y < height / 2 ? 1 : -1) + 1.0, 1.0);
                img.at(x, y)[c] = float(lo + (hi - lo) * t);
            }
    return img;
}

// Flat patches interrupted by strong content: hard-edged discs, a fine checkerboard, a
// sine grating and a band of strong value noise (texture), over a third of the frame.
inline Image picture_with_content(int width, int height, int channels, double lo, double hi) {
    Image img = flat_patches(width, height, channels, lo, hi, 128);
    const double amplitude = 0.4 * (hi - lo);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float* px = img.at(x, y);
            double u = double(x) / width, v = double(y) / height;
            double delta = 0;
            if (std::hypot(u - 0.3, v - 0.3) < 0.12 || std::hypot(u - 0.75, v - 0.6) < 0.08) delta = amplitude;
            else if (u > 0.55 && v < 0.3) delta = ((x / 3 + y / 3) % 2 ? 0.5 : -0.5) * amplitude;
            else if (u < 0.3 && v > 0.7) delta = 0.5 * amplitude * std::sin(x * 0.45 + y * 0.2);
            else if (u > 0.4 && u < 0.7 && v > 0.75) {
                unsigned h = (unsigned)(x / 5) * 73856093u ^ (unsigned)(y / 5) * 19349663u;
                delta = ((h % 1000) / 1000.0 - 0.5) * amplitude;
            }
            for (int c = 0; c < channels; ++c) px[c] = float(std::clamp(px[c] + delta, lo, hi));
        }
    return img;
}

}  // namespace darkroom::test
