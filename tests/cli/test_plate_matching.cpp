// Plate matching on real film scans (the Kodak Photo CD plates of the reference data): a
// profile analysed with default settings, synthesised onto flat patches at the plate's
// levels, must give grain that an independent estimator cannot tell from the plate's.
//
// The independent estimator (not the analysis' code): 8x8 blocks less their least-squares
// plane, binned by level into 8 bins over the plate's 2..98 % level range; in each bin the
// quietest quarter of the blocks (the flattest on a picture; the same selection on the
// patches, so the selection bias is the same on both); from them the RMS residual, the
// horizontal lag-1 correlation and the R-G correlation.
//
// Marked may-fail: with the analysis as it stands the real plates miss these tolerances (see
// docs/guides/plate-matching.md for the figures); the unreliable-plate checks hold.
#include <OpenImageIO/imagebuf.h>
#include <catch2/catch.hpp>
#include <filesystem>
#include <sstream>

#include "core/plate/grain_analysis.h"
#include "core/plate/grain_synthesis.h"
#include "tests/core/plate_test_support.h"

using namespace darkroom;
namespace fs = std::filesystem;

namespace {

constexpr int kBlock = 8, kBins = 8;

struct Estimate {
    double lo = 0, hi = 0;
    std::array<std::vector<double>, 3> sigma;  // per channel, per bin (NAN: no blocks)
    std::array<double, 3> lag1{};
    double rg = 0;
};

Estimate estimate(const Image& img, double lo_in = NAN, double hi_in = NAN) {
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
                const double norm = 4 * 21.0 * kBlock;  // sum of (x - 3.5)^2 over a block
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
            const size_t quiet = bin.size() / 4;
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

Image read_png(const fs::path& path) {
    OIIO::ImageBuf buf(path.string());
    REQUIRE(buf.read(0, 0, true, OIIO::TypeDesc::FLOAT));
    const OIIO::ImageSpec& spec = buf.spec();
    Image img(spec.width, spec.height, 3);
    std::vector<float> px((size_t)spec.width * spec.height * spec.nchannels);
    buf.get_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, px.data());
    for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x)
            for (int c = 0; c < 3; ++c) img.at(x, y)[c] = px[((size_t)y * spec.width + x) * spec.nchannels + c];
    return img;
}

GrainProfile analyse_default(const Image& plate) {
    GrainAnalysisSettings settings;
    settings.encoding = SignalEncoding::display;
    return analyze_grain({plate.view()}, settings);
}

}  // namespace

TEST_CASE("grain analysed from real scans with defaults resynthesises to grain an independent estimator matches",
          "[plate][reference][!mayfail]") {
    const fs::path dir = fs::path(DARKROOM_REFERENCE_DATA) / "plates";
    if (!fs::exists(dir / "kodim23.png")) {
        WARN("reference plates in " << dir << " not found: skipped");
        return;
    }
    // kodim01 and kodim05 are textured nearly everywhere (brick, foliage, engines): the
    // analysis must say its profile is unreliable rather than pass picture texture off as grain.
    for (const char* name : {"kodim01", "kodim05"}) {
        const ProfileAssessment trust = assess_grain_profile(analyse_default(read_png(dir / (std::string(name) + ".png"))));
        INFO(name << ": " << trust.reason);
        CHECK(trust.quality == ProfileQuality::unreliable);
    }
    for (const char* name : {"kodim10", "kodim23"}) {
        const Image plate = read_png(dir / (std::string(name) + ".png"));
        const GrainProfile profile = analyse_default(plate);
        CHECK(assess_grain_profile(profile).quality == ProfileQuality::good);
        const Estimate on_plate = estimate(plate);
        auto synthetic = [&](const GrainProfile& p) {
            Image patches = test::flat_patches(512, 512, 3, on_plate.lo, on_plate.hi, 64);
            apply_grain_profile(p, patches.view(), 7, 0, 0);
            return estimate(patches, on_plate.lo, on_plate.hi);
        };
        auto response_error = [&](const Estimate& e, int c) {
            double sum = 0;
            int n = 0;
            for (int k = 0; k < kBins; ++k)
                if (std::isfinite(on_plate.sigma[c][k]) && std::isfinite(e.sigma[c][k]))
                    sum += std::abs(e.sigma[c][k] / on_plate.sigma[c][k] - 1), ++n;
            return n ? sum / n : INFINITY;
        };
        const Estimate matched = synthetic(profile);
        std::ostringstream table;
        for (int c = 0; c < 3; ++c)
            table << "RGB"[c] << ": response " << 100 * response_error(matched, c) << " %, lag-1 " << on_plate.lag1[c]
                  << " vs " << matched.lag1[c] << "; ";
        table << "R-G correlation " << on_plate.rg << " vs " << matched.rg;
        INFO(name << ": " << table.str());
        for (int c = 0; c < 3; ++c) {
            CHECK(response_error(matched, c) < 0.15);
            CHECK(std::abs(matched.lag1[c] - on_plate.lag1[c]) < 0.1);
        }
        CHECK(std::abs(matched.rg - on_plate.rg) < 0.1);
        // Negative controls: 20 % more grain, or coarser grain, is told apart.
        const Estimate more = synthetic(adjusted_grain_profile(profile, GrainControls{{1.2, 1.2, 1.2}}));
        const Estimate coarser = synthetic(adjusted_grain_profile(profile, GrainControls{{1, 1, 1}, {1.6, 1.6, 1.6}}));
        for (int c = 0; c < 3; ++c) {
            CHECK(response_error(more, c) > 0.15);
            CHECK(coarser.lag1[c] - on_plate.lag1[c] > 0.1);
        }
        WARN(name << ": " << table.str());
    }
}
