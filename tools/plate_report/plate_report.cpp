// darkroom_plate_report: how well grain analysed from real plates with default settings
// resynthesises, as an independent estimator (independent_estimate.h) sees it. Prints the
// per-plate table of docs/guides/plate-matching.md (tests/cli/test_plate_matching.cpp holds
// kodim10's and kodim23's figures within stated bounds). The response error counts the level
// bins inside the levels the analysis found grain alone at (the plate's level range).
//
//   darkroom_plate_report [PLATE.png ...]   (default: the four reference plates)
//   darkroom_plate_report --bins PLATE.png  (also each level bin's sigma ratio)
//   darkroom_plate_report --block-size N    (the analysis' block size, as grain analyze's)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "core/plate/grain_analysis.h"
#include "core/plate/grain_synthesis.h"
#include "tests/core/plate_test_support.h"
#include "tools/plate_report/independent_estimate.h"

using namespace darkroom;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
    bool bins = false;
    int block_size = 0;
    std::vector<fs::path> plates;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--bins")) bins = true;
        else if (!std::strcmp(argv[i], "--block-size") && i + 1 < argc) block_size = std::atoi(argv[++i]);
        else plates.emplace_back(argv[i]);
    }
    if (plates.empty())
        for (const char* name : {"kodim01", "kodim05", "kodim10", "kodim23"})
            plates.push_back(fs::path(DARKROOM_REFERENCE_DATA) / "plates" / (std::string(name) + ".png"));
    std::printf("| plate | profile | response error R / G / B | lag-1 R / G / B plate vs synth | R-G corr plate vs synth |\n");
    std::printf("|---|---|---|---|---|\n");
    try {
        for (const fs::path& path : plates) {
            const Image plate = independent::read_rgb(path);
            GrainAnalysisSettings settings;
            settings.encoding = SignalEncoding::display;
            settings.block_size_px = block_size;
            const GrainProfile profile = analyze_grain({plate.view()}, settings);
            const ProfileAssessment trust = assess_grain_profile(profile);
            const independent::Estimate ref = independent::estimate(plate);
            Image synthetic = test::flat_patches(512, 512, 3, ref.lo, ref.hi, 64);
            apply_grain_profile(profile, synthetic.view(), 7, 0, 0);
            const independent::Estimate e = independent::estimate(synthetic, ref.lo, ref.hi);
            // Over the levels the analysis found grain alone at (the plate's level range).
            auto error = [&](int c) {
                const GrainChannel& ch = profile.channels[c];
                return independent::response_error(ref, e, c, ch.level.front(), ch.level.back());
            };
            std::printf("| %s | %s | %.1f / %.1f / %.1f %% | %.2f / %.2f / %.2f vs %.2f / %.2f / %.2f | %.2f vs %.2f |\n",
                        path.stem().c_str(), quality_name(trust.quality), 100 * error(0), 100 * error(1), 100 * error(2),
                        ref.lag1[0], ref.lag1[1], ref.lag1[2], e.lag1[0], e.lag1[1], e.lag1[2], ref.rg, e.rg);
            if (bins)
                for (int c = 0; c < 3; ++c) {
                    std::printf("  %c synth/plate per bin:", "RGB"[c]);
                    for (int k = 0; k < independent::kBins; ++k) std::printf(" %.2f", e.sigma[c][k] / ref.sigma[c][k]);
                    std::printf("\n");
                }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "darkroom_plate_report: %s\n", e.what());
        return 1;
    }
    return 0;
}
