// The colour pipeline: three dyed layers, spectral printing, halation, scan and texture.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "core/demo_scene.h"
#include "core/develop.h"
#include "core/stages/filters.h"
#include "test_support.h"

using namespace darkroom;

namespace {

using test::render;

DevelopSettings clean(OutputMode output) {
    DevelopSettings s;
    s.output = output;
    s.grain = false;
    s.mtf = false;
    s.halation = 0;
    return s;
}

// CIELAB chroma of a linear Rec.709 colour relative to the D65 white.
double chroma(const float* rgb) {
    Lab lab = xyz_to_lab(linear_srgb_to_xyz({rgb[0], rgb[1], rgb[2]}), linear_srgb_to_xyz({1, 1, 1}));
    return std::hypot(lab[1], lab[2]);
}

}  // namespace

TEST_CASE("a colour stock has three dyed layers over a spectral base", "[colour][stock]") {
    Stock film = test::test_colour_film();
    REQUIRE(film.is_colour());
    for (const Layer& l : film.layers) {
        CHECK(*std::max_element(l.dye_density.begin(), l.dye_density.end()) == Approx(1.0));
        CHECK(*std::max_element(l.sensitivity.begin(), l.sensitivity.end()) == Approx(1.0));
    }
    // The spectral density is base + net density x dye: at d_min it is the base.
    double d_min[3], plus_half[3];
    for (int l = 0; l < 3; ++l) d_min[l] = plus_half[l] = film.layers[l].density_curve.y_min();
    plus_half[0] += 0.5;
    Spectrum base = spectral_density(film, d_min), cyan = spectral_density(film, plus_half);
    for (int i = 0; i < kSpectralSamples; ++i) {
        REQUIRE(base[i] == Approx(film.base_density[i]));
        REQUIRE(cyan[i] - base[i] == Approx(0.5 * film.layers[0].dye_density[i]).margin(1e-12));
    }
    // The orange mask absorbs blue more than red.
    CHECK(base[wavelength_index(440)] > base[wavelength_index(650)] + 0.5);
    Stock again = parse_stock_json(stock_to_json(film), "round trip");
    CHECK(again.base_density == film.base_density);
    CHECK(again.layers[2].dye_density == film.layers[2].dye_density);
    CHECK(again.layers[0].halation.strength == film.layers[0].halation.strength);
}

TEST_CASE("a scene mid grey prints neutral at the paper's aim density", "[colour][print]") {
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image grey(4, 4, 3, 0.18f);
    // The printer lights' design is exact in the spectral tiers; the fast tiers' tables
    // are measured against them in test_quality.cpp.
    DevelopSettings spectral = clean(OutputMode::print);
    spectral.quality = Quality::high;
    // Seen absolute, at the aim's reflectance; seen media-relative, where the scene's grey was.
    spectral.print_viewing = PrintViewing::absolute;
    Image print = render(film, &paper, spectral, grey);
    double aim = std::pow(10.0, -paper.mid_grey_aim_density);
    for (int c = 0; c < 3; ++c) CHECK(print.at(1, 1)[c] == Approx(aim).epsilon(1e-5));
    spectral.print_viewing = PrintViewing::media_relative;
    print = render(film, &paper, spectral, grey);
    for (int c = 0; c < 3; ++c) CHECK(print.at(1, 1)[c] == Approx(0.18).epsilon(1e-5));
    // A grey ramp: exactly neutral only at mid grey, since the same ratio of three dyes is
    // not neutral at every density (their sum is not flat); the tolerance is stated for
    // these test stocks (the presets' own test reads the published curves).
    double worst = 0;
    for (double ev = -2; ev <= 2; ev += 0.25) {
        Image patch(2, 2, 3, float(0.18 * std::exp2(ev)));
        worst = std::max(worst, chroma(render(film, &paper, spectral, patch).at(0, 0)));
    }
    INFO("largest C*ab over -2..+2 EV: " << worst);
    CHECK(worst < 4.5);
}

TEST_CASE("printer lights and filtration move the print's colour the way a lab's do", "[colour][print]") {
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image grey(2, 2, 3, 0.18f);
    DevelopSettings s = clean(OutputMode::print);
    Image automatic = render(film, &paper, s, grey);
    PrintSettings lights{mid_grey_exposure_lux_s(film.iso_speed), {37, 25, 25}, {0, 0, 0}, 0, {}};
    PrintExposure base = PrintExposure::design(film, paper, {mid_grey_exposure_lux_s(film.iso_speed), {25, 25, 25}, {0, 0, 0}, 0, {}});
    PrintExposure more_red = PrintExposure::design(film, paper, lights);
    // 12 points = 0.3 log exposure on the red-sensitive layer only.
    CHECK(std::log10(more_red.light_lux_s()[0] / base.light_lux_s()[0]) == Approx(0.3));
    CHECK(more_red.light_lux_s()[1] == Approx(base.light_lux_s()[1]));
    s.printer_lights = {37, 25, 25};
    Image cyan = render(film, &paper, s, grey);
    CHECK(cyan.at(0, 0)[0] < 0.8 * automatic.at(0, 0)[0]);  // more cyan dye: less red
    s.printer_lights = {25, 25, 25};
    s.filtration_ymc = {30, 0, 0};  // a yellow filter holds back blue light: less yellow dye
    Image bluer = render(film, &paper, s, grey);
    CHECK(bluer.at(0, 0)[2] / bluer.at(0, 0)[1] > 1.1 * automatic.at(0, 0)[2] / automatic.at(0, 0)[1]);
    s.filtration_ymc = {0, 0, 0};
    s.print_exposure_ev = 1;  // more light: a darker print
    CHECK(render(film, &paper, s, grey).at(0, 0)[1] < automatic.at(0, 0)[1]);
}

TEST_CASE("the enlarger's exposure by layer factors of the transmittance equals its exposure", "[colour][print]") {
    // (The fast tiers' print table exposes its grid this way: PrintExposure::layer_transmittance.)
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const PrintExposure enlarger =
        PrintExposure::design(film, paper, {mid_grey_exposure_lux_s(film.iso_speed), {27, 24, 25}, {10, 0, 5}, 0.5, {}});
    REQUIRE(enlarger.spectral());
    for (double d0 : {0.1, 0.9, 2.4})
        for (double d1 : {0.5, 1.6, 3.1})
            for (double d2 : {0.8, 2.0, 3.5}) {
                const double d[3] = {d0, d1, d2};
                const Spectrum t[3] = {enlarger.layer_transmittance(0, d0), enlarger.layer_transmittance(1, d1),
                                       enlarger.layer_transmittance(2, d2)};
                double direct[3], factored[3];
                enlarger.expose(d, direct);
                enlarger.expose({&t[0], &t[1], &t[2]}, factored);
                for (int j = 0; j < 3; ++j) CHECK(factored[j] == Approx(direct[j]).epsilon(1e-12));
            }
}

TEST_CASE("scan output is Cineon code values of the developed density", "[colour][scan]") {
    Stock film = test::test_colour_film();
    Image scene = demo_scene(48, 32);
    DevelopSettings s;
    s.output = OutputMode::density;
    Image density = render(film, nullptr, s, scene);
    s.output = OutputMode::scan;
    Image balanced = render(film, nullptr, s, scene);
    s.scan_balance = false;
    Image raw = render(film, nullptr, s, scene);
    const double log_h_grey = std::log10(mid_grey_exposure_lux_s(film.iso_speed));
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 48; ++x)
            for (int c = 0; c < 3; ++c) {
                const Curve& curve = film.layers[c].density_curve;
                const double d = density.at(x, y)[c];
                // Unbalanced: base+fog at code 95; balanced: the 0 EV mid grey's density at 445.
                REQUIRE(raw.at(x, y)[c] * 1023.0 == Approx(95.0 + (d - curve.y_min()) / 0.002).epsilon(1e-5));
                REQUIRE(balanced.at(x, y)[c] * 1023.0 == Approx(445.0 + (d - curve(log_h_grey)) / 0.002).epsilon(1e-5));
            }
}

TEST_CASE("halation adds its strength of the light, spread as a Gaussian of its radius", "[colour][halation]") {
    const double pitch_um = 5, radius_um = 40, strength = 0.25;
    HalationKernel k = design_halation(strength, radius_um, pitch_um);
    Window frame{0, 0, 129, 129};
    Plane point(frame, 0.0f), out(frame);
    point.at(64, 64) = 1.0f;
    apply_halation(point, out, k, frame, 2);
    double sum = 0, second_moment = 0;
    for (int y = 0; y < 129; ++y)
        for (int x = 0; x < 129; ++x) {
            double v = out.at(x, y) - point.at(x, y);
            sum += v;
            second_moment += v * ((x - 64) * (x - 64));
        }
    CHECK(sum == Approx(strength).epsilon(1e-5));
    // Variance of the pixel-integrated Gaussian: sigma^2 + 1/12 pixel^2.
    double sigma_px = radius_um / pitch_um;
    CHECK(second_moment / sum == Approx(sigma_px * sigma_px + 1.0 / 12).epsilon(2e-3));
}

TEST_CASE("texture leaves tone and colour unchanged on average and bypasses cleanly", "[colour][texture]") {
    Stock film = test::test_colour_film();
    const int size = 256;
    Image flat(size, size, 3);
    for (int i = 0; i < size * size; ++i) {
        flat.pixels[3 * i] = 0.30f, flat.pixels[3 * i + 1] = 0.18f, flat.pixels[3 * i + 2] = 0.07f;
    }
    DevelopSettings s;
    s.output = OutputMode::texture;
    s.frame_width_mm = 6.0;  // coarse grain at this pitch: a strong test
    Image out = render(film, nullptr, s, flat, 2);
    for (int c = 0; c < 3; ++c) {
        // Standard error of the mean from 16x16 block means (the grain is spatially correlated).
        std::vector<double> blocks;
        for (int by = 0; by < size; by += 16)
            for (int bx = 0; bx < size; bx += 16) {
                double m = 0;
                for (int y = by; y < by + 16; ++y)
                    for (int x = bx; x < bx + 16; ++x) m += out.at(x, y)[c];
                blocks.push_back(m / 256);
            }
        double mean = 0, var = 0;
        for (double b : blocks) mean += b / blocks.size();
        for (double b : blocks) var += (b - mean) * (b - mean) / (blocks.size() - 1);
        double standard_error = std::sqrt(var / blocks.size());
        double expected = flat.at(0, 0)[c];
        INFO("channel " << c << " mean " << mean << " standard error " << standard_error);
        CHECK(std::abs(mean - expected) < 3 * standard_error);
        CHECK(std::sqrt(var) > 1e-4 * expected);  // there is grain
    }
    // With grain, MTF and halation off, texture returns its input.
    Image scene = demo_scene(40, 30);
    Image bypass = render(film, nullptr, clean(OutputMode::texture), scene);
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x)
            for (int c = 0; c < 3; ++c) REQUIRE(bypass.at(x, y)[c] == Approx(scene.at(x, y)[c]).epsilon(1e-6));
}

TEST_CASE("colour renders are the same for any thread count and window", "[colour][determinism]") {
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image scene = demo_scene(96, 64);
    for (Quality quality : kQualities)
    for (OutputMode mode : {OutputMode::print, OutputMode::scan, OutputMode::texture}) {
        DevelopSettings s;
        s.quality = quality;
        s.output = mode;
        s.frame_width_mm = 3.0;  // kernels of several pixels: halos matter
        s.halation = 3.0;
        s.seed = 5;
        s.frame = 1001;
        Image full = render(film, &paper, s, scene, 1);
        CHECK(render(film, &paper, s, scene, 7).pixels == full.pixels);
        for (Window w : {Window{0, 0, 1, 1}, Window{31, 17, 60, 40}, Window{90, 50, 96, 64}}) {
            Image part = render(film, &paper, s, scene, 3, w);
            for (int y = w.y0; y < w.y1; ++y)
                for (int x = w.x0; x < w.x1; ++x)
                    for (int c = 0; c < 3; ++c) REQUIRE(part.at(x, y)[c] == full.at(x, y)[c]);
        }
    }
}

TEST_CASE("per-channel grain settings change only their channel", "[colour][grain]") {
    Stock film = test::test_colour_film();
    Image grey(64, 64, 3, 0.18f);
    DevelopSettings s;
    s.output = OutputMode::density;
    s.mtf = false;
    s.halation = 0;
    auto channel_std = [](const Image& im, int c) {
        double m = 0, v = 0;
        size_t n = im.pixels.size() / 3;
        for (size_t i = 0; i < n; ++i) m += im.pixels[3 * i + c] / n;
        for (size_t i = 0; i < n; ++i) v += (im.pixels[3 * i + c] - m) * (im.pixels[3 * i + c] - m) / n;
        return std::sqrt(v);
    };
    Image base = render(film, nullptr, s, grey);
    s.grain_amount = {1, 2, 1};
    Image more_green = render(film, nullptr, s, grey);
    CHECK(channel_std(more_green, 1) == Approx(2 * channel_std(base, 1)).epsilon(1e-3));
    for (int c : {0, 2})
        for (size_t i = c; i < base.pixels.size(); i += 3) REQUIRE(more_green.pixels[i] == base.pixels[i]);
}

TEST_CASE("bad colour stocks and pixels get clear errors or finite output", "[colour][bad-input]") {
    auto error_of = [](const std::string& json) { return test::stock_error_of(json, "c.json"); };
    const std::string good = test::test_colour_film_json();
    auto replace = [&](const std::string& from, const std::string& to) { return test::replaced(good, from, to); };
    // A missing channel: two layers.
    std::string two = good.substr(0, good.rfind(",{\"name\": \"blue\"")) + "]}";
    CHECK_THAT(error_of(two), Catch::Contains("exactly three layers"));
    CHECK_THAT(error_of(replace(R"("dye_density": {"gaussians": [{"nm": 450)", R"("dye_xx": {"gaussians": [{"nm": 450)")),
               Catch::Contains("layers[2].dye_density': missing"));
    CHECK_THAT(error_of(replace(R"({"nm": 680, "sigma_nm": 55, "weight": 1}, {"nm": 440, "sigma_nm": 40, "weight": 0.1})",
                                R"({"nm": 680, "sigma_nm": 55, "weight": -1})")),
               Catch::Contains("layers[0].dye_density") && Catch::Contains("not positive"));
    CHECK_THAT(error_of(replace(R"("exposure_illuminant": "D55")", R"("exposure_illuminant": "F11")")),
               Catch::Contains("unknown illuminant 'F11'"));
    CHECK_THAT(error_of(replace(R"({"log_h": 1.0, "slope": -0.6, "width": 0.4})", R"({"log_h": 1.0, "slope": -0.9, "width": 0.4})")),
               Catch::Contains("density must not decrease"));
    CHECK_THAT(error_of(replace(R"("base_density": {"constant": 0.1, "gaussians")", R"("base_density": {"nm": [400, 500], "values": [1], "x")")),
               Catch::Contains("'nm' has 2 values but 'values' has 1"));

    // Out-of-gamut, negative and non-finite pixels: finite output in every mode.
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    const float pixels[][3] = {{nan, 0.2f, 0.2f}, {inf, -inf, 1}, {-1, 2, -0.5f}, {1e30f, 0, 0}, {0, 0, 1e-38f}, {5, -3, 0}};
    Image in(6, 1, 3);
    for (int x = 0; x < 6; ++x)
        for (int c = 0; c < 3; ++c) in.at(x, 0)[c] = pixels[x][c];
    for (OutputMode mode : {OutputMode::print, OutputMode::negative, OutputMode::density, OutputMode::scan, OutputMode::texture}) {
        DevelopSettings s;
        s.output = mode;
        s.halation = 5;
        Image out = render(film, &paper, s, in);
        for (float v : out.pixels) REQUIRE(std::isfinite(v));
    }
}
