// Plate matching end to end: grain of a known profile on a plate, analysed, resynthesised
// with another seed and compared (plate matching's acceptance tolerances: response 5 %, NPS 1 dB,
// channel correlation 0.05).
#include <catch2/catch.hpp>
#include <functional>

#include "core/plate/grain_analysis.h"
#include "core/plate/grain_compare.h"
#include "core/plate/grain_synthesis.h"
#include "tests/core/plate_test_support.h"

using namespace darkroom;
using namespace darkroom::test;

namespace {

using Scene = std::function<Image(int, int, int, double, double)>;

struct Case {
    std::string name;
    GrainProfile truth;
    double lo, hi;
    int width, height;
};

std::vector<Case> cases() {
    return {
        {"fine, uncorrelated, linear",
         known_profile({{0.004, 0.02, 0.5, 0.0}, {0.003, 0.015, 0.5, 0.4}, {0.006, 0.025, 0.5, 0.0}},
                       {1, 0, 0, 0, 1, 0, 0, 0, 1}, SignalEncoding::linear, 0.05, 1.5),
         0.05, 1.5, 512, 512},
        {"coarse, correlated, log",
         known_profile({{0.012, -0.006, 1.0, 1.8}, {0.010, -0.004, 1.0, 1.5}, {0.016, -0.008, 1.0, 2.2}},
                       {1, 0.6, 0.3, 0.6, 1, 0.5, 0.3, 0.5, 1}, SignalEncoding::log, 0.1, 0.9),
         0.1, 0.9, 1024, 832},
        {"mixed sizes, strongly correlated, log",
         known_profile({{0.006, 0.004, 1.0, 1.0}, {0.005, 0.003, 1.0, 0.7}, {0.008, 0.006, 1.0, 1.3}},
                       {1, 0.8, 0.7, 0.8, 1, 0.75, 0.7, 0.75, 1}, SignalEncoding::log, 0.1, 0.9),
         0.1, 0.9, 512, 512},
    };
}

Image grainy(const Scene& scene, const Case& k, const GrainProfile& profile, uint64_t seed) {
    Image img = scene(k.width, k.height, 3, k.lo, k.hi);
    apply_grain_profile(profile, img.view(), seed, 0, 0);
    return img;
}

GrainProfile analyse(const Image& plate, SignalEncoding encoding) {
    GrainAnalysisSettings settings;
    settings.encoding = encoding;
    return analyze_grain({plate.view()}, settings);
}

std::string describe(const GrainMatch& m) {
    std::string s;
    for (const ChannelMatch& c : m.channels)
        s += c.name + ": response " + std::to_string(c.response_error_percent) + " % over " +
             std::to_string(c.levels_compared) + " levels, NPS " + std::to_string(c.nps_distance_db) + " dB, f50 " +
             std::to_string(c.half_power_a) + " vs " + std::to_string(c.half_power_b) + "; ";
    return s + "correlation difference " + std::to_string(m.max_correlation_difference);
}

}  // namespace

TEST_CASE("grain analysed from a plate matches the known profile and resynthesises to a match", "[plate][roundtrip]") {
    const std::vector<std::pair<std::string, Scene>> scenes = {
        {"flat patches", [](int w, int h, int c, double lo, double hi) { return flat_patches(w, h, c, lo, hi); }},
        {"ramps", ramp},
        {"picture with content", picture_with_content}};
    for (const Case& k : cases())
        for (const auto& [scene_name, scene] : scenes) {
            SECTION(k.name + " on " + scene_name) {
                GrainProfile measured = analyse(grainy(scene, k, k.truth, 1), k.truth.encoding);
                GrainMatch against_truth = compare_grain_profiles(k.truth, measured);
                GrainProfile remeasured = analyse(grainy(scene, k, measured, 2), k.truth.encoding);
                GrainMatch round_trip = compare_grain_profiles(measured, remeasured);
                INFO("against the known profile: " << describe(against_truth));
                INFO("round trip (seed 2): " << describe(round_trip));
                CHECK(against_truth.passes());
                CHECK(round_trip.passes());
            }
        }
}
