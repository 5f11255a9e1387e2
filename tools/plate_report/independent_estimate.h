// An independent estimate of a plate's grain, for checking the analysis
// (core/plate/grain_analysis) from outside: none of its code.
//
// 8x8 blocks less their least-squares plane, binned by level into 8 bins over the plate's
// 2..98 % level range (of G); in each bin the quietest tenth of the blocks (the flattest on a
// picture; the same selection on synthetic patches, so the selection bias is the same on
// both when their grain matches); from them the RMS residual per bin, the horizontal lag-1
// correlation and the R-G correlation. A picture's quiet blocks still hold some content,
// which adds to the plate's figures only: kodim10's response error (R / G / B) is 7.7 / 7.8 /
// 6.7 % from the quietest quarter, 4.6 / 5.1 / 3.3 % from the tenth and 3.6 / 4.0 / 2.0 %
// from the twentieth. Used by tools/plate_report (the per-plate match figures of
// docs/guides/plate-matching.md) and tests/cli/test_plate_matching.cpp.
#pragma once
#include <OpenImageIO/imagebuf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "core/image.h"

namespace darkroom::independent {

constexpr int kBlock = 8, kBins = 8;
constexpr double kQuietFraction = 0.1;  // of each bin's blocks: the flattest

struct Estimate {
    double lo = 0, hi = 0;
    std::array<std::vector<double>, 3> sigma;  // per channel, per bin (NAN: no blocks)
    std::array<double, 3> lag1{};
    double rg = 0;
};

inline Estimate estimate(const Image& img, double lo_in = NAN, double hi_in = NAN) {
    const int bx = img.window.width() / kBlock, by = img.window.height() / kBlock, npx = kBlock * kBlock;
    struct B {
        std::array<double, 3> level, var, lag1;
        double rg;
    };
    std::vector<B> blocks;
    for (int j = 0; j < by; ++j)
        for (int i = 0; i < bx; ++i) {
            B b{};
            double r[3][kBlock * kBlock];
            for (int c = 0; c < 3; ++c) {
                double m = 0, sx = 0, sy = 0;
                for (int y = 0; y < kBlock; ++y)
                    for (int x = 0; x < kBlock; ++x) {
                        const double v = img.at(i * kBlock + x, j * kBlock + y)[c], u = x - 3.5, w = y - 3.5;
                        m += v, sx += v * u, sy += v * w;
                    }
                // Sum of (x - 3.5)^2 over a block: (n^2 - 1) n / 12 per row, n rows.
                const double norm = (kBlock * kBlock - 1) * kBlock / 12.0 * kBlock;
                for (int y = 0; y < kBlock; ++y)
                    for (int x = 0; x < kBlock; ++x)
                        r[c][y * kBlock + x] = img.at(i * kBlock + x, j * kBlock + y)[c] - m / npx -
                                               sx / norm * (x - 3.5) - sy / norm * (y - 3.5);
                b.level[c] = m / npx;
                double v = 0, l = 0;
                for (int p = 0; p < npx; ++p) v += r[c][p] * r[c][p];
                for (int y = 0; y < kBlock; ++y)
                    for (int x = 0; x + 1 < kBlock; ++x) l += r[c][y * kBlock + x] * r[c][y * kBlock + x + 1];
                b.var[c] = v / npx;
                b.lag1[c] = v > 0 ? l / (kBlock - 1) * kBlock / v : 0;
            }
            double rg = 0, rr = 0, gg = 0;
            for (int p = 0; p < npx; ++p) rg += r[0][p] * r[1][p], rr += r[0][p] * r[0][p], gg += r[1][p] * r[1][p];
            b.rg = rr > 0 && gg > 0 ? rg / std::sqrt(rr * gg) : 0;
            blocks.push_back(b);
        }
    Estimate e;
    std::vector<double> levels;
    for (const B& b : blocks) levels.push_back(b.level[1]);
    std::sort(levels.begin(), levels.end());
    e.lo = std::isnan(lo_in) ? levels[levels.size() / 50] : lo_in;
    e.hi = std::isnan(hi_in) ? levels[levels.size() * 49 / 50] : hi_in;
    std::array<int, 3> quiet_blocks{};
    for (int c = 0; c < 3; ++c) {
        std::vector<std::vector<const B*>> bins(kBins);
        for (const B& b : blocks) {
            const int k = (int)std::floor((b.level[c] - e.lo) / (e.hi - e.lo) * kBins);
            if (k >= 0 && k < kBins) bins[k].push_back(&b);
        }
        for (auto& bin : bins) {
            std::sort(bin.begin(), bin.end(), [&](const B* a, const B* b) { return a->var[c] < b->var[c]; });
            const size_t quiet = (size_t)(bin.size() * kQuietFraction);
            if (quiet < 4) {
                e.sigma[c].push_back(NAN);
                continue;
            }
            double v = 0;
            for (size_t i = 0; i < quiet; ++i) {
                v += bin[i]->var[c];
                e.lag1[c] += bin[i]->lag1[c];
                ++quiet_blocks[c];
                if (c == 1) e.rg += bin[i]->rg;
            }
            e.sigma[c].push_back(std::sqrt(v / quiet));
        }
    }
    for (int c = 0; c < 3; ++c) e.lag1[c] /= std::max(1, quiet_blocks[c]);
    e.rg /= std::max(1, quiet_blocks[1]);
    return e;
}

inline Image read_rgb(const std::filesystem::path& path) {
    OIIO::ImageBuf buf(path.string());
    if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT)) throw std::runtime_error("cannot read " + path.string());
    const OIIO::ImageSpec& spec = buf.spec();
    Image img(spec.width, spec.height, 3);
    std::vector<float> px((size_t)spec.width * spec.height * spec.nchannels);
    buf.get_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, px.data());
    for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x)
            for (int c = 0; c < 3; ++c) img.at(x, y)[c] = px[((size_t)y * spec.width + x) * spec.nchannels + c];
    return img;
}

// Mean |sigma_e / sigma_ref - 1| over the bins both measured (channel c) whose levels reach
// into [level_lo, level_hi] (the levels where the plate shows grain alone; default all);
// INFINITY if none.
inline double response_error(const Estimate& ref, const Estimate& e, int c, double level_lo = -INFINITY,
                             double level_hi = INFINITY) {
    double sum = 0;
    int n = 0;
    const double width = (ref.hi - ref.lo) / kBins;
    for (int k = 0; k < kBins; ++k)
        if (std::isfinite(ref.sigma[c][k]) && std::isfinite(e.sigma[c][k]) && ref.lo + (k + 1) * width > level_lo &&
            ref.lo + k * width < level_hi)
            sum += std::abs(e.sigma[c][k] / ref.sigma[c][k] - 1), ++n;
    return n ? sum / n : INFINITY;
}

}  // namespace darkroom::independent
