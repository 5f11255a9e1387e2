// Plate matching on real film scans (the Kodak Photo CD plates of the reference data) and on
// bad plates and profiles, through the program and the core.
//
// How closely grain analysed from the real plates resynthesises (response, lag-1 and channel
// correlation against an independent estimator) is printed by tools/plate_report and recorded
// in docs/guides/plate-matching.md; the bounds here hold those figures with a stated margin.
#include <OpenImageIO/imagebuf.h>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/demo_scene.h"
#include "core/plate/grain_analysis.h"
#include "core/plate/grain_compare.h"
#include "core/plate/grain_synthesis.h"
#include "tests/cli/cli_support.h"
#include "tests/core/plate_test_support.h"
#include "tools/plate_report/independent_estimate.h"

using namespace darkroom;
using namespace darkroom::test;
using namespace darkroom_test;

namespace {

const fs::path kPlates = fs::path(DARKROOM_REFERENCE_DATA) / "plates";

GrainProfile analyse(const Image& plate, SignalEncoding encoding = SignalEncoding::display) {
    GrainAnalysisSettings settings;
    settings.encoding = encoding;
    return analyze_grain({plate.view()}, settings);
}

std::string write_rgb(const Image& img, const std::string& name) {
    fs::create_directories(kTmp);
    const std::string path = (kTmp / name).string();
    OIIO::ImageBuf buf(OIIO::ImageSpec(img.window.width(), img.window.height(), 3, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < img.window.height(); ++y)
        for (int x = 0; x < img.window.width(); ++x) buf.setpixel(x, y, img.at(x, y));
    REQUIRE(buf.write(path));
    return path;
}

nlohmann::json read_json(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

// A linear profile of moderate, correlated grain over 0.05..0.95.
GrainProfile linear_grain(double amount = 1.0) {
    return known_profile({{0.01 * amount, 0.01 * amount, 1.0, 1.0},
                          {0.008 * amount, 0.01 * amount, 1.0, 0.8},
                          {0.012 * amount, 0.01 * amount, 1.0, 1.2}},
                         {1, 0.5, 0.3, 0.5, 1, 0.4, 0.3, 0.4, 1}, SignalEncoding::linear, 0.05, 0.95);
}

// RMS of b - a over the colour channel c.
double rms_difference(const Image& a, const Image& b, int c) {
    double sum = 0;
    for (int y = 0; y < a.window.height(); ++y)
        for (int x = 0; x < a.window.width(); ++x) {
            const double d = double(b.at(x, y)[c]) - a.at(x, y)[c];
            sum += d * d;
        }
    return std::sqrt(sum / a.window.width() / a.window.height());
}

// Horizontal correlation at lag `lag` of b - a in channel c.
double correlation_at(const Image& a, const Image& b, int c, int lag) {
    double v = 0, l = 0;
    for (int y = 0; y < a.window.height(); ++y)
        for (int x = 0; x + lag < a.window.width(); ++x) {
            const double d0 = double(b.at(x, y)[c]) - a.at(x, y)[c], d1 = double(b.at(x + lag, y)[c]) - a.at(x + lag, y)[c];
            v += d0 * d0, l += d0 * d1;
        }
    return l / v;
}

}  // namespace

TEST_CASE("real plates: textured ones are reported unreliable, flat-sky ones trusted", "[plate][reference]") {
    if (!fs::exists(kPlates / "kodim23.png")) {
        WARN("reference plates in " << kPlates << " not found: skipped");
        return;
    }
    // kodim01 and kodim05 are textured nearly everywhere (brick, foliage, engines): the
    // analysis must say its profile is unreliable rather than pass picture texture off as grain.
    // kodim23 and kodim10 are good: kodim10's R shows grain alone at 7 of its 16 levels, but
    // those levels hold 84 % of the plate (the sky); the rest is crew, water and highlights.
    for (const char* name : {"kodim01", "kodim05", "kodim10", "kodim23"}) {
        const ProfileAssessment trust =
            assess_grain_profile(analyse(independent::read_rgb(kPlates / (std::string(name) + ".png"))));
        INFO(name << ": " << quality_name(trust.quality) << " " << trust.reason);
        const std::string plate = name;
        if (plate == "kodim01" || plate == "kodim05") CHECK(trust.quality == ProfileQuality::unreliable);
        else CHECK(trust.quality == ProfileQuality::good);
    }
}

TEST_CASE("known grain put on the real pictures analyses back to the known grain", "[plate][reference]") {
    if (!fs::exists(kPlates / "kodim23.png")) {
        WARN("reference plates in " << kPlates << " not found: skipped");
        return;
    }
    // The plate's own grain adds to the known: the expected grain is their sum (sum_of_grains),
    // the plate's as analysed alone. The pictures' content is what the analysis must see past,
    // within plate matching's tolerances (GrainMatchTolerance); texture of the grain's own
    // correlation passes the block tests in proportion to the grain (the guide's Limits), which
    // the response's pooling across levels brought within them.
    // Three realisations of the known grain: the estimator scatters from one to the next (over
    // seeds 11-22, 2 of the 96 readings reach 5.3-5.4 %, both 1 px grain).
    constexpr uint64_t kKnownGrainSeeds[] = {11, 12, 13};
    struct Case {
        const char* what;
        GrainProfile known;
    };
    const std::vector<double> correlation = {1, 0.5, 0.3, 0.5, 1, 0.4, 0.3, 0.4, 1};
    const Case cases[] = {
        // White grain about the plates' own amount (2-4 code values of 255). Measured (seed
        // 11): 1.1-2.4 % (up to 4.2 % over seeds 11-13, and 11-22), NPS up to 0.57 dB (0.87),
        // correlation 0.003-0.020.
        {"white grain, the plates' amount",
         known_profile({{0.0075, 0.005, 1.0, 0}, {0.0075, 0.00375, 1.0, 0}, {0.00875, 0.005, 1.0, 0}}, correlation,
                       SignalEncoding::display, 0, 1)},
        // Grain of 1 px (lag-1 0.7-0.8), the plates' own amount: the size of the pictures'
        // fine texture (water, feathers), which the weak-texture test rejects. Measured 1.8-3.1 %
        // (up to 4.8 % over seeds 11-13; over 11-22 up to 5.4 %, 2 of 24 readings above 5 %),
        // NPS up to 0.30 dB (0.67), correlation 0.027-0.038.
        {"1 px grain, the plates' amount",
         known_profile({{0.0075, 0.005, 1.0, 1.0}, {0.0075, 0.00375, 1.0, 0.8}, {0.00875, 0.005, 1.0, 1.2}}, correlation,
                       SignalEncoding::display, 0, 1)},
        // The same 3-5x the plates' own, in 16 px blocks like the rest. Measured 0.7-3.3 %
        // (up to 4.7 % over seeds 11-13, 4.9 % over 11-22), NPS up to 0.30 dB (0.53),
        // correlation 0.013-0.020 (0.021).
        {"1 px grain, 3-5x the plates'",
         known_profile({{0.03, 0.02, 1.0, 1.0}, {0.03, 0.015, 1.0, 0.8}, {0.035, 0.02, 1.0, 1.2}}, correlation,
                       SignalEncoding::display, 0, 1)},
    };
    for (const Case& k : cases)
        for (const char* name : {"kodim10", "kodim23"}) {
            Image plate = independent::read_rgb(kPlates / (std::string(name) + ".png"));
            const GrainProfile plate_alone = analyse(plate);
            GrainProfile expected = sum_of_grains(k.known, plate_alone);
            // The plate's own grain is known only at the levels it was measured at: the expected
            // grain is compared there, not where it holds the plate's end values.
            for (size_t c = 0; c < expected.channels.size(); ++c) {
                const std::vector<double>& measured = plate_alone.channels[c].level;
                GrainChannel& e = expected.channels[c];
                std::vector<double> level, sigma;
                for (size_t i = 0; i < e.level.size(); ++i)
                    if (e.level[i] >= measured.front() && e.level[i] <= measured.back())
                        level.push_back(e.level[i]), sigma.push_back(e.sigma[i]);
                e.level = level, e.sigma = sigma;
            }
            for (uint64_t seed : kKnownGrainSeeds) {
                Image grained = plate;
                apply_grain_profile(k.known, grained.view(), seed, 0, 0);
                const GrainMatch m = compare_grain_profiles(expected, analyse(grained));
                std::ostringstream figures;
                for (const ChannelMatch& c : m.channels)
                    figures << " " << c.name << " " << c.response_error_percent << " % " << c.nps_distance_db << " dB;";
                INFO(k.what << ", " << name << ", seed " << seed << ":" << figures.str() << " correlation "
                            << m.max_correlation_difference);
                CHECK(m.passes());
            }
        }
}

TEST_CASE("known grain on a CG render with sharp detail analyses back within the match tolerances",
          "[plate]") {
    // The demo scene (ramps, a step wedge, sine bursts, a Siemens star, a colour chart), clean,
    // in display code values: every block the analysis keeps must be grain alone, however
    // sharp the detail beside it. White and 1 px grain of a plate's amount and 3-5x that.
    // Measured (seed 11, the largest channel): 0.3-1.9 %, 0.18-0.55 dB, correlation
    // 0.007-0.030 (before the response pooled each level with its neighbours: 0.7-1.7 %; with
    // the response a quantile of the blocks' variances: 0.8-2.8 %; before the weak-texture
    // test: 0.5-4.0 %).
    Image scene = demo_scene(768, 512);
    for (int y = 0; y < scene.window.height(); ++y)
        for (int x = 0; x < scene.window.width(); ++x)
            for (int c = 0; c < 3; ++c) scene.at(x, y)[c] = std::pow(std::clamp(scene.at(x, y)[c], 0.0f, 1.0f), 1 / 2.2f);
    const std::vector<double> correlation = {1, 0.5, 0.3, 0.5, 1, 0.4, 0.3, 0.4, 1};
    for (double size_px : {0.0, 1.0})
        for (double amount : {1.0, 4.0}) {
            const GrainProfile known = known_profile({{0.0075 * amount, 0.005 * amount, 1.0, size_px},
                                                      {0.0075 * amount, 0.00375 * amount, 1.0, 0.8 * size_px},
                                                      {0.00875 * amount, 0.005 * amount, 1.0, 1.2 * size_px}},
                                                     correlation, SignalEncoding::display, 0, 1);
            Image grained = scene;
            apply_grain_profile(known, grained.view(), 11, 0, 0);
            const GrainMatch m = compare_grain_profiles(known, analyse(grained));
            std::ostringstream figures;
            for (const ChannelMatch& c : m.channels)
                figures << " " << c.name << " " << c.response_error_percent << " % " << c.nps_distance_db << " dB;";
            INFO(size_px << " px, " << amount << "x:" << figures.str() << " correlation " << m.max_correlation_difference);
            CHECK(m.passes());
        }
}

TEST_CASE("the independent estimator removes each block's least-squares plane", "[plate]") {
    // A picture that is a plane leaves no residual in any block: the estimator reads no grain
    // (float rounding only) at every level, and so no picture gradient passes as grain.
    Image plane(512, 512, 3);
    for (int y = 0; y < 512; ++y)
        for (int x = 0; x < 512; ++x)
            for (int c = 0; c < 3; ++c) plane.at(x, y)[c] = float(0.1 + 0.0012 * x + (0.0004 + 0.0002 * c) * y);
    const independent::Estimate e = independent::estimate(plane);
    for (int c = 0; c < 3; ++c) {
        int measured = 0;
        for (double sigma : e.sigma[c])
            if (std::isfinite(sigma)) {
                INFO("RGB"[c] << ": sigma " << sigma);
                CHECK(sigma < 1e-5);
                ++measured;
            }
        CHECK(measured >= independent::kBins / 2);
    }
}

TEST_CASE("grain analysed from the real plates resynthesises to the plate's by an independent estimator",
          "[plate][reference]") {
    if (!fs::exists(kPlates / "kodim23.png")) {
        WARN("reference plates in " << kPlates << " not found: skipped");
        return;
    }
    // The figures of the guide's table (tools/plate_report: seed 7, 64 px patches), inside the
    // targets of a match by eye (15 %, 0.1, 0.1) with a margin. Measured: kodim10 5.4-6.2 %,
    // lag-1 0.01 apart, correlation 0.07 apart; kodim23 7.0-7.9 %, lag-1 0.02-0.03 apart,
    // correlation 0.06 apart.
    struct Bound {
        const char* name;
        double response, lag1, correlation;
    };
    for (const Bound& bound : {Bound{"kodim10", 0.10, 0.05, 0.1}, Bound{"kodim23", 0.10, 0.05, 0.1}}) {
        const Image plate = independent::read_rgb(kPlates / (std::string(bound.name) + ".png"));
        const GrainProfile profile = analyse(plate);
        const independent::Estimate on_plate = independent::estimate(plate);
        Image patches = flat_patches(512, 512, 3, on_plate.lo, on_plate.hi, 64);
        apply_grain_profile(profile, patches.view(), 7, 0, 0);
        const independent::Estimate synthetic = independent::estimate(patches, on_plate.lo, on_plate.hi);
        for (int c = 0; c < 3; ++c) {
            const GrainChannel& ch = profile.channels[c];
            const double response = independent::response_error(on_plate, synthetic, c, ch.level.front(), ch.level.back());
            INFO(bound.name << " " << "RGB"[c] << ": response " << 100 * response << " %, lag-1 plate " << on_plate.lag1[c]
                            << " vs " << synthetic.lag1[c]);
            CHECK(response < bound.response);
            CHECK(std::abs(synthetic.lag1[c] - on_plate.lag1[c]) < bound.lag1);
        }
        INFO(bound.name << ": R-G correlation plate " << on_plate.rg << " vs " << synthetic.rg);
        CHECK(std::abs(synthetic.rg - on_plate.rg) < bound.correlation);
    }
}

TEST_CASE("coarser grain than the plate's is told apart by an independent estimator", "[plate][reference]") {
    if (!fs::exists(kPlates / "kodim23.png")) {
        WARN("reference plates in " << kPlates << " not found: skipped");
        return;
    }
    for (const char* name : {"kodim10", "kodim23"}) {
        const Image plate = independent::read_rgb(kPlates / (std::string(name) + ".png"));
        const GrainProfile profile = analyse(plate);
        const independent::Estimate on_plate = independent::estimate(plate);
        auto synthetic = [&](const GrainControls& controls) {
            Image patches = flat_patches(512, 512, 3, on_plate.lo, on_plate.hi, 64);
            apply_grain_profile(plan_grain_synthesis(profile, controls), patches.view(), 7, 0, 0);
            return independent::estimate(patches, on_plate.lo, on_plate.hi);
        };
        const independent::Estimate matched = synthetic({}), coarser = synthetic({{1, 1, 1}, {1.6, 1.6, 1.6}});
        for (int c = 0; c < 3; ++c) {
            INFO(name << " " << "RGB"[c] << ": lag-1 plate " << on_plate.lag1[c] << ", matched " << matched.lag1[c]
                      << ", coarser " << coarser.lag1[c]);
            CHECK(coarser.lag1[c] - matched.lag1[c] > 0.1);
        }
    }
}

TEST_CASE("grain controls: gain scales the RMS, size the correlation length, tilt the response", "[plate][controls]") {
    const Image clean = flat_patches(256, 256, 3, 0.3, 0.3);  // one level: sigma 0.013, 0.011, 0.015
    auto grained = [&](const GrainControls& controls) {
        Image img = clean;
        apply_grain_profile(plan_grain_synthesis(linear_grain(), controls), img.view(), 3, 0, 0);
        return img;
    };
    const Image plain = grained({}), gained = grained({{0.5, 1.0, 2.0}}), larger = grained({{1, 1, 1}, {2, 2, 2}});
    for (int c = 0; c < 3; ++c) {
        const double gain = std::array<double, 3>{0.5, 1.0, 2.0}[c];
        // The same white noise: the RMS scales exactly.
        CHECK(rms_difference(clean, gained, c) == Approx(gain * rms_difference(clean, plain, c)).epsilon(1e-4));
        // Twice the size: the correlation at lag 2 is the plain grain's at lag 1, and at lag 1
        // halfway between 1 and it (bilinear between the profile's lags).
        const double r1 = correlation_at(clean, plain, c, 1), r2 = correlation_at(clean, larger, c, 2);
        INFO("RGB"[c] << ": lag-1 " << r1 << " -> lag-2 " << r2);
        CHECK(r2 == Approx(r1).margin(0.02));
        CHECK(correlation_at(clean, larger, c, 1) == Approx((1 + r1) / 2).margin(0.02));
        CHECK(correlation_at(clean, larger, c, 1) > r1 + 0.05);
        CHECK(rms_difference(clean, larger, c) == Approx(rms_difference(clean, plain, c)).epsilon(0.05));
    }
    // Tilt: 2^(tilt t) times sigma, t from -1/2 at the lowest level to 1/2 at the highest.
    const GrainProfile original = linear_grain(), tilted = adjusted_grain_profile(original, {{1, 1, 1}, {1, 1, 1}, 2.0});
    for (size_t c = 0; c < 3; ++c) {
        const GrainChannel &a = original.channels[c], &b = tilted.channels[c];
        CHECK(b.sigma.front() == Approx(a.sigma.front() / 2));
        CHECK(b.sigma.back() == Approx(a.sigma.back() * 2));
        CHECK(b.sigma_at(0.5) == Approx(a.sigma_at(0.5)));
    }
}

TEST_CASE("grain analyze --frames pools frames of different exposures into one response", "[cli][grain][plate]") {
    // Frame 1 shows only the lower half of the levels, frame 2 the upper half.
    const GrainProfile grain = linear_grain();
    const fs::path dir = kTmp / "grain-pool";
    fs::create_directories(dir);
    for (int frame : {1, 2}) {
        Image img = flat_patches(256, 256, 3, frame == 1 ? 0.1 : 0.5, frame == 1 ? 0.45 : 0.9, 64);
        apply_grain_profile(grain, img.view(), 5, frame, 0);
        write_rgb(img, "grain-pool/plate.000" + std::to_string(frame) + ".exr");
    }
    const std::string pooled = (dir / "pooled.json").string(), one = (dir / "one.json").string();
    Result r = darkroom_test::darkroom("grain analyze " + (dir / "plate.####.exr").string() + " --frames 1-2 --encoding linear -o " + pooled);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    REQUIRE(darkroom_test::darkroom("grain analyze " + (dir / "plate.0001.exr").string() + " --encoding linear -o " + one).exit_code == 0);
    const nlohmann::json p = read_json(pooled), q = read_json(one);
    for (int c = 0; c < 3; ++c) {
        const auto& levels = p["channels"][c]["response"]["level"];
        INFO("channel " << c << ": pooled " << levels.front() << ".." << levels.back() << ", frame 1 "
                        << q["channels"][c]["response"]["level"].back());
        CHECK(levels.front().get<double>() < 0.45);
        CHECK(levels.back().get<double>() > 0.55);
        CHECK(q["channels"][c]["response"]["level"].back().get<double>() < 0.55);
    }
    const GrainProfile measured = load_grain_profile_file(pooled);
    const GrainMatch m = compare_grain_profiles(grain, measured);
    for (const ChannelMatch& c : m.channels) {
        INFO(c.name << ": response " << c.response_error_percent << " %, NPS " << c.nps_distance_db << " dB");
        CHECK(c.response_error_percent < 5);
    }
}

TEST_CASE("grain: bad plates give a clear message and no garbage profile", "[cli][grain][bad-input]") {
    const std::string out = (kTmp / "bad-plate.json").string();
    auto analyse_file = [&](const Image& img, const std::string& name) {
        fs::remove(out);
        return darkroom_test::darkroom("grain analyze " + write_rgb(img, name) + " --encoding linear -o " + out);
    };
    SECTION("2x2") {
        Result r = analyse_file(Image(2, 2, 3, 0.5f), "bad-2x2.exr");
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains("too small") && Catch::Contains("2x2"));
        CHECK_FALSE(fs::exists(out));
    }
    SECTION("constant") {
        Result r = analyse_file(Image(256, 256, 3, 0.5f), "bad-constant.exr");
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains("no grain"));
        CHECK_FALSE(fs::exists(out));
    }
    SECTION("all NaN") {
        Result r = analyse_file(Image(256, 256, 3, NAN), "bad-nan.exr");
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains("non-finite"));
        CHECK_FALSE(fs::exists(out));
    }
    SECTION("some NaN pixels and a hot pixel are left out, not measured as grain") {
        Image clean = flat_patches(256, 256, 3, 0.1, 0.9, 64);
        apply_grain_profile(linear_grain(), clean.view(), 9, 0, 0);
        Image spoilt = clean;
        for (int i = 0; i < 40; ++i) spoilt.at(7 * i % 256, 13 * i % 256)[i % 3] = NAN;
        for (int c = 0; c < 3; ++c) spoilt.at(100, 100)[c] = 1e4f;
        Result r = analyse_file(spoilt, "bad-spoilt.exr");
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        const GrainMatch m = compare_grain_profiles(linear_grain(), load_grain_profile_file(out));
        for (const ChannelMatch& c : m.channels) {
            INFO(c.name << ": response " << c.response_error_percent << " %");
            CHECK(c.response_error_percent < 5);
        }
    }
    SECTION("no flat area: a real plate of brick and foliage") {
        // (Texture that is stationary at the block scale, alike everywhere, cannot be told from
        // coarse grain: see the guide's Limits. kodim05 is engines and foliage throughout.)
        if (!fs::exists(kPlates / "kodim05.png")) return;
        Result r = darkroom_test::darkroom("grain analyze " + (kPlates / "kodim05.png").string() +
                                           " --iscolorspace sRGB -o " + out);
        INFO(r.output);
        CHECK(r.exit_code == 0);
        CHECK_THAT(r.output, Catch::Contains("profile: unreliable") && Catch::Contains("warning"));
    }
}

TEST_CASE("grain apply: an absurd profile or one of another encoding is refused", "[cli][grain][bad-input]") {
    const std::string clean = write_rgb(flat_patches(64, 64, 3, 0.2, 0.8, 32), "bad-profile-clean.exr"),
                      out = (kTmp / "bad-profile-out.exr").string(), profile = (kTmp / "bad-profile.json").string();
    std::ofstream(profile) << grain_profile_to_json(linear_grain());
    nlohmann::json j = read_json(profile);
    REQUIRE(darkroom_test::darkroom("grain apply " + clean + " --profile " + profile + " -o " + out + " --iscolorspace ACEScg").exit_code ==
            0);

    j["channels"][1]["response"]["sigma"][3] = 1e39;
    std::ofstream((kTmp / "bad-sigma.json").string()) << j.dump();
    fs::remove(out);
    Result r = darkroom_test::darkroom("grain apply " + clean + " --profile " + (kTmp / "bad-sigma.json").string() + " -o " + out +
                        " --iscolorspace ACEScg");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("bad-sigma.json") && Catch::Contains("sigma"));
    CHECK_FALSE(fs::exists(out));

    // A log profile on a linear image: the encodings are named, and --iscolorspace.
    j = read_json(profile);
    j["encoding"] = "log";
    std::ofstream((kTmp / "bad-log.json").string()) << j.dump();
    r = darkroom_test::darkroom("grain apply " + clean + " --profile " + (kTmp / "bad-log.json").string() + " -o " + out +
                 " --iscolorspace ACEScg");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("log") && Catch::Contains("linear") && Catch::Contains("--iscolorspace"));
    CHECK_FALSE(fs::exists(out));
}
