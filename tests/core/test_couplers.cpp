// DIR couplers in colour development (core/stages/couplers.h, docs/model/dir-couplers.md).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/demo_scene.h"
#include "core/develop.h"
#include "core/spectral.h"
#include "core/stages/couplers.h"
#include "core/stages/filters.h"
#include "test_support.h"

using namespace darkroom;

namespace {

using test::render;

// The stock with its couplers' matrix zero: developed through its data sheet's curves alone.
Stock without_couplers(Stock s) {
    s.dir_couplers = DirCouplerSpec{};
    return s;
}

// A row of neutral exposures (lux-seconds, every layer the same) developed to densities
// (grain, MTF and halation off), on a frame `pitch_um` a pixel.
Image develop_neutral_row(const Stock& film, const std::vector<float>& lux_seconds, double pitch_um,
                          const DevelopSettings& settings) {
    DevelopSettings s = settings;
    s.output = OutputMode::density;
    s.input_units = InputUnits::lux_seconds;
    s.grain = s.mtf = false;
    s.halation = 0;
    const int width = int(lux_seconds.size()), height = 3;
    s.frame_width_mm = width * pitch_um / 1000;
    Image in(width, height, 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c) in.at(x, y)[c] = lux_seconds[size_t(x)];
    return render(film, nullptr, s, in);
}

double lab_chroma(const float* rgb) {
    const Lab lab = xyz_to_lab(linear_srgb_to_xyz({rgb[0], rgb[1], rgb[2]}), linear_srgb_to_xyz({1, 1, 1}));
    return std::hypot(lab[1], lab[2]);
}

}  // namespace

TEST_CASE("DIR couplers at amount 0 give the pixels of the data sheet's curves, bit for bit", "[couplers]") {
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Stock plain = without_couplers(film);
    const Image scene = demo_scene(96, 64);
    for (Quality q : kQualities) {
        for (OutputMode output : {OutputMode::print, OutputMode::density}) {
            DevelopSettings s;
            s.quality = q;
            s.output = output;
            s.frame_width_mm = 0.4;  // ~4 um pixels: the inhibitor's spread would reach several
            s.print_width_mm = 4;
            if (q == Quality::reference) s.grain = false;  // (silver disks at this pitch take long)
            DevelopSettings off = s;
            off.dir_couplers = 0;
            INFO(quality_name(q) << " output " << int(output));
            const Image a = render(film, &paper, off, scene, 2), b = render(plain, &paper, s, scene, 2);
            REQUIRE(a.pixels == b.pixels);
            CHECK(render(film, &paper, s, scene, 2).pixels != a.pixels);  // (on, they change the image)
        }
    }
    // Off, a pixel's density is its layer's curve at its exposure (the reference tier evaluates
    // the curve in double).
    DevelopSettings s;
    s.quality = Quality::reference;
    s.dir_couplers = 0;
    const std::vector<float> h = {0.0005f, 0.003f, 0.02f, 0.1f, 0.7f, 4.0f};
    const Image d = develop_neutral_row(film, h, 5.0, s);
    for (size_t x = 0; x < h.size(); ++x)
        for (int l = 0; l < 3; ++l)
            CHECK(d.at(int(x), 1)[l] ==
                  Approx(film.layers[size_t(l)].density_curve(std::log10(double(h[x])))).epsilon(1e-6));
}

TEST_CASE("the curves before inhibition develop a neutral uniform field to the data sheet", "[couplers]") {
    // Every built-in colour negative at every tier: the stage's own inversion, with the
    // default couplers and 1.8 times them (the most the steepest built-in curve, Portra 800
    // pushed two stops, can be inverted for). The steeper curves before inhibition leave more
    // to the tiers' curve tables: up to 0.02 D, and at the preview tier's coarser tables (2^5
    // samples an octave) up to 0.013 D at the default.
    for (const Stock& film : builtin_stocks()) {
        if (film.kind != StockKind::negative || !film.is_colour()) continue;
        std::vector<float> h;
        for (double log_h = -4; log_h <= 1.5; log_h += 0.05) h.push_back(float(std::pow(10.0, log_h)));
        for (Quality q : kQualities)
            for (double amount : {1.0, 1.8}) {
                DevelopSettings s;
                s.quality = q;
                s.dir_couplers = amount;
                const Image d = develop_neutral_row(film, h, 2000.0, s);  // (pixels far apart: uniform fields)
                double worst = 0;
                for (size_t x = 0; x < h.size(); ++x)
                    for (int l = 0; l < 3; ++l)
                        worst = std::max(worst, std::abs(d.at(int(x), 1)[l] -
                                                         film.layers[size_t(l)].density_curve(std::log10(double(h[x])))));
                INFO(film.id << " " << quality_name(q) << " amount " << amount);
                CHECK(worst <= (amount > 1 ? 0.02 : q == Quality::preview ? 0.015 : 0.005));
            }
    }
}

TEST_CASE("DIR couplers raise a colour chart's print chroma with their amount", "[couplers]") {
    // The median over the chart's 18 colour patches of each patch's CIELAB chroma over its
    // chroma without couplers: above 1, and rising with the amount.
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const int width = 288, height = 192;  // the demo scene's chart: rows 144-191, patches 48 x 12
    const Image scene = demo_scene(width, height);
    auto patch_chroma = [&](double amount) {
        DevelopSettings s;
        s.grain = false;
        s.dir_couplers = amount;
        const Image print = render(film, &paper, s, scene, 2);
        std::vector<double> chroma;
        for (int patch = 0; patch < 18; ++patch)  // (the last six are greys)
            chroma.push_back(lab_chroma(print.at(patch % 6 * 48 + 24, 144 + patch / 6 * 12 + 6)));
        return chroma;
    };
    const std::vector<double> off = patch_chroma(0);
    double last = 1;
    for (double amount : {0.5, 1.0, 2.0}) {
        const std::vector<double> on = patch_chroma(amount);
        std::vector<double> ratio;
        for (size_t i = 0; i < on.size(); ++i) ratio.push_back(on[i] / off[i]);
        std::nth_element(ratio.begin(), ratio.begin() + 9, ratio.end());
        const double median = 0.5 * (ratio[9] + *std::max_element(ratio.begin(), ratio.begin() + 9));
        INFO("amount " << amount << ": median chroma ratio " << median);
        CHECK(median > last);
        last = median;
    }
}

TEST_CASE("a step edge develops the adjacency effect of the inhibitor's Gaussian spread", "[couplers]") {
    // Neutral exposure stepping from 0.01 to 0.3 lux s at x = 120 on 2.5 um pixels. The donors'
    // net densities n_j step too; their spread at pixel k from the edge is the step through the
    // pixel-integrated Gaussian, n_lo + (n_hi - n_lo) Phi((k + 1/2) / sigma), and each layer
    // develops to D0_i(log H - sum_j M_ij spread_j): denser than the sheet just inside the
    // bright side, lighter just outside it (the edge effect), over a width that follows sigma.
    const Stock film = find_stock("kodak-vision3-250d");
    const DirCouplerSpec spec = stock_dir_couplers(film);
    std::array<const Curve*, 3> sheet;
    for (size_t l = 0; l < 3; ++l) sheet[l] = &film.layers[l].density_curve;
    const std::array<Curve, 3> before = curves_before_inhibition(sheet, spec.matrix, {"R", "G", "B"});
    const double pitch_um = 2.5, h_lo = 0.01, h_hi = 0.3;
    const int width = 240, edge = 120;
    std::vector<float> h = std::vector<float>(size_t(width), float(h_lo));
    for (int x = edge; x < width; ++x) h[size_t(x)] = float(h_hi);
    double half_width[2];
    for (int spread_index = 0; spread_index < 2; ++spread_index) {
        DevelopSettings s;
        s.quality = Quality::reference;
        s.dir_coupler_spread = 1 + spread_index;
        const double sigma_px = spec.diffusion_um * s.dir_coupler_spread / pitch_um;
        const Image d = develop_neutral_row(film, h, pitch_um, s);
        double peak = 0;
        std::vector<double> overshoot;  // layer G, the bright side
        for (int x = 0; x < width; ++x) {
            const double phi = 0.5 * std::erfc(-(x - edge + 0.5) / (sigma_px * std::sqrt(2.0)));
            const double log_h = std::log10(double(h[size_t(x)]));
            for (size_t i = 0; i < 3; ++i) {
                double shift = 0;
                for (size_t j = 0; j < 3; ++j) {
                    const double n_lo = (*sheet[j])(std::log10(h_lo)) - sheet[j]->y_min();
                    const double n_hi = (*sheet[j])(std::log10(h_hi)) - sheet[j]->y_min();
                    shift += spec.matrix[i][j] * (n_lo + (n_hi - n_lo) * phi);
                }
                INFO("spread " << s.dir_coupler_spread << " x " << x << " layer " << i);
                REQUIRE(d.at(x, 1)[i] == Approx(before[i](log_h - shift)).margin(2e-4));
            }
            if (x >= edge) {
                overshoot.push_back(d.at(x, 1)[1] - (*sheet[1])(std::log10(h_hi)));
                peak = std::max(peak, overshoot.back());
            }
            if (x < edge) CHECK(d.at(x, 1)[1] <= (*sheet[1])(std::log10(h_lo)) + 1e-6);  // (lighter beside the edge)
        }
        CHECK(peak > 0.05);
        // The distance from the edge at which the overshoot falls to half its peak.
        half_width[spread_index] = double(std::find_if(overshoot.begin(), overshoot.end(),
                                                       [&](double o) { return o < peak / 2; }) - overshoot.begin());
        CHECK(std::abs(d.at(width - 1, 1)[1] - (*sheet[1])(std::log10(h_hi))) < 1e-4);  // far off, the sheet
    }
    CHECK(half_width[1] / half_width[0] == Approx(2.0).epsilon(0.15));
}

TEST_CASE("the fast tiers' coarse inhibitor spreads a step within its grid's bound of the exact Gaussian",
          "[couplers][quality]") {
    // The fast tier's design at a 4K frame's pitch (6.08 um): the 15 um inhibitor (sigma 2.47 px)
    // on a grid of 2, twice as wide on a grid of 4. The exact spread of a unit step is
    // f(x) = Phi(x / sigma); linear interpolation between nodes d apart is within
    // d^2/8 max|f''| = d^2 phi(1) / (8 sigma^2) = 0.030 (d / sigma)^2 of it, and the block means
    // and the narrowed Gaussian keep the exact one's variance, adding less than that. A step at
    // every place within a block, across x and across y, on one plane.
    const Stock film = find_stock("kodak-vision3-250d");
    const double pitch_um = 6.08;
    for (double spread : {1.0, 2.0}) {
        const CouplerStage fast = design_couplers(film, 1, spread, pitch_um, 6, 8);
        const double sigma_px = stock_dir_couplers(film).diffusion_um * spread / pitch_um;
        const int d = fast.spread.decimation;
        REQUIRE(d == int(sigma_px));
        const double bound = std::exp(-0.5) / std::sqrt(2 * M_PI) * d * d / (8 * sigma_px * sigma_px);
        const std::vector<float> exact_taps = pixel_integrated_gaussian(sigma_px);
        const Window frame{0, 0, 96, 96};
        double worst = 0;
        for (int across_y = 0; across_y < 2; ++across_y)
            for (int edge = 48; edge < 48 + d; ++edge) {
                Plane step = Plane::unset(frame), exact = Plane::unset(frame);
                for (int y = 0; y < frame.y1; ++y)
                    for (int x = 0; x < frame.x1; ++x) step.at(x, y) = (across_y ? y : x) >= edge ? 1.0f : 0.0f;
                convolve_separable(step, exact, exact_taps, frame, 1);
                CoarseGaussianStream coarse({&fast.spread.taps}, d, frame, frame,
                                            [&](int y, int x_begin, int x_end, float* const* rows) {
                                                std::copy(step.row(y) + x_begin, step.row(y) + x_end, rows[0]);
                                            });
                for (int y = 0; y < frame.y1; ++y) {
                    const CoarseGaussianStream::Row& r = coarse.row(y);
                    for (int x = 0; x < frame.x1; ++x) {
                        const double spread_value = r.above[0][x] + r.t * (r.below[0][x] - r.above[0][x]);
                        worst = std::max(worst, std::abs(spread_value - exact.at(x, y)));
                    }
                }
            }
        INFO("spread " << spread << ": sigma " << sigma_px << " px, grid " << d << ", bound " << bound);
        CHECK(worst <= bound);
        CHECK(worst > bound / 4);  // (the grid is coarse: the bound is not loose by orders)
    }
}

TEST_CASE("DIR couplers give the same pixels for any thread count and window", "[couplers][determinism]") {
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Image scene = demo_scene(160, 120);
    // ~3 um pixels: the inhibitor reaches 20 px, on a grid of 5 in the fast tiers; a 4K
    // frame's 6.08 um: on a grid of 2 (its vector loops).
    for (auto [q, frame_width_mm] : {std::pair{Quality::high, 0.5}, std::pair{Quality::fast, 0.5},
                                     std::pair{Quality::preview, 0.5}, std::pair{Quality::fast, 160 * 0.00608}}) {
        DevelopSettings s;
        s.quality = q;
        s.seed = 3;
        s.frame_width_mm = frame_width_mm;
        s.print_width_mm = 5;
        INFO(quality_name(q) << ", frame width " << frame_width_mm << " mm");
        for (OutputMode mode : {OutputMode::print, OutputMode::density}) {
            s.output = mode;
            const Image one = render(film, &paper, s, scene, 1);
            REQUIRE(render(film, &paper, s, scene, 5).pixels == one.pixels);
            for (Window w : {Window{0, 0, 37, 29}, Window{50, 41, 160, 120}, Window{77, 3, 78, 4}}) {
                const Image part = render(film, &paper, s, scene, 2, w);
                for (int y = w.y0; y < w.y1; ++y)
                    for (int x = w.x0; x < w.x1; ++x)
                        for (int c = 0; c < 3; ++c) REQUIRE(part.at(x, y)[c] == one.at(x, y)[c]);
            }
        }
    }
}

TEST_CASE("stock files give a colour negative's DIR couplers, and refuse them elsewhere", "[couplers][stock]") {
    const std::string couplers =
        R"("dir_couplers": {"matrix": [[0.4, 0.1, 0.1], [0.2, 0.3, 0.1], [0.1, 0.2, 0.25]], "diffusion_um": 8},)";
    const std::string film_json = test::replaced(test::test_colour_film_json(), R"("layers": [)", couplers + R"("layers": [)");
    const Stock film = parse_stock_json(film_json, "film.json");
    REQUIRE(film.dir_couplers);
    CHECK(stock_dir_couplers(film).matrix[1][0] == 0.2);
    CHECK(stock_dir_couplers(film).diffusion_um == 8);
    CHECK(parse_stock_json(stock_to_json(film), "again").dir_couplers == film.dir_couplers);
    // Without the field, a colour negative has the default; other stocks none.
    CHECK(stock_dir_couplers(test::test_colour_film()) == default_dir_couplers());
    CHECK(stock_dir_couplers(test::test_film()) == DirCouplerSpec{});
    CHECK(stock_dir_couplers(test::test_colour_paper()) == DirCouplerSpec{});

    const std::string paper_json =
        test::replaced(test::test_colour_paper_json(), R"("layers": [)", couplers + R"("layers": [)");
    CHECK_THROWS_WITH(parse_stock_json(paper_json, "paper.json"),
                      Catch::Contains("paper.json") && Catch::Contains("dir_couplers") &&
                          Catch::Contains("only colour negatives"));
    CHECK_THROWS_WITH(parse_stock_json(test::replaced(film_json, ", [0.1, 0.2, 0.25]]", "]"), "film.json"),
                      Catch::Contains("dir_couplers.matrix") && Catch::Contains("3 rows"));
    CHECK_THROWS_WITH(parse_stock_json(test::replaced(film_json, "0.25]]", "-0.25]]"), "film.json"),
                      Catch::Contains("dir_couplers.matrix[2][2]"));

    // Inhibition steeper than the curves it inverts has no curve before it: refused by name.
    DevelopSettings s;
    s.output = OutputMode::density;
    s.dir_couplers = 3;
    Stock strong = film;
    for (auto& row : strong.dir_couplers->matrix) row = {1.0, 1.0, 1.0};
    CHECK_THROWS_WITH(Plan::compile(strong, nullptr, s, {8, 8}),
                      Catch::Contains("DIR couplers") && Catch::Contains("lower the dir-couplers amount"));
    s.dir_couplers = -1;
    CHECK_THROWS_WITH(Plan::compile(film, nullptr, s, {8, 8}), Catch::Contains("DIR couplers must be 0-3"));
}
