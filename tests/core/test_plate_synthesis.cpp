// Grain synthesis from a profile: the statistics it promises, and determinism.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>

#include "core/plate/grain_synthesis.h"
#include "tests/core/plate_test_support.h"

using namespace darkroom;
using namespace darkroom::test;

namespace {

// Grain of channel c on a flat image: pixel minus the flat level.
struct FlatGrain {
    Image image;
    double level;
    double covariance(int a, int b, int dx, int dy) const {
        double sum = 0;
        long long n = 0;
        const Window& w = image.window;
        for (int y = w.y0; y < w.y1 - std::abs(dy); ++y)
            for (int x = w.x0 + std::max(0, -dx); x < w.x1 - std::max(0, dx); ++x) {
                sum += (image.at(x, y)[a] - level) * (image.at(x + dx, y + dy)[b] - level);
                ++n;
            }
        return sum / n;
    }
};

FlatGrain flat_grain(const GrainProfile& p, double level, uint64_t seed = 7, int frame = 3) {
    FlatGrain g{Image(384, 384, (int)p.channels.size(), float(level)), level};
    apply_grain_profile(p, g.image.view(), seed, frame, 2);
    return g;
}

}  // namespace

TEST_CASE("synthesised grain has the profile's sigma, autocorrelation and channel correlation",
          "[plate][synthesis]") {
    // Different grain sizes per channel: the mixing must still give the asked correlation.
    GrainProfile p = known_profile({{0.01, 0.02, 1.0, 1.2}, {0.02, -0.01, 1.0, 0.6}, {0.015, 0.0, 1.0, 2.0}},
                                   {1, 0.6, -0.3, 0.6, 1, 0.2, -0.3, 0.2, 1}, SignalEncoding::log, 0.0, 1.0);
    const double level = 0.5;
    FlatGrain g = flat_grain(p, level);
    for (int c = 0; c < 3; ++c) {
        double sigma = p.channels[c].sigma_at(level);
        CHECK(std::sqrt(g.covariance(c, c, 0, 0)) == Approx(sigma).epsilon(0.04));
        for (auto [dx, dy] : {std::pair{1, 0}, {0, 1}, {2, 1}})
            CHECK(g.covariance(c, c, dx, dy) / g.covariance(c, c, 0, 0) == Approx(p.channels[c].acf(dx, dy)).margin(0.03));
    }
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b)
            CHECK(g.covariance(a, b, 0, 0) / std::sqrt(g.covariance(a, a, 0, 0) * g.covariance(b, b, 0, 0)) ==
                  Approx(p.correlation(a, b)).margin(0.03));
}

TEST_CASE("the grain's amount follows the response curve at each pixel's level", "[plate][synthesis]") {
    GrainProfile p = known_profile({{0.002, 0.03, 1.0, 0.0}}, {1}, SignalEncoding::linear, 0.0, 1.0);
    for (double level : {0.1, 0.8}) {
        FlatGrain g = flat_grain(p, level);
        CHECK(std::sqrt(g.covariance(0, 0, 0, 0)) == Approx(0.002 + 0.03 * level).epsilon(0.03));
    }
}

// The per-pixel lookup of a response curve is its linear interpolation exactly (the same
// segment, so the same arithmetic), on unevenly spaced levels (an analysis drops bins), at
// and between every level, across each lookup cell's start, and beyond both ends.
TEST_CASE("the response lookup gives the curve's sigma bit for bit", "[plate][synthesis]") {
    GrainChannel uneven, even;  // (even: levels where the lookup's cells start, as a prediction's)
    uneven.level = {-0.3, -0.29, 0.0, 0.001, 0.4, 0.41, 0.95, 2.0};
    uneven.sigma = {0.01, 0.012, 0.02, 0.019, 0.03, 0.031, 0.05, 0.04};
    for (int k = 0; k < 25; ++k) {
        even.level.push_back(0.0928641 + k * (1.0 - 0.0928641) / 24);
        even.sigma.push_back(0.02 * std::sqrt(k + 1.0));
    }
    for (const GrainChannel& ch : {uneven, even}) {
        const ResponseLookup lookup(ch);
        std::vector<double> xs{-1e30, -1.0, 1.0, 3.0, 1e30};
        for (double l : ch.level)
            for (double x : {l, std::nextafter(l, -1e9), std::nextafter(l, 1e9)}) xs.push_back(x);
        for (int k = 0; k <= 20000; ++k) xs.push_back(-0.4 + 2.6 * k / 20000.0);
        long differing = 0;
        for (double x : xs) differing += lookup.sigma_at(x) != ch.sigma_at(x);
        CHECK(differing == 0);
    }
    GrainChannel one;  // a single level: its sigma everywhere
    one.level = {0.5};
    one.sigma = {0.02};
    CHECK(ResponseLookup(one).sigma_at(-3.0) == 0.02);
    CHECK(ResponseLookup(one).sigma_at(7.0) == 0.02);
}

TEST_CASE("synthesised grain is a function of seed, frame and absolute pixel only", "[plate][synthesis][determinism]") {
    GrainProfile p = known_profile({{0.01, 0.0, 1.0, 1.5}, {0.01, 0.0, 1.0, 0.5}, {0.01, 0.0, 1.0, 0.0}},
                                   {1, 0.5, 0.2, 0.5, 1, 0.3, 0.2, 0.3, 1}, SignalEncoding::log, 0.0, 1.0);
    Image full(200, 150, 4, 0.4f);  // the fourth channel (alpha) must be left alone
    apply_grain_profile(p, full.view(), 11, 1001, 1);
    Image part(Window{37, 21, 37 + 90, 21 + 64}, 4, 0.4f);
    apply_grain_profile(p, part.view(), 11, 1001, 3);
    for (int y = part.window.y0; y < part.window.y1; ++y)
        for (int x = part.window.x0; x < part.window.x1; ++x)
            for (int c = 0; c < 4; ++c) REQUIRE(part.at(x, y)[c] == full.at(x, y)[c]);
    CHECK(full.at(5, 5)[3] == 0.4f);

    Image other_frame(200, 150, 4, 0.4f), other_seed(200, 150, 4, 0.4f), again(200, 150, 4, 0.4f);
    apply_grain_profile(p, other_frame.view(), 11, 1002, 2);
    apply_grain_profile(p, other_seed.view(), 12, 1001, 2);
    apply_grain_profile(p, again.view(), 11, 1001, 2);
    CHECK(again.pixels == full.pixels);
    CHECK(other_frame.pixels != full.pixels);
    CHECK(other_seed.pixels != full.pixels);
}

TEST_CASE("synthesis leaves non-finite pixels alone and refuses a profile of other channels",
          "[plate][synthesis][bad-input]") {
    GrainProfile p = known_profile({{0.01, 0.0, 1.0, 0.0}}, {1}, SignalEncoding::linear, 0.0, 1.0);
    Image img(8, 8, 1, 0.5f);
    img.at(3, 3)[0] = NAN;
    apply_grain_profile(p, img.view(), 1, 0, 1);
    CHECK(std::isnan(img.at(3, 3)[0]));
    CHECK(img.at(4, 3)[0] != 0.5f);
    GrainProfile rgb = known_profile({{0.01, 0, 1, 0}, {0.01, 0, 1, 0}, {0.01, 0, 1, 0}}, {1, 0, 0, 0, 1, 0, 0, 0, 1},
                                     SignalEncoding::linear, 0.0, 1.0);
    CHECK_THROWS_AS(apply_grain_profile(rgb, img.view(), 1, 0, 1), std::invalid_argument);
    // Grey with alpha and depth (Y, A, Z): one colour channel, whatever the count.
    Image grey_alpha_depth(8, 8, 3, 0.5f);
    ImageView view = grey_alpha_depth.view();
    view.colour_channels = 1;
    CHECK_THROWS_AS(apply_grain_profile(rgb, view, 1, 0, 1), std::invalid_argument);
    GrainProfile two = known_profile({{0.01, 0, 1, 0}, {0.01, 0, 1, 0}}, {1, 0, 0, 1}, SignalEncoding::linear, 0.0, 1.0);
    Image colour(8, 8, 3, 0.5f);
    CHECK_THROWS_AS(apply_grain_profile(two, colour.view(), 1, 0, 1), std::invalid_argument);
}

// A black-and-white plate's grain on a colour element (a CG render comped into a black-and-
// white plate, or the program's RGB print): the one field on each colour channel, at each
// channel's level; the channels past the colour untouched.
TEST_CASE("a grey profile grains every colour channel with its one field", "[plate][synthesis]") {
    GrainProfile grey = known_profile({{0.01, 0.02, 1.0, 0.5}}, {1}, SignalEncoding::linear, 0.0, 1.0);
    Image one(48, 40, 1, 0.3f);
    apply_grain_profile(grey, one.view(), 9, 2, 2);
    Image rgba(48, 40, 4, 0.3f);
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 48; ++x) rgba.at(x, y)[2] = 0.6f;  // blue at another level
    apply_grain_profile(grey, rgba.view(), 9, 2, 2);
    Image grey_alpha_depth(48, 40, 3, 0.3f);
    ImageView view = grey_alpha_depth.view();
    view.colour_channels = 1;
    apply_grain_profile(grey, view, 9, 2, 2);
    const GrainChannel& ch = grey.channels[0];
    int differing_sigma = 0;
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 48; ++x) {
            const float* px = rgba.at(x, y);
            REQUIRE(px[0] == one.at(x, y)[0]);  // red and green: the grey image's pixel, bit for bit
            REQUIRE(px[1] == one.at(x, y)[0]);
            CHECK(px[3] == 0.3f);  // alpha untouched
            // Blue: the same unit field, at its own level's sigma.
            const double field = (one.at(x, y)[0] - 0.3) / ch.sigma_at(0.3);
            CHECK(px[2] - 0.6 == Approx(ch.sigma_at(0.6) * field).margin(1e-6));
            differing_sigma += px[2] - 0.6f != px[0] - 0.3f;
            REQUIRE(grey_alpha_depth.at(x, y)[0] == one.at(x, y)[0]);
            CHECK(grey_alpha_depth.at(x, y)[1] == 0.3f);
            CHECK(grey_alpha_depth.at(x, y)[2] == 0.3f);
        }
    CHECK(differing_sigma > 1000);
}

// The separable synthesis against its definition: the profile's white noise (Philox at each
// absolute pixel, mixed by the Cholesky factor) through each channel's exact 2D kernel, summed
// directly in double. Grain that is correlated along a diagonal (not separable in x and y)
// needs several terms; the fields then differ by at most the energy they leave out.
TEST_CASE("synthesised grain is the exact 2D convolution of its white noise, within the terms' residual",
          "[plate][synthesis]") {
    GrainProfile p = known_profile({{0.02, 0.0, 1.0, 0.0}, {0.01, 0.02, 1.0, 0.0}, {0.03, 0.0, 1.0, 0.0}},
                                   {1, 0.5, 0.2, 0.5, 1, 0.3, 0.2, 0.3, 1}, SignalEncoding::linear, 0.0, 1.0);
    for (GrainChannel& ch : p.channels) {  // correlated along x = y over 3 px, across it over 0.7 px
        ch.acf_radius = 8;
        ch.autocorrelation.clear();
        for (int dy = -8; dy <= 8; ++dy)
            for (int dx = -8; dx <= 8; ++dx)
                ch.autocorrelation.push_back(std::exp(-(dx + dy) * (dx + dy) / (8.0 * 9.0) - (dx - dy) * (dx - dy) / (8.0 * 0.49)));
    }
    const GrainSynthesisPlan plan = plan_grain_synthesis(p);
    REQUIRE(plan.filters[0].terms.size() > 1);
    const double level = 0.4;
    const Window w{-20, 7, 60, 57};  // (a window off the origin: absolute pixels)
    Image image(w, 3, float(level));
    apply_grain_profile(plan, image.view(), 5, 9, 2);
    const int n = 3, halo = plan.halo_px;
    const Window noise_window = w.grown(halo);
    std::vector<Plane> mixed(n, Plane(noise_window));
    for (int y = noise_window.y0; y < noise_window.y1; ++y)
        for (int x = noise_window.x0; x < noise_window.x1; ++x) {
            double white[3];
            for (int c = 0; c < n; ++c) plate_grain_white_noise(5, 9, c, x, 1, y, &white[c]);  // (pixel by pixel)
            for (int c = 0; c < n; ++c) {
                double sum = 0;
                for (int j = 0; j <= c; ++j) sum += plan.mixing[c * n + j] * white[j];
                mixed[c].at(x, y) = float(sum);
            }
        }
    for (int c = 0; c < n; ++c) {
        const GrainKernel& k = plan.kernels[c];
        const double sigma = p.channels[c].sigma_at(level);
        double squares = 0, worst = 0;
        for (int y = w.y0; y < w.y1; ++y)
            for (int x = w.x0; x < w.x1; ++x) {
                double g = 0;
                for (int dy = -k.radius; dy <= k.radius; ++dy)
                    for (int dx = -k.radius; dx <= k.radius; ++dx) g += k.at(dx, dy) * mixed[c].at(x + dx, y + dy);
                const double difference = (image.at(x, y)[c] - (level + sigma * g)) / sigma;
                squares += difference * difference;
                worst = std::max(worst, std::abs(difference));
            }
        const double rms = std::sqrt(squares / (w.width() * w.height()));
        INFO("channel " << c << ": " << plan.filters[c].terms.size() << " terms, rms " << rms << ", worst " << worst);
        CHECK(rms <= 1.5 * std::sqrt(kGrainKernelResidualEnergy));
        CHECK(worst <= 6 * std::sqrt(kGrainKernelResidualEnergy));
    }
}
