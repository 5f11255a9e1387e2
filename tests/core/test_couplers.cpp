// DIR couplers in colour development (core/stages/couplers.h, docs/model/dir-couplers.md).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/demo_scene.h"
#include "core/develop.h"
#include "core/spectral.h"
#include "core/stages/couplers.h"
#include "core/simd.h"
#include "core/stages/coarse_gaussian.h"
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

// The coarse Gaussian's mass beyond its taps' pixels (both sides), which its taps, truncated
// and renormalised, leave out: they differ from the whole Gaussian by that much (half the sum
// of their differences), so a field whose values span `range` along one direction moves by at
// most range times it (along two directions, twice that).
double coarse_tail(const CouplerStage& c) {
    return std::erfc((double(c.spread.taps.size() / 2) + 0.5) / (c.spread.coarse_sigma * std::sqrt(2.0)));
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
    // on a grid of 3, twice as wide on a grid of 6. The exact spread of a unit step is
    // f(x) = Phi(x / sigma); linear interpolation between nodes d apart is within
    // d^2/8 max|f''| = d^2 phi(1) / (8 sigma^2) = 0.030 (d / sigma)^2 of it, and the coarse
    // Gaussian's width is the one that brings a step closest, adding less than that; the coarse
    // taps' truncation (they reach 3 of its sigmas) adds at most their tail. A step at every
    // place within a block, across x and across y, on one plane.
    const Stock film = find_stock("kodak-vision3-250d");
    const double pitch_um = 6.08;
    for (double spread : {1.0, 2.0}) {
        const CouplerStage fast = design_couplers(film, 1, spread, pitch_um, 6, 8);
        const double sigma_px = stock_dir_couplers(film).diffusion_um * spread / pitch_um;
        const int d = fast.spread.decimation;
        REQUIRE(d == int(kCouplerGridPerSigma * sigma_px));
        const double bound = std::exp(-0.5) / std::sqrt(2 * M_PI) * d * d / (8 * sigma_px * sigma_px) +
                             coarse_tail(fast);
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

TEST_CASE("a coarse Gaussian's interpolation and block means are their scalar definitions on every grid and "
          "instruction set", "[couplers][simd]") {
    test::IsaScope scope;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.01f, 1.0f);
    // Grids of 2 to 8 run vector kernels, 9 the scalar loops; a window from an odd column, so
    // that its first and last blocks are partial, wide enough for several vectors and a tail.
    for (int d = 2; d <= 9; ++d) {
        const Window frame{0, 0, 16 * 9 * 3 + 13, 4 * d + 40}, out{5, 0, frame.x1 - 3, frame.y1};
        const std::vector<float> taps = design_coarse_gaussian(1.2 * d, d).taps;
        const int reach = (int(taps.size() / 2) + 3) * d;  // past it from the frame's edges, no clamping
        Plane fine = Plane::unset(frame), ramp = Plane::unset(frame);
        for (int y = 0; y < frame.y1; ++y)
            for (int x = 0; x < frame.x1; ++x) {
                fine.at(x, y) = u(rng);
                ramp.at(x, y) = 1.0f + 0.01f * float(x) + 0.02f * float(y);
            }
        // The blocks' column of out's first column, as the stream counts them.
        const int first_block = floor_div(2 * out.x0 + 1 - d, 2 * d);
        std::vector<std::vector<float>> products;
        for (simd::Isa isa : test::runnable_isas()) {
            simd::set_isa(isa);
            CoarseGaussianStream random({&taps}, d, out, frame, [&](int y, int x_begin, int x_end, float* const* rows) {
                std::copy(fine.row(y) + x_begin, fine.row(y) + x_end, rows[0]);
            });
            CoarseGaussianStream linear({&taps}, d, out, frame, [&](int y, int x_begin, int x_end, float* const* rows) {
                std::copy(ramp.row(y) + x_begin, ramp.row(y) + x_end, rows[0]);
            });
            std::vector<float> product(size_t(out.width())), all;
            long long differ = 0;
            double worst_ramp = 0;
            for (int y = out.y0; y < out.y1; ++y) {
                const CoarseGaussianStream::Row& r = random.coarse_row(y);
                random.multiply_by_interpolated(r.above[0], r.below[0], r.t, fine.row(y) + out.x0, product.data());
                for (int x = out.x0; x < out.x1; ++x) {
                    // The definition: along y on the coarse nodes either side, along x, times the pixel.
                    const int i = floor_div(2 * x + 1 - d, 2 * d), k = i - first_block;
                    const float tx = float(2 * x + 1 - d - 2 * d * i) / float(2 * d);
                    const float c0 = r.above[0][k] + r.t * (r.below[0][k] - r.above[0][k]);
                    const float c1 = r.above[0][k + 1] + r.t * (r.below[0][k + 1] - r.above[0][k + 1]);
                    if (product[size_t(x - out.x0)] != fine.at(x, y) * (c0 + tx * (c1 - c0))) ++differ;
                }
                all.insert(all.end(), product.begin(), product.end());
                // A linear ramp is its own block means, blur and interpolation, away from the edges.
                const CoarseGaussianStream::Row& s = linear.row(y);
                if (y < reach || y >= frame.y1 - reach) continue;
                for (int x = std::max(out.x0, reach); x < std::min(out.x1, frame.x1 - reach); ++x) {
                    const double value = s.above[0][x - out.x0] + s.t * (s.below[0][x - out.x0] - s.above[0][x - out.x0]);
                    worst_ramp = std::max(worst_ramp, std::abs(value / ramp.at(x, y) - 1));
                }
            }
            INFO("grid " << d << ", " << simd::isa_name(isa));
            CHECK(differ == 0);
            CHECK(worst_ramp < 1e-5);
            products.push_back(std::move(all));
        }
        for (size_t i = 1; i < products.size(); ++i) CHECK(products[i] == products[0]);
    }
}

TEST_CASE("DIR couplers give the same pixels for any thread count and window", "[couplers][determinism]") {
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Image scene = demo_scene(160, 120);
    // ~3 um pixels: the inhibitor on a coarse grid twice as coarse as at a 4K frame's 6.08 um
    // (3).
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

namespace {

// Each layer's inhibited exposure of three exposure planes on `frame`, by the stage's per-pixel
// path (the donors at every pixel, the spread on the pixels, 2^ at every pixel) or, where its
// spread is coarse, by CoarseCouplerStream.
std::array<Plane, 3> inhibited(const CouplerStage& c, const std::array<Plane, 3>& exposure, const Window& frame) {
    std::array<Plane, 3> out{Plane::unset(frame), Plane::unset(frame), Plane::unset(frame)};
    if (c.spread.decimation > 1) {
        CoarseCouplerStream stream(c, frame, frame, [&](int y, int x_begin, int x_end, float* const* rows) {
            for (size_t l = 0; l < 3; ++l) std::copy(exposure[l].row(y) + x_begin, exposure[l].row(y) + x_end, rows[l]);
        });
        for (int y = frame.y0; y < frame.y1; ++y) {
            float* const* rows = stream.row(y);
            for (size_t l = 0; l < 3; ++l) std::copy_n(rows[l], frame.width(), out[l].row(y));
        }
        return out;
    }
    std::array<Plane, 3> spread{Plane::unset(frame), Plane::unset(frame), Plane::unset(frame)};
    for (size_t l = 0; l < 3; ++l) {
        Plane donor = Plane::unset(frame);
        for (int y = frame.y0; y < frame.y1; ++y)
            coupler_donor_row(c, l, exposure[l].row(y), donor.row(y), frame.width());
        convolve_separable(donor, spread[l], c.spread.taps, frame, 1);
        out[l] = exposure[l];
    }
    for (int y = frame.y0; y < frame.y1; ++y) {
        float* rows[3] = {out[0].row(y), out[1].row(y), out[2].row(y)};
        const float* spread_rows[3] = {spread[0].row(y), spread[1].row(y), spread[2].row(y)};
        inhibit_rows(c, rows, spread_rows, frame.width());
    }
    return out;
}

// The largest |log10| of the coarse inhibited exposure over the per-pixel one, per layer.
std::array<double, 3> worst_log_ratio(const std::array<Plane, 3>& coarse, const std::array<Plane, 3>& exact) {
    std::array<double, 3> worst{};
    for (size_t l = 0; l < 3; ++l)
        for (size_t k = 0; k < exact[l].pixels.size(); ++k)
            worst[l] = std::max(worst[l], std::abs(std::log10(double(coarse[l].pixels[k]) / exact[l].pixels[k])));
    return worst;
}

}  // namespace

TEST_CASE("the fast tiers' coarse inhibition stays within its bound of the per-pixel one", "[couplers][quality]") {
    // The fast tier at a 4K frame's pitch (6.08 um: sigma 2.47 px, a grid of d = 3) against the
    // per-pixel path with the same tables, as the log10 of the inhibited exposures' ratio. The
    // coarse path differs from it in three ways, each bounded (log10 H, receiver i, donors j):
    //  1. the spread of the blocks' mean net densities on the coarse grid, interpolated: within
    //     phi(1) d^2 / (8 sigma^2) of the exact spread of a unit step, and the truncated coarse
    //     taps within their tail (the test above), so sum_j |M_ij| dn_j times that for a step of
    //     net densities dn_j;
    //  2. a block's donor is its curve at the block's geometric mean exposure (by the floats'
    //     bits: the mean log10 H within 0.0259, docs/model/dir-couplers.md), not its mean net
    //     density: they differ by the curve's departure from its chord, delta_j, only in the
    //     blocks a step crosses, each weighing at most the largest coarse tap w in any pixel
    //     (the interpolation is a convex combination of nodes, each taking a column of blocks
    //     by one tap): sum_j |M_ij| delta_j w;
    //  3. the factors 10^-s interpolated between nodes, not s: by Hoeffding's lemma the log of
    //     a linear interpolation of e^a exceeds the interpolated a by at most D^2/8, D the
    //     nodes' difference in a; adjacent nodes of a step's spread differ by at most w dn_j,
    //     so D <= ln 10 w sum_j |M_ij| dn_j, and the error is at most D^2 / (8 ln 10).
    // A smooth field: the same three with (1) the exact shift's curvature in place of the
    // step's, and the tail twice (both directions) of each donor's range, (2) every block's departure of its curve at its mean log exposure from its mean
    // net density, with the pseudo logarithm's 0.0259 at the curve's steepest slope (every
    // block: weights summing to 1), and (3) the nodes' differences at most d times the exact
    // shift's largest gradient, in both directions.
    const Stock film = find_stock("kodak-vision3-250d");
    const double pitch_um = 6.08;
    const CouplerStage coarse = design_couplers(film, 1, 1, pitch_um, 6, 8);
    const CouplerStage exact = design_couplers(film, 1, 1, pitch_um, 6, 1);
    const int d = coarse.spread.decimation;
    REQUIRE(d == 3);
    REQUIRE(exact.spread.decimation == 1);
    const CouplerMatrix m = stock_dir_couplers(film).matrix;
    const double sigma_px = stock_dir_couplers(film).diffusion_um / pitch_um;
    const double ln10 = std::log(10.0), pseudo_log10 = 0.0861 * std::log10(2.0);
    const Window frame{0, 0, 96, 96};
    auto net = [&](size_t j, double log_h) { return film.layers[j].density_curve(log_h) - exact.d_min[j]; };
    double w = 0;
    for (float t : coarse.spread.taps) w = std::max(w, double(t));

    SECTION("a step edge") {
        const double log_lo = -2, log_hi = -0.5;  // 1.5 decades, at every place within a block, across x and y
        std::array<double, 3> dn, delta{};
        for (size_t j = 0; j < 3; ++j) {
            dn[j] = net(j, log_hi) - net(j, log_lo);
            for (int k = 1; k < d; ++k) {  // the step's share of a block it crosses
                const double f = double(k) / d, chord = (1 - f) * net(j, log_lo) + f * net(j, log_hi);
                for (double g = -pseudo_log10; g <= pseudo_log10; g += pseudo_log10 / 50)
                    delta[j] = std::max(delta[j], std::abs(net(j, (1 - f) * log_lo + f * log_hi + g) - chord));
            }
        }
        const double interpolation =
            std::exp(-0.5) / std::sqrt(2 * M_PI) * d * d / (8 * sigma_px * sigma_px) + coarse_tail(coarse);
        for (int across_y = 0; across_y < 2; ++across_y)
            for (int edge = 48; edge < 48 + d; ++edge) {
                std::array<Plane, 3> h{Plane::unset(frame), Plane::unset(frame), Plane::unset(frame)};
                for (auto& p : h)
                    for (int y = 0; y < frame.y1; ++y)
                        for (int x = 0; x < frame.x1; ++x)
                            p.at(x, y) = float(std::pow(10.0, (across_y ? y : x) >= edge ? log_hi : log_lo));
                const std::array<double, 3> worst =
                    worst_log_ratio(inhibited(coarse, h, frame), inhibited(exact, h, frame));
                for (size_t i = 0; i < 3; ++i) {
                    double step = 0, crossed = 0;
                    for (size_t j = 0; j < 3; ++j) {
                        step += std::abs(m[i][j]) * dn[j];
                        crossed += std::abs(m[i][j]) * delta[j];
                    }
                    const double nodes = ln10 * w * step;
                    const double bound = step * interpolation + crossed * w + nodes * nodes / (8 * ln10) + 1e-5;
                    INFO("edge " << edge << (across_y ? " across y" : " across x") << ", layer " << i << ": "
                                 << worst[i] << " against " << bound << " (" << step * interpolation << " + "
                                 << crossed * w << " + " << nodes * nodes / (8 * ln10) << ")");
                    CHECK(worst[i] <= bound);
                    CHECK(worst[i] > bound / 4);  // (the bound is not loose by orders)
                }
            }
    }

    SECTION("a smooth field") {
        // A colour field: each layer's log10 H a product of sines of wavelength 32 px (13 sigma).
        const double lambda = 32, amplitude = 0.5;
        std::array<Plane, 3> h{Plane::unset(frame), Plane::unset(frame), Plane::unset(frame)};
        std::array<Plane, 3> log_h{Plane::unset(frame), Plane::unset(frame), Plane::unset(frame)};
        for (size_t l = 0; l < 3; ++l)
            for (int y = 0; y < frame.y1; ++y)
                for (int x = 0; x < frame.x1; ++x) {
                    log_h[l].at(x, y) = float(-1.2 + amplitude * std::sin(2 * M_PI * x / lambda + 2.0 * l) *
                                                       std::cos(2 * M_PI * y / lambda + 1.0 * l));
                    h[l].at(x, y) = float(std::pow(10.0, log_h[l].at(x, y)));
                }
        const std::array<Plane, 3> exact_h = inhibited(exact, h, frame);
        const std::array<double, 3> worst = worst_log_ratio(inhibited(coarse, h, frame), exact_h);
        // Per donor: its curve's largest slope, and the largest departure of a block's curve at
        // its mean log exposure from its mean net density.
        std::array<double, 3> slope{}, departure{}, range{};
        for (size_t j = 0; j < 3; ++j) {
            const Curve& curve = film.layers[j].density_curve;
            const auto [lo, hi] = std::minmax_element(log_h[j].pixels.begin(), log_h[j].pixels.end());
            range[j] = net(j, *hi) - net(j, *lo);  // (the curve rises)
            for (size_t k = 1; k < curve.x.size(); ++k)
                slope[j] = std::max(slope[j], (curve.y[k] - curve.y[k - 1]) / (curve.x[k] - curve.x[k - 1]));
            for (int by = 0; by < frame.y1 / d; ++by)
                for (int bx = 0; bx < frame.x1 / d; ++bx) {
                    double mean_log = 0, mean_net = 0;
                    for (int y = by * d; y < by * d + d; ++y)
                        for (int x = bx * d; x < bx * d + d; ++x)
                            mean_log += log_h[j].at(x, y) / (d * d), mean_net += net(j, log_h[j].at(x, y)) / (d * d);
                    departure[j] = std::max(departure[j], std::abs(net(j, mean_log) - mean_net));
                }
        }
        for (size_t i = 0; i < 3; ++i) {
            // The exact shift s_i = log10 H - log10 H_inhibited, its largest second derivatives and
            // gradient inside the frame (central differences).
            auto s_at = [&](int x, int y) {
                return double(log_h[i].at(x, y)) - std::log10(double(exact_h[i].at(x, y)));
            };
            double curvature = 0, gradient = 0;
            for (int y = 1; y + 1 < frame.y1; ++y)
                for (int x = 1; x + 1 < frame.x1; ++x) {
                    const double c = s_at(x, y);
                    curvature = std::max(curvature, std::abs(s_at(x - 1, y) - 2 * c + s_at(x + 1, y)) +
                                                        std::abs(s_at(x, y - 1) - 2 * c + s_at(x, y + 1)));
                    gradient = std::max(gradient, std::max(std::abs(s_at(x + 1, y) - s_at(x - 1, y)),
                                                           std::abs(s_at(x, y + 1) - s_at(x, y - 1))) / 2);
                }
            double donors = 0;
            for (size_t j = 0; j < 3; ++j) donors += std::abs(m[i][j]) * (departure[j] + slope[j] * pseudo_log10);
            // The coarse spread: its nodes' kernel (blocks and the narrowed Gaussian) is d^2/6
            // narrower in variance than the Gaussian, a shift of d^2/12 of the second derivative a
            // direction, which the interpolation (within d^2/8 of it) makes up on average.
            double truncated = 0;
            for (size_t j = 0; j < 3; ++j) truncated += std::abs(m[i][j]) * range[j] * 2 * coarse_tail(coarse);
            const double spread = (1.0 / 12 + 1.0 / 8) * d * d * curvature + truncated;
            const double nodes = ln10 * d * gradient;
            const double bound = spread + donors + 2 * nodes * nodes / (8 * ln10);
            INFO("layer " << i << ": " << worst[i] << " against " << bound << " (" << spread << " + " << donors << " + "
                          << 2 * nodes * nodes / (8 * ln10) << ")");
            CHECK(worst[i] <= bound);
        }
    }
}
