// The benchmark's measurements against their definitions (no timing is asserted).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>

#include "bench/bench.h"
#include "core/spectral.h"
#include "core/stock.h"

using namespace darkroom;
using namespace darkroom::bench;

namespace {

Image constant_image(int w, int h, std::array<float, 3> rgb) {
    Image img(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) img.at(x, y)[c] = rgb[c];
    return img;
}

Lab lab_of(const Rgb& rgb) { return xyz_to_lab(linear_srgb_to_xyz(rgb), linear_srgb_to_xyz({1, 1, 1})); }

// A sampled, normalised Gaussian of standard deviation sigma_px applied to a sampled sine.
std::vector<double> blurred_sine(double cycles_per_px, double sigma_px, int n) {
    const int radius = int(std::ceil(8 * sigma_px));
    std::vector<double> taps;
    double sum = 0;
    for (int k = -radius; k <= radius; ++k) sum += taps.emplace_back(std::exp(-0.5 * k * k / (sigma_px * sigma_px)));
    std::vector<double> out(n);
    for (int x = 0; x < n; ++x)
        for (int k = -radius; k <= radius; ++k)
            out[x] += taps[k + radius] / sum * std::sin(2 * M_PI * cycles_per_px * (x - k + 0.5));
    return out;
}

}  // namespace

TEST_CASE("identical images have zero colour and density error") {
    Image a(40, 30, 3);
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x)
            for (int c = 0; c < 3; ++c) a.at(x, y)[c] = float(0.01 + 0.9 * ((x * 7 + y * 13 + c * 5) % 17) / 16.0);
    ColourError e = colour_error(a.view(), a.view());
    CHECK(e.mean == 0.0);
    CHECK(e.max == 0.0);
    CHECK(e.pixels == 40 * 30);
    CHECK(max_abs_difference(a.view(), a.view()) == 0.0);
}

TEST_CASE("a known colour shift gives the CIEDE2000 of the core function") {
    const std::array<float, 3> base{0.18f, 0.12f, 0.05f}, shifted{0.19f, 0.12f, 0.045f};
    Image reference = constant_image(20, 10, base), test = reference;
    // The left half shifted: the mean is half the difference, the max all of it.
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 10; ++x)
            for (int c = 0; c < 3; ++c) test.at(x, y)[c] = shifted[c];
    const double expected = ciede2000(lab_of({base[0], base[1], base[2]}), lab_of({shifted[0], shifted[1], shifted[2]}));
    REQUIRE(expected > 0.5);
    ColourError e = colour_error(test.view(), reference.view());
    CHECK(e.max == Approx(expected).epsilon(1e-12));
    CHECK(e.mean == Approx(expected / 2).epsilon(1e-12));
    CHECK(max_abs_difference(test.view(), reference.view()) == Approx(0.01).margin(1e-7));
}

TEST_CASE("a sub-window is compared with the same pixels of the reference") {
    Image reference = constant_image(32, 32, {0.5f, 0.5f, 0.5f});
    Image window(Window{8, 8, 16, 16}, 3, 0.5f);
    CHECK(colour_error(window.view(), reference.view()).max == 0.0);
    Image outside(Window{28, 28, 36, 36}, 3, 0.5f);
    CHECK_THROWS_AS(colour_error(outside.view(), reference.view()), std::invalid_argument);
}

TEST_CASE("the sine response of a Gaussian blur is its closed-form MTF") {
    const double sigma_px = 2.0;
    for (double f : {1 / 64.0, 4 / 64.0, 8 / 64.0, 12 / 64.0, 16 / 64.0, 32 / 64.0}) {
        std::vector<double> input(1024);
        for (int x = 0; x < 1024; ++x) input[x] = std::sin(2 * M_PI * f * (x + 0.5));
        double measured = sine_amplitude(blurred_sine(f, sigma_px, 1024), f) / sine_amplitude(input, f);
        // Fourier transform of a unit-area Gaussian: exp(-2 pi^2 sigma^2 f^2).
        CHECK(measured == Approx(std::exp(-2 * M_PI * M_PI * sigma_px * sigma_px * f * f)).margin(1e-6));
    }
}

TEST_CASE("the density MTF of a film whose MTF is a Gaussian is that Gaussian") {
    // Every layer's MTF the response of a Gaussian PSF of 2 px at the pitch, sampled to
    // twice the diagonal Nyquist frequency.
    const double pitch_um = 6.0, sigma_mm = 2.0 * pitch_um / 1000.0;
    std::vector<double> cycles_per_mm, response;
    for (int i = 0; i <= 400; ++i) {
        double f = i * 2.0 * std::sqrt(2.0) * 0.5 / (pitch_um / 1000.0) / 400;
        cycles_per_mm.push_back(f);
        response.push_back(std::exp(-2 * M_PI * M_PI * sigma_mm * sigma_mm * f * f));
    }
    Stock film = find_stock("kodak-vision3-250d");
    for (Layer& layer : film.layers) layer.mtf = make_curve(cycles_per_mm, response, "Gaussian MTF");
    const std::vector<double> frequencies{1 / 64.0, 4 / 64.0, 8 / 64.0, 16 / 64.0, 24 / 64.0, 32 / 64.0};
    auto mtf = measure_density_mtf(film, Quality::high, pitch_um, frequencies, 2);
    REQUIRE(mtf.size() == 3);
    for (const auto& layer : mtf)
        for (size_t k = 0; k < frequencies.size(); ++k) {
            double f_px = frequencies[k];
            CHECK(layer[k] == Approx(std::exp(-2 * M_PI * M_PI * 4.0 * f_px * f_px)).margin(0.01));
        }
}

TEST_CASE("the printed grain wedge reads the print's densities, and the fast tier's print grain is high's") {
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const double pitch_um = film.frame_width_mm * 1000.0 / 4096;
    const GrainProfile negative = measure_wedge_grain(film, nullptr, Quality::high, 0, pitch_um, 2);
    // Seen absolute: seen media-relative (the default look), the automatic lights put the
    // wedge's brightest patch's blue layer further into 2383's toe, where the fold cannot carry
    // all of the paper's grain (there fast's blue grain is 24 % under high's, 5.8 % on average
    // over the wedge, against the 5 % tolerance: docs/development/quality-tiers.md).
    const PrintViewing viewing = PrintViewing::absolute;
    const GrainProfile high = measure_wedge_grain(film, &paper, Quality::high, 0, pitch_um, 2, viewing);
    const GrainProfile fast = measure_wedge_grain(film, &paper, Quality::fast, 0, pitch_um, 2, viewing);
    // The print's levels are the print's densities, -log10 of its linear Rec.709: the middle
    // patch, the scene's mid grey, is the grain-free print's of it (neutral at the paper's aim,
    // by PrintExposure's automatic lights), and the print spans more density than the negative
    // (its contrast the paper's gamma times the negative's).
    DevelopSettings s;
    s.quality = Quality::high;
    s.print_viewing = viewing;
    s.grain = false;
    s.mtf = false;
    s.halation = 0;
    s.input_units = InputUnits::lux_seconds;
    s.frame_width_mm = pitch_um * 4 / 1000.0, s.print_width_mm = paper.frame_width_mm * 4 / 4096;
    const Plan plan = Plan::compile(film, &paper, s, {4, 4});
    Image grey(4, 4, 3, float(mid_grey_exposure_lux_s(film.iso_speed))), print(4, 4, 3);
    plan.run(grey.view(), print.view(), 1);
    REQUIRE(high.channels.size() == 3);
    for (int c = 0; c < 3; ++c) {
        const std::vector<double>& level = high.channels[c].level;
        const double grey_density = -std::log10(print.at(1, 1)[c]);
        INFO("channel " << c << ": grey prints at density " << grey_density);
        CHECK(std::any_of(level.begin(), level.end(), [&](double l) { return std::abs(l - grey_density) < 0.01; }));
        const std::vector<double>& negative_level = negative.channels[c].level;
        CHECK(level.back() - level.front() > 1.5 * (negative_level.back() - negative_level.front()));
    }
    // Fast prints through one table with the paper's grain folded into the film's, each
    // channel's variance matched (develop.cpp, fold_paper_grain); high prints each pixel
    // spectrally with the paper's own grain: two paths, the same grain in amplitude and
    // spectrum, and the channels' correlation: the fold's extra grain reaches the print through
    // the negative's dyes, which mix the channels more than the paper's own grain does, so the
    // film layers' grains are correlated to undo it (0.051 from high's with them independent,
    // 0.025 so: docs/development/quality-tiers.md, the print's grain).
    const GrainMatch m = compare_grain_profiles(high, fast);
    const GrainMatchTolerance tolerance;
    CHECK(m.max_correlation_difference <= tolerance.correlation);
    for (const ChannelMatch& c : m.channels) {
        INFO(c.name);
        CHECK(c.response_error_percent <= tolerance.response_percent);
        CHECK(c.nps_distance_db <= tolerance.nps_db);
    }
}

TEST_CASE("the copy pass copies the pixels, and a copy ratio is time over copy time") {
    Image src(37, 23, 3), dst(37, 23, 3);
    for (size_t i = 0; i < src.pixels.size(); ++i) src.pixels[i] = float(i) * 0.25f;
    double s = copy_pass_seconds(src.view(), dst.view(), 3);
    CHECK(s >= 0.0);
    CHECK(dst.pixels == src.pixels);
    CHECK(copy_ratio(0.3, 0.02) == Approx(15.0).epsilon(1e-15));
    CHECK(copy_ratio(0.02, 0.02) == 1.0);
}

TEST_CASE("a tier is Pareto-optimal unless another is at least as fast and as accurate") {
    // (seconds, mean CIEDE2000): a slow exact reference, a dominated tier (slower and worse
    // than the third), a fast one, an equal copy of the fast one (neither dominates).
    std::vector<bool> optimal = pareto_optimal({{100, 0}, {5, 0.4}, {2, 0.3}, {2, 0.3}, {1, 1.0}});
    CHECK(optimal == std::vector<bool>{true, false, true, true, true});
}

TEST_CASE("the reference renders four sample windows along the diagonal, or with whole_frame the frame") {
    BenchOptions o;
    o.width = 1024, o.height = 683;
    const std::vector<Window> windows = reference_windows(o);
    REQUIRE(windows.size() == 4);
    const Window frame{0, 0, 1024, 683};
    for (size_t i = 0; i < windows.size(); ++i) {
        CHECK(windows[i].width() == 128);
        CHECK(windows[i].height() == 128);
        CHECK(windows[i].intersected(frame).pixel_count() == windows[i].pixel_count());
        if (i > 0) CHECK(windows[i].x0 > windows[i - 1].x0);  // down the diagonal
        if (i > 0) CHECK(windows[i].y0 > windows[i - 1].y0);
    }
    o.whole_frame = true;
    const std::vector<Window> whole = reference_windows(o);
    REQUIRE(whole.size() == 1);
    CHECK(whole[0].x0 == 0);
    CHECK(whole[0].y0 == 0);
    CHECK(whole[0].x1 == 1024);
    CHECK(whole[0].y1 == 683);
}
