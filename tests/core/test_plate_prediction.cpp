// Profiles predicted from a stock and a scan resolution.
#include <catch2/catch.hpp>
#include <cmath>

#include "core/plate/grain_prediction.h"
#include "core/plate/grain_synthesis.h"
#include "core/stages/grain.h"
#include "tests/core/test_support.h"

using namespace darkroom;

TEST_CASE("a predicted profile's grain reads back the stock's RMS granularity through a 48 um aperture",
          "[plate][prediction]") {
    // Selwyn's definition (core/stages/grain.h): at net density 1.0 the density read through
    // a 48 um circular aperture has standard deviation rms_granularity.
    const Stock film = find_stock("kodak-tri-x-400");
    const double pitch_um = 3.0, frame_mm = 36.0;
    GrainProfile p = predict_grain_profile(film, ScanGeometry{int(frame_mm * 1000 / pitch_um), frame_mm, false});
    CHECK(p.encoding == SignalEncoding::log);
    const double d_min = film.layers[0].density_curve.y_min();
    const double level = scan_level(d_min + 1.0, d_min);
    Image scan(1024, 1024, 3, float(level));
    apply_grain_profile(p, scan.view(), 4, 0, 0);
    const int radius = int(std::lround(kGranularityApertureUm / 2 / pitch_um));  // 8 px
    std::vector<double> readings;
    for (int cy = radius; cy + radius < 1024; cy += 2 * radius)
        for (int cx = radius; cx + radius < 1024; cx += 2 * radius) {
            double sum = 0;
            int n = 0;
            for (int y = cy - radius; y <= cy + radius; ++y)
                for (int x = cx - radius; x <= cx + radius; ++x)
                    if (std::hypot(x - cx, y - cy) <= radius) sum += scan.at(x, y)[1], ++n;
            // Code value back to density: 0.002 D per code value of 1023.
            readings.push_back((sum / n - level) * kMaxScanCode * kScanDensityPerCode);
        }
    double mean = 0, square = 0;
    for (double r : readings) mean += r / readings.size();
    for (double r : readings) square += (r - mean) * (r - mean) / (readings.size() - 1);
    CHECK(std::sqrt(square) == Approx(film.layers[0].grain.rms_granularity).epsilon(0.06));
}

TEST_CASE("a predicted profile follows the film model: D^exponent, Cineon levels, size in pixels",
          "[plate][prediction]") {
    const Stock film = test::test_film();  // rms 0.012, grain 1.5 um, 36 mm
    const GrainSpec& grain = film.layers[0].grain;
    for (int width : {2048, 4096}) {
        GrainProfile p = predict_grain_profile(film, ScanGeometry{width, 0, false});
        const double pitch_um = 36000.0 / width;
        GrainModel model = design_grain(grain, 0.25, pitch_um, NoiseKey{});
        const GrainChannel& ch = p.channels[0];
        CHECK(ch.level.front() == Approx(95.0 / 1023));
        for (double net : {0.3, 1.0, 1.8}) {
            double code_sigma = ch.sigma_at(scan_level(0.25 + net, 0.25));
            CHECK(code_sigma * 1023 * 0.002 ==
                  Approx(model.pixel_sigma_at_unit_density() * std::pow(net, grain.density_exponent)).epsilon(0.02));
        }
    }
    // Finer pixels see the grain larger: the autocorrelation at lag 1 rises with resolution.
    double rho_2k = predict_grain_profile(film, ScanGeometry{2048, 0}).channels[0].acf(1, 0);
    double rho_8k = predict_grain_profile(film, ScanGeometry{8192, 0}).channels[0].acf(1, 0);
    CHECK(rho_8k > rho_2k);
}

TEST_CASE("black-and-white stocks predict identical, fully correlated channels, colour layers independent ones",
          "[plate][prediction]") {
    GrainProfile bw = predict_grain_profile(find_stock("kodak-t-max-100"), ScanGeometry{4096, 0});
    REQUIRE(bw.channels.size() == 3);
    CHECK(bw.correlation(0, 2) == 1.0);
    CHECK(bw.channels[0].sigma == bw.channels[2].sigma);
    Stock colour = test::test_film();
    colour.layers = {colour.layers[0], colour.layers[0], colour.layers[0]};
    colour.layers[0].name = "red";
    colour.layers[2].grain.rms_granularity *= 2;
    GrainProfile c = predict_grain_profile(colour, ScanGeometry{4096, 0});
    REQUIRE(c.channels.size() == 3);
    CHECK(c.channels[0].name == "red");
    CHECK(c.correlation(0, 1) == 0.0);
    CHECK(c.channels[2].sigma.back() == Approx(2 * c.channels[1].sigma.back()));
    CHECK_THROWS_AS(predict_grain_profile(colour, ScanGeometry{0, 0}), std::invalid_argument);
}

TEST_CASE("a predicted profile's levels are the scan output's: balanced, a mid grey at the aim", "[plate][prediction]") {
    // The develop command's scan of a normally exposed mid grey (no grain) and the profile of
    // the same stock and scan settings agree on where that grey sits, and the profile's
    // grain there is the film model's at the grey's net density.
    const Stock film = find_stock("kodak-vision3-500t");
    for (const double aim : {445.0, 520.0}) {
        DevelopSettings s;
        s.output = OutputMode::scan;
        s.grain = s.mtf = false;
        s.halation = 0;
        s.scan_aim_code = aim;
        Image grey(4, 4, 3, 0.18f), scan(grey.window, 3);
        Plan::compile(film, nullptr, s, {4, 4}).run(grey.view(), scan.view(), 1);
        const GrainProfile p = predict_grain_profile(film, ScanGeometry{4096, 0, true, aim});
        const double grey_log_h = std::log10(mid_grey_exposure_lux_s(film.iso_speed));
        for (size_t l = 0; l < 3; ++l) {
            INFO("layer " << l << ", aim " << aim);
            const GrainChannel& ch = p.channels[l];
            CHECK(scan.at(1, 1)[l] * 1023 == Approx(aim).margin(2));
            CHECK(ch.level.front() <= aim / 1023);
            CHECK(ch.level.back() >= aim / 1023);
            const Curve& curve = film.layers[l].density_curve;
            const GrainModel model = design_grain(film.layers[l].grain, curve.y_min(), film.frame_width_mm * 1000 / 4096, NoiseKey{});
            const double net = curve(grey_log_h) - curve.y_min();
            CHECK(ch.sigma_at(aim / 1023) * 1023 * kScanDensityPerCode ==
                  Approx(model.pixel_sigma_at_unit_density() * std::pow(net, model.density_exponent)).epsilon(0.02));
        }
    }
}
