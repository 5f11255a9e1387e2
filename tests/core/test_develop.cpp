#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/demo_scene.h"
#include "core/develop.h"
#include "core/develop_rows.h"
#include "test_support.h"

using namespace darkroom;

namespace {

using test::render;

DevelopSettings density_settings() {
    DevelopSettings s;
    s.output = OutputMode::density;
    return s;
}

}  // namespace

TEST_CASE("at 0 EV scene-linear 0.18 receives the ISO mid-grey exposure", "[develop]") {
    Stock film = test::test_film();
    DevelopSettings s = density_settings();
    s.grain = false;
    Image grey(8, 8, 3, 0.18f);
    Image d = render(film, nullptr, s, grey);
    double expected_h = 0.65 * 12.5 / film.iso_speed;
    CHECK(d.at(4, 4)[0] == Approx(film.layers[0].density_curve(std::log10(expected_h))).margin(1e-5));
    s.exposure_ev = 1.0;  // one stop more doubles H
    Image d1 = render(film, nullptr, s, grey);
    CHECK(d1.at(4, 4)[0] == Approx(film.layers[0].density_curve(std::log10(2 * expected_h))).margin(1e-5));
}

TEST_CASE("a reversal film's print is the film itself, viewed: more light gives a brighter slide, no paper",
          "[develop][reversal]") {
    const Stock slide = find_stock("fujifilm-provia-100f"), print_film = find_stock("kodak-2383");
    REQUIRE(slide.kind == StockKind::reversal);
    DevelopSettings s;
    s.quality = Quality::high;
    s.grain = s.mtf = false;
    s.halation = 0;
    Image ramp(13, 1, 3);  // greys from -3 to +3 EV around mid grey, half a stop apart
    for (int i = 0; i < 13; ++i)
        for (int c = 0; c < 3; ++c) ramp.at(i, 0)[c] = float(0.18 * std::exp2(-3.0 + 0.5 * i));
    const Image slide_print = render(slide, nullptr, s, ramp);
    // A paper given (the look's default) is not used: the slide is the picture.
    CHECK(render(slide, &print_film, s, ramp).pixels == slide_print.pixels);
    DevelopSettings density = s;
    density.output = OutputMode::density;
    const Image d = render(slide, nullptr, density, ramp);
    const PrintView view(slide, {s.print_viewing, s.print_gamut_compression});
    // Seen media-relative (the default), a normally exposed mid grey is 0.18, as on every print.
    REQUIRE(s.print_viewing == PrintViewing::media_relative);
    const float* grey = slide_print.at(6, 0);
    CHECK(luminance({grey[0], grey[1], grey[2]}) == Approx(0.18).epsilon(0.02));
    for (int i = 0; i < 13; ++i) {
        INFO("step " << i);
        const double layer_density[3] = {d.at(i, 0)[0], d.at(i, 0)[1], d.at(i, 0)[2]};
        double rgb[3];
        view.rgb(layer_density, rgb);
        for (int c = 0; c < 3; ++c) CHECK(slide_print.at(i, 0)[c] == Approx(rgb[c]).epsilon(1e-5));
        if (i == 0) continue;
        for (int c = 0; c < 3; ++c) {
            CHECK(d.at(i, 0)[c] < d.at(i - 1, 0)[c]);  // a positive: density falls as light rises
            CHECK(slide_print.at(i, 0)[c] > slide_print.at(i - 1, 0)[c]);
        }
    }
    // The fast tier views the densities through a table: within 1 % of the spectral view
    // (its curves are tables too), wherever the slide is not near black.
    s.quality = Quality::fast;
    const Image fast = render(slide, nullptr, s, ramp);
    for (int i = 0; i < 13; ++i)
        for (int c = 0; c < 3; ++c)
            if (slide_print.at(i, 0)[c] > 0.01) CHECK(fast.at(i, 0)[c] == Approx(slide_print.at(i, 0)[c]).epsilon(0.01));
    // A reversal film is a camera film: it exposes in the camera, it is not printed on.
    CHECK_THROWS_WITH(Plan::compile(find_stock("kodak-vision3-250d"), &slide, s, {4, 4}),
                      Catch::Contains("'fujifilm-provia-100f' is a camera film, not a paper or print film"));
}

TEST_CASE("lux-seconds input is the exposure itself", "[develop]") {
    Stock film = test::test_film();
    DevelopSettings s = density_settings();
    s.input_units = InputUnits::lux_seconds;
    s.grain = false;
    for (double h : {1e-4, 3e-3, 0.05, 2.0}) {
        Image in(6, 6, 3, float(h));
        CHECK(render(film, nullptr, s, in).at(3, 3)[0] == Approx(film.layers[0].density_curve(std::log10(h))).margin(1e-5));
    }
}

TEST_CASE("the texture's grain is the same whether the input is scene-linear or in lux seconds", "[develop]") {
    // The grain's exposure fluctuation takes the curve's slope at mid grey: the film's, at its
    // ISO speed, in either units (in lux seconds 0.18 is no grey: 2.5 stops over 250D's).
    Stock film = find_stock("kodak-vision3-250d");
    const double lux_s_per_unit = mid_grey_exposure_lux_s(film.iso_speed) / 0.18;
    Image scene = demo_scene(64, 48), lux_seconds = scene;
    for (float& v : lux_seconds.pixels) v = float(v * lux_s_per_unit);
    DevelopSettings s;
    s.output = OutputMode::texture;
    Image from_scene = render(film, nullptr, s, scene);
    s.input_units = InputUnits::lux_seconds;
    Image from_lux_seconds = render(film, nullptr, s, lux_seconds);
    for (size_t i = 0; i < scene.pixels.size(); ++i)
        REQUIRE(from_lux_seconds.pixels[i] / lux_s_per_unit == Approx(from_scene.pixels[i]).epsilon(1e-4));
}

TEST_CASE("negative output is the transmittance of the density output", "[develop]") {
    Stock film = test::test_film();
    Image scene = demo_scene(96, 64);
    DevelopSettings s = density_settings();
    Image d = render(film, nullptr, s, scene);
    s.output = OutputMode::negative;
    Image t = render(film, nullptr, s, scene);
    for (size_t i = 0; i < d.pixels.size(); ++i) REQUIRE(t.pixels[i] == Approx(std::pow(10.0, -d.pixels[i])).epsilon(1e-6));
}

TEST_CASE("mid grey prints at 18 % reflectance with the automatic print exposure", "[develop]") {
    Stock film = test::test_film(), paper = test::test_paper();
    DevelopSettings s;
    s.grain = false;
    Image grey(8, 8, 3, 0.18f);
    CHECK(render(film, &paper, s, grey).at(4, 4)[0] == Approx(0.18).epsilon(0.01));
    // More print exposure: a darker print; more camera exposure: a denser negative, a lighter print.
    s.print_exposure_ev = 1.0;
    CHECK(render(film, &paper, s, grey).at(4, 4)[0] < 0.17);
    s.print_exposure_ev = 0.0;
    s.exposure_ev = 1.0;
    CHECK(render(film, &paper, s, grey).at(4, 4)[0] > 0.19);
}

TEST_CASE("same settings give identical pixels for any thread count and window", "[develop][determinism]") {
    Stock film = test::test_film(), paper = test::test_paper();
    Image scene = demo_scene(160, 120);
    DevelopSettings s;
    s.seed = 11;
    s.frame = 3;
    s.frame_width_mm = 3.0;  // ~19 um pixels: the MTF kernel has a real radius
    s.print_width_mm = 20.0;
    for (auto [quality, mode] : {std::pair{Quality::fast, OutputMode::print}, std::pair{Quality::fast, OutputMode::negative},
                                 std::pair{Quality::preview, OutputMode::print}, std::pair{Quality::preview, OutputMode::negative}}) {
        s.quality = quality;
        s.output = mode;
        Image one = render(film, &paper, s, scene, 1);
        Image many = render(film, &paper, s, scene, 7);
        REQUIRE(one.pixels == many.pixels);
        for (Window w : {Window{0, 0, 37, 29}, Window{50, 41, 160, 120}, Window{77, 3, 78, 4}}) {
            Image part = render(film, &paper, s, scene, 2, w);
            for (int y = w.y0; y < w.y1; ++y)
                for (int x = w.x0; x < w.x1; ++x)
                    for (int c = 0; c < 3; ++c) REQUIRE(part.at(x, y)[c] == one.at(x, y)[c]);
        }
    }
    // Another frame or seed gives other grain.
    s.quality = Quality::fast;
    s.output = OutputMode::negative;
    Image frame3 = render(film, &paper, s, scene);
    s.frame = 4;
    CHECK(render(film, &paper, s, scene).pixels != frame3.pixels);
    s.frame = 3;
    s.seed = 12;
    CHECK(render(film, &paper, s, scene).pixels != frame3.pixels);
}

TEST_CASE("the reference tier's FFT-summed MTF gives any window the whole frame's bits", "[develop][determinism]") {
    // At these pitches film and paper have kernels of radius 119-122 px, summed by FFT on
    // tiles of about 270 px: each window below cuts tiles, at the frame's edges and inside
    // it, and must still be the whole frame's pixels, bit for bit. A bright
    // pixel beyond the windows' reach moves every output of its tile within the FFT's
    // rounding of it (1e10 x 1e-16 here, far more than a float's last bit): a window that
    // summed its tile without it would show.
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image scene = demo_scene(400, 300);
    std::fill_n(scene.at(380, 280), 3, 1e10f);
    DevelopSettings s;
    s.quality = Quality::reference;
    s.grain = false;  // (window-independent on its own: tested above)
    s.halation = 0;   // (its halo would reach over the frame)
    s.frame_width_mm = 0.68;  // 1.7 um pixels
    s.print_width_mm = 3.4;   // 8.5 um pixels
    const Window frame = scene.window;
    for (OutputMode mode : {OutputMode::negative, OutputMode::print}) {
        s.output = mode;
        const Plan plan = Plan::compile(film, &paper, s, {frame.width(), frame.height()});
        REQUIRE(plan.halo_px() >= 2 * kMinFftRadius);
        Image whole(frame, 3);
        plan.run(scene.view(), whole.view(), 2);
        for (Window w : {Window{120, 90, 121, 91}, Window{0, 0, 37, 29}, Window{0, 100, 400, 101}}) {
            Image part(w, 3);
            plan.run(scene.view(), part.view(), 3);
            for (int y = w.y0; y < w.y1; ++y)
                for (int x = w.x0; x < w.x1; ++x)
                    for (int c = 0; c < 3; ++c) REQUIRE(part.at(x, y)[c] == whole.at(x, y)[c]);
        }
    }
}

TEST_CASE("an image that is part of the film frame develops as that part of the whole frame", "[develop][determinism]") {
    // A CG element's bounding box inside the frame, and overscan around it: the plan takes
    // the pitch from the film frame's width and the pixels' coordinates from the frame's origin.
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    DevelopSettings s;
    s.seed = 4;
    s.frame_width_mm = 3.0;
    s.print_width_mm = 20.0;
    s.halation = 0;  // (its halo would reach past these small parts)
    const Image scene = demo_scene(160, 120);
    const Plan whole = Plan::compile(film, &paper, s, {160, 120});
    Image expected(scene.window, 3);
    whole.run(scene.view(), expected.view(), 2);
    struct Part {
        Window window;   // in the frame's coordinates
        Window compare;  // its pixels 12 or more from its edges (inside the frame)
    };
    for (const Part& part : {Part{{40, 30, 120, 90}, {52, 42, 108, 78}}, Part{{-16, -9, 176, 129}, {12, 12, 148, 108}}}) {
        const Window& w = part.window;
        // The part's pixels, in their own buffer: the scene's inside the frame, edge pixels beyond.
        Image pixels(w, 3);
        for (int y = w.y0; y < w.y1; ++y)
            for (int x = w.x0; x < w.x1; ++x)
                std::copy_n(scene.at(std::clamp(x, 0, 159), std::clamp(y, 0, 119)), 3, pixels.at(x, y));
        const FrameGeometry geometry{w.width(), w.height(), false, w.x0, w.y0, 160};
        const Plan plan = Plan::compile(film, &paper, s, geometry);
        Image got(w, 3), moved(w, 3);
        plan.run(pixels.view(), got.view(), 3);
        // The whole frame's plan moved to this image window is the same plan.
        whole.in_image(geometry).run(pixels.view(), moved.view(), 2);
        CHECK(moved.pixels == got.pixels);
        for (int y = part.compare.y0; y < part.compare.y1; ++y)
            for (int x = part.compare.x0; x < part.compare.x1; ++x)
                for (int c = 0; c < 3; ++c) REQUIRE(got.at(x, y)[c] == expected.at(x, y)[c]);
    }
    CHECK_THROWS_WITH(Plan::compile(film, &paper, s, FrameGeometry{10, 10, false, 0, 0, -1}), Catch::Contains("negative"));
    CHECK_THROWS_AS(whole.in_image(FrameGeometry{80, 60, false, 0, 0, 0}), std::invalid_argument);  // another pitch
    CHECK_THROWS_WITH(Plan::compile(film, &paper, s, FrameGeometry{10, 10, false, std::numeric_limits<int>::max() - 5, 0, 0}),
                      Catch::Contains("beyond"));
}

TEST_CASE("a plan compiled once and moved to another frame renders that frame's pixels", "[develop]") {
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image scene = demo_scene(32, 24);
    for (Quality quality : kQualities) {
        INFO(quality_name(quality));
        DevelopSettings s;
        s.quality = quality;
        s.seed = 5;
        s.frame_width_mm = 1.0;
        s.print_width_mm = 5.0;
        const Plan first = Plan::compile(film, &paper, s, {32, 24});
        s.frame = 9;
        const Plan compiled = Plan::compile(film, &paper, s, {32, 24});
        Image moved(scene.window, 3), direct(scene.window, 3), frame0(scene.window, 3);
        first.for_frame(9).run(scene.view(), moved.view(), 2);
        compiled.run(scene.view(), direct.view(), 2);
        first.run(scene.view(), frame0.view(), 2);
        CHECK(moved.pixels == direct.pixels);
        CHECK(moved.pixels != frame0.pixels);  // the grain is the frame's own
    }
}

TEST_CASE("a skipped stage gives the pixels of running it with its neutral value", "[develop]") {
    Image scene = demo_scene(64, 48);
    DevelopSettings s = density_settings();
    s.frame_width_mm = 2.0;
    Stock film = test::test_film();
    Stock zero_grain = parse_stock_json(test::test_film_json(R"({"rms_granularity": 0, "grain_size_um": 1.5})"), "z");
    s.grain = false;
    Image off = render(film, nullptr, s, scene);
    s.grain = true;
    CHECK(render(zero_grain, nullptr, s, scene).pixels == off.pixels);

    Stock flat_mtf = film;
    flat_mtf.layers[0].mtf = make_curve({0, 1000}, {1, 1}, "flat");
    s.grain = false;
    s.mtf = false;
    Image no_mtf = render(film, nullptr, s, scene);
    s.mtf = true;
    CHECK(render(flat_mtf, nullptr, s, scene).pixels == no_mtf.pixels);
}

TEST_CASE("leaving out the stages that cannot change a colour print changes no pixel", "[develop][skip]") {
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image scene = demo_scene(64, 48);
    for (Quality quality : {Quality::high, Quality::fast}) {
        DevelopSettings s;
        s.quality = quality;
        s.frame_width_mm = 2.0;
        s.halation = 0;
        s.grain_amount = {0, 0, 0};
        Plan skipping = Plan::compile(film, &paper, s, {64, 48});
        PlanStructure all_stages;
        all_stages.skip_noop_stages = false;
        Plan running = Plan::compile(film, &paper, s, {64, 48}, 0, all_stages);
        auto has = [](const Plan& p, const std::string& what) {
            for (const std::string& line : p.describe())
                if (line.find(what) != std::string::npos) return true;
            return false;
        };
        CHECK(has(skipping, "skipped halation"));
        CHECK(has(skipping, "skipped grain"));
        // Kept at their neutral values; the fast tier's one print table leaves the paper's
        // grain to the film's (folded, at amount 0 too), which is no skip for a no-op.
        CHECK_FALSE(has(running, "skipped halation (film"));
        CHECK_FALSE(has(running, "skipped grain (film"));
        CHECK_FALSE(has(running, "below"));
        CHECK_FALSE(has(running, "turned off"));
        Image a(scene.window, 3), b(scene.window, 3);
        skipping.run(scene.view(), a.view(), 2);
        running.run(scene.view(), b.view(), 2);
        CHECK(a.pixels == b.pixels);
    }
}

TEST_CASE("grey input skips the spectral stage and develops as R = G = B does", "[develop][skip]") {
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image colour = demo_scene(48, 32);
    Image grey(colour.window, 1), grey_rgb(colour.window, 3);
    for (size_t i = 0; i < grey.pixels.size(); ++i) {
        grey.pixels[i] = colour.pixels[3 * i + 1];
        for (int c = 0; c < 3; ++c) grey_rgb.pixels[3 * i + c] = grey.pixels[i];
    }
    DevelopSettings s;
    s.frame_width_mm = 2.0;
    Plan rgb_plan = Plan::compile(film, &paper, s, {48, 32});
    Plan grey_plan = Plan::compile(film, &paper, s, {48, 32, true});
    bool says_why = false;
    for (const std::string& line : grey_plan.describe()) says_why |= line.find("skipped spectral") != std::string::npos;
    CHECK(says_why);
    Image a(colour.window, 3), b(colour.window, 3);
    rgb_plan.run(grey_rgb.view(), a.view(), 1);
    grey_plan.run(grey.view(), b.view(), 1);
    // The same exposure summed in another order: within float rounding, through the curves.
    for (size_t i = 0; i < a.pixels.size(); ++i) REQUIRE(b.pixels[i] == Approx(a.pixels[i]).epsilon(1e-5).margin(1e-6));
}

TEST_CASE("grey and alpha input develops as its grey alone and passes its alpha", "[develop]") {
    Stock film = test::test_colour_film(), paper = test::test_colour_paper();
    Image colour = demo_scene(48, 32);
    Image grey(colour.window, 1), grey_alpha(colour.window, 2);
    for (size_t i = 0; i < grey.pixels.size(); ++i) {
        grey.pixels[i] = grey_alpha.pixels[2 * i] = colour.pixels[3 * i + 1];
        grey_alpha.pixels[2 * i + 1] = colour.pixels[3 * i];  // an alpha unlike the grey
    }
    // The grey path, the spectral path that reads R, G and B, and the texture output.
    for (auto [skip, output] : {std::pair{true, OutputMode::print}, std::pair{false, OutputMode::print},
                                std::pair{true, OutputMode::texture}}) {
        INFO("skip_noop_stages " << skip << ", output " << int(output));
        DevelopSettings s;
        s.frame_width_mm = 2.0;
        s.output = output;
        PlanStructure structure;
        structure.skip_noop_stages = skip;
        Plan plan = Plan::compile(film, &paper, s, {48, 32, true}, 0, structure);
        Image a(colour.window, 3), b(colour.window, 4);
        plan.run(grey.view(), a.view(), 1);
        plan.run(grey_alpha.view(), b.view(), 1);
        for (size_t i = 0; i < grey.pixels.size(); ++i) {
            for (int c = 0; c < 3; ++c) REQUIRE(b.pixels[4 * i + c] == a.pixels[3 * i + c]);
            REQUIRE(b.pixels[4 * i + 3] == grey_alpha.pixels[2 * i + 1]);
        }
    }
}

TEST_CASE("non-finite and negative pixels have a defined treatment and finite output", "[develop][stability]") {
    Stock film = test::test_film(), paper = test::test_paper();
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    Image in(7, 1, 3);
    const float values[7] = {nan, inf, -inf, -1.0f, 0.0f, 1e-38f, 3e38f};
    for (int x = 0; x < 7; ++x)
        for (int c = 0; c < 3; ++c) in.at(x, 0)[c] = values[x];
    for (OutputMode mode : {OutputMode::print, OutputMode::negative, OutputMode::density}) {
        DevelopSettings s;
        s.output = mode;
        Image out = render(film, &paper, s, in);
        for (float v : out.pixels) REQUIRE(std::isfinite(v));
        if (mode == OutputMode::density) {
            s.grain = false;
            s.mtf = false;  // keep each pixel's treatment apart from its neighbours'
            Image clean = render(film, &paper, s, in);
            // NaN, -Inf and negatives count as no light: base+fog density.
            for (int x : {0, 2, 3, 4}) CHECK(clean.at(x, 0)[0] == Approx(film.layers[0].density_curve.y_min()).margin(1e-3));
            // +Inf is the brightest light: the shoulder.
            CHECK(clean.at(1, 0)[0] == Approx(film.layers[0].density_curve.y_max()).margin(1e-3));
        }
    }
}

TEST_CASE("bad settings are rejected with the reason", "[develop]") {
    Stock film = test::test_film(), paper = test::test_paper();
    DevelopSettings s;
    CHECK_THROWS_WITH(Plan::compile(film, nullptr, s, {8, 8}), Catch::Contains("print output needs a paper"));
    CHECK_THROWS_WITH(Plan::compile(paper, nullptr, density_settings(), {8, 8}), Catch::Contains("not a film"));
    CHECK_THROWS_WITH(Plan::compile(film, &paper, s, {0, 8}), Catch::Contains("empty"));
    s.exposure_ev = NAN;
    CHECK_THROWS_WITH(Plan::compile(film, &paper, s, {8, 8}), Catch::Contains("exposure"));
}

TEST_CASE("the fast tiers' run a row at a time gives the pixels of the stage-by-stage run", "[develop][one-pass]") {
    // Every stage at a 4K frame's pitch (grain, MTF, halation on its coarse grid), a frame
    // narrower than the halation's halo and odd in size, RGB, RGBA and grey input, outputs,
    // settings that leave stages out, windows and thread counts: one pass must change nothing.
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Stock bw = test::test_film(), bw_paper = test::test_paper(), slide = find_stock("fujifilm-provia-100f");
    const int width = 203, height = 77;
    const Image rgb = demo_scene(width, height);
    Image rgba(width, height, 4), grey(width, height, 1);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            for (int c = 0; c < 3; ++c) rgba.at(x, y)[c] = rgb.at(x, y)[c];
            rgba.at(x, y)[3] = float(x % 7) / 7;
            grey.at(x, y)[0] = rgb.at(x, y)[1];
        }
    int one_pass_runs = 0, runs = 0;
    auto compare = [&](const Stock& f, const Stock* p, DevelopSettings s, const Image& scene, int threads, Window w,
                       PlanStructure structure = {}) {
        s.frame_width_mm = f.frame_width_mm * width / 4096;
        s.print_width_mm = p ? p->frame_width_mm * width / 4096 : 0.0;
        FrameGeometry frame{width, height};
        frame.monochrome = scene.channels == 1;
        const Plan plan = Plan::compile(f, s.output == OutputMode::print ? p : nullptr, s, frame, 0, structure);
        structure.one_pass = false;
        const Plan staged = Plan::compile(f, s.output == OutputMode::print ? p : nullptr, s, frame, 0, structure);
        const std::vector<std::string> lines = plan.describe();
        one_pass_runs += std::count(lines.begin(), lines.end(), "run: every stage a row at a time, the frame's planes never stored");
        Image a(w, 4, -1.0f), b(w, 4, -1.0f);
        ++runs;
        plan.run(scene.view(), a.view(), threads);
        staged.run(scene.view(), b.view(), threads);
        INFO(quality_name(s.quality) << " output " << int(s.output) << " channels " << scene.channels << " window "
                                     << w.x0 << "," << w.y0 << " " << w.width() << "x" << w.height() << " threads "
                                     << threads << " halation " << s.halation << " mtf " << s.mtf << " grain " << s.grain);
        REQUIRE(a.pixels == b.pixels);
    };
    const Window whole{0, 0, width, height};
    for (Quality q : {Quality::fast, Quality::preview})
        for (OutputMode output : {OutputMode::print, OutputMode::negative, OutputMode::density, OutputMode::scan}) {
            DevelopSettings s;
            s.quality = q;
            s.output = output;
            s.seed = 5;
            s.frame = 2;
            for (const Image* scene : std::vector<const Image*>{&rgb, &rgba, &grey}) compare(film, &paper, s, *scene, 2, whole);
            for (Window w : {Window{0, 0, 31, 20}, Window{150, 60, 203, 77}, Window{90, 30, 91, 31}})
                compare(film, &paper, s, rgb, 3, w);
            compare(film, &paper, s, rgb, 1, whole);
            compare(bw, &bw_paper, s, grey, 2, whole);
            compare(slide, nullptr, s, rgb, 2, whole);  // a reversal film's print: its view table
            DevelopSettings off = s;
            off.halation = 0;
            compare(film, &paper, off, rgb, 2, whole);
            off.mtf = false;
            compare(film, &paper, off, rgb, 2, whole);
            off = s;
            off.grain = false;
            compare(film, &paper, off, rgb, 2, whole);
            off = s;
            off.grain_amount = {0, 0, 0};
            PlanStructure all_stages;
            all_stages.skip_noop_stages = false;
            compare(film, &paper, off, rgb, 2, whole, all_stages);
        }
    // All but the one-layer film's prints (no tables to stream: they run stage by stage).
    CHECK(one_pass_runs == runs - 2);
}

TEST_CASE("a result row is written to RGB and RGBA pixels, with the input's alpha, as its definition says",
          "[develop][write]") {
    const int width = 16 * 5 + 5;  // vector blocks of every instruction set and a tail
    std::vector<float> planes[3];
    for (int c = 0; c < 3; ++c)
        for (int x = 0; x < width; ++x) planes[c].push_back(float(c * 1000 + x));
    for (int in_channels : {1, 2, 3, 4, 5})
        for (int out_channels : {3, 4, 6})
            for (size_t result_planes : {size_t(1), size_t(3)})
                // From every first pixel of a vector block: each alignment of the row in memory
                // (RGB rows are streamed past the cache from their first 64-byte aligned pixel).
                for (int first = 0; first <= 16; ++first) {
                    const float* result[3] = {planes[0].data() + first, planes[1].data() + first,
                                              planes[2].data() + first};
                    Image in(width, 1, in_channels), out(width, 1, out_channels, -7.0f);
                    for (size_t i = 0; i < in.pixels.size(); ++i) in.pixels[i] = -float(i);
                    write_row(result, result_planes, in.view(), out.view(), 0, first, width - first);
                    const int alpha = colour_channel_count(in_channels);
                    INFO("in " << in_channels << ", out " << out_channels << ", planes " << result_planes << ", from "
                               << first);
                    for (int x = 0; x < width; ++x) {
                        for (int c = 0; c < 3; ++c)
                            REQUIRE(out.at(x, 0)[c] ==
                                    (x < first ? -7.0f : planes[std::min<size_t>(c, result_planes - 1)][x]));
                        const bool has_alpha = alpha < in_channels && out_channels >= 4 && x >= first;
                        if (out_channels >= 4) REQUIRE(out.at(x, 0)[3] == (has_alpha ? in.at(x, 0)[alpha] : -7.0f));
                        for (int c = 4; c < out_channels; ++c) REQUIRE(out.at(x, 0)[c] == -7.0f);
                    }
                }
}

TEST_CASE("the reference tier's budget refuses a render of more than a day before it starts", "[develop][quality]") {
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    DevelopSettings s;
    s.quality = Quality::reference;
    // A 150 mm frame in 48 x 32 px: 3 mm of film a pixel, billions of silver grains each, and
    // about 30 times a Super 35 frame's area in all.
    s.frame_width_mm = s.print_width_mm = 150;
    const Window frame{0, 0, 48, 32};
    const Plan plan = Plan::compile(film, &paper, s, {frame.width(), frame.height()}, 1);
    REQUIRE(reference_cpu_seconds(plan, frame) > kReferenceCpuBudgetSeconds);
    CHECK_THROWS_WITH(check_reference_render_budget(plan, frame, "--quality "),
                      Catch::Contains("--quality reference") && Catch::Contains("window 0,0,48,32") &&
                          Catch::Contains("budget of 24 CPU hours"));
    // The estimate counts every pixel whose grain is drawn: an interior window's halo too.
    const Window inner{20, 12, 24, 16};
    CHECK(plan.silver_grains_drawn(inner) > 2 * plan.silver_grains_per_pixel() * inner.pixel_count());
    // One pixel of it is within the budget, and still long enough to be warned of.
    const Window one{24, 16, 25, 17};
    REQUIRE(reference_cpu_seconds(plan, one) < kReferenceCpuBudgetSeconds);
    std::string warning;
    CHECK_NOTHROW(warning = check_reference_render_budget(plan, one, "--quality "));
    CHECK_THAT(warning, Catch::Contains("CPU hours") && Catch::Contains("--quality high"));
    // The other tiers draw no silver grains: nothing to refuse or warn of.
    s.quality = Quality::high;
    const Plan high = Plan::compile(film, &paper, s, {frame.width(), frame.height()}, 1);
    CHECK(high.silver_grains_drawn(frame) == 0);
    CHECK(check_reference_render_budget(high, frame, "--quality ").empty());
}

TEST_CASE("the proxy's upsample keeps a constant and reproduces a linear ramp, held at the edges",
          "[develop][preview]") {
    // Bilinear interpolation at frame pixel x's centre, proxy coordinate t = (x + 1/2) / N - 1/2,
    // with the edge pixels repeated: a linear function of the proxy's pixels gives that function
    // at t clamped to the proxy frame's first and last centres. Factors with vector code
    // (2, 3, 8) and without (9), every instruction set, windows at any offset in a block.
    test::IsaScope scope;
    const Window proxy_frame{-3, 2, 31, 19};
    Image proxy(proxy_frame, 3);
    auto ramp = [](double X, double Y) { return std::array<double, 3>{0.37, 0.5 + 0.25 * X, -1 + 0.125 * Y}; };
    for (int Y = proxy_frame.y0; Y < proxy_frame.y1; ++Y)
        for (int X = proxy_frame.x0; X < proxy_frame.x1; ++X)
            for (int c = 0; c < 3; ++c) proxy.at(X, Y)[c] = float(ramp(X, Y)[size_t(c)]);
    for (simd::Isa isa : test::runnable_isas()) {
        simd::set_isa(isa);
        for (int n : {2, 3, 8, 9}) {
            const Window frame{n * proxy_frame.x0, n * proxy_frame.y0, n * proxy_frame.x1, n * proxy_frame.y1};
            const Image in(frame, 3);
            for (const Window& w : {frame, Window{frame.x0 + 1, frame.y0 + n + 2, frame.x1 - n - 1, frame.y1 - 1}}) {
                INFO(simd::isa_name(isa) << ", factor " << n << ", window from " << w.x0 << "," << w.y0);
                Image out(w, 3);
                upsample_proxy(proxy.view(), proxy_frame, n, in.view(), out.view(), w, 2);
                for (int y = w.y0; y < w.y1; ++y)
                    for (int x = w.x0; x < w.x1; ++x) {
                        const double tx = std::clamp((x + 0.5) / n - 0.5, proxy_frame.x0 + 0.0, proxy_frame.x1 - 1.0);
                        const double ty = std::clamp((y + 0.5) / n - 0.5, proxy_frame.y0 + 0.0, proxy_frame.y1 - 1.0);
                        for (int c = 0; c < 3; ++c)
                            REQUIRE(out.at(x, y)[c] == Approx(ramp(tx, ty)[size_t(c)]).margin(2e-6));
                    }
            }
        }
    }
}

TEST_CASE("the grain's standard deviation after the proxy's upsample is proxy_upsampled_sigma_ratio's",
          "[develop][preview][grain]") {
    // At factor 2 the closed form it had: along an axis 3/4 a + 1/4 b, variance 9/16 + 1/16 +
    // 6/16 rho; both axes: (0.625 + 0.375 rho)^2.
    for (double rho : {0.0, 0.3, 0.8}) CHECK(proxy_upsampled_sigma_ratio(rho, 2) == Approx(0.625 + 0.375 * rho));
    // Monte Carlo: unit Gaussian noise with lag-1 correlation rho along x and y (an AR(1)
    // filter along each axis: correlation rho^|dx| rho^|dy|), upsampled; its RMS over the
    // frame's pixels away from the proxy frame's edges.
    constexpr int kSide = 400;
    const Window proxy_frame{0, 0, kSide, kSide};
    for (double rho : {0.0, 0.6})
        for (int n : {2, 3, 5}) {
            std::mt19937 random(7);
            std::normal_distribution<double> normal;
            std::vector<double> field(size_t(kSide) * kSide);
            for (double& v : field) v = normal(random);
            const double innovation = std::sqrt(1 - rho * rho);
            for (int y = 0; y < kSide; ++y)
                for (int x = 1; x < kSide; ++x)
                    field[size_t(y) * kSide + x] = rho * field[size_t(y) * kSide + x - 1] + innovation * field[size_t(y) * kSide + x];
            for (int y = 1; y < kSide; ++y)
                for (int x = 0; x < kSide; ++x)
                    field[size_t(y) * kSide + x] = rho * field[size_t(y - 1) * kSide + x] + innovation * field[size_t(y) * kSide + x];
            Image proxy(proxy_frame, 3);
            for (size_t i = 0; i < field.size(); ++i)
                for (int c = 0; c < 3; ++c) proxy.pixels[3 * i + size_t(c)] = float(field[i]);
            const Window frame{0, 0, n * kSide, n * kSide};
            const Window inside = frame.grown(-n);
            const Image in(inside, 3);
            Image out(inside, 3);
            upsample_proxy(proxy.view(), proxy_frame, n, in.view(), out.view(), inside, 2);
            double proxy_sum2 = 0, out_sum2 = 0;
            for (double v : field) proxy_sum2 += v * v;
            for (size_t i = 0; i < out.pixels.size(); i += 3) out_sum2 += double(out.pixels[i]) * out.pixels[i];
            const double ratio = std::sqrt(out_sum2 / double(inside.pixel_count()) / (proxy_sum2 / double(field.size())));
            INFO("rho " << rho << ", factor " << n);
            CHECK(ratio == Approx(proxy_upsampled_sigma_ratio(rho, n)).epsilon(0.01));
        }
}
