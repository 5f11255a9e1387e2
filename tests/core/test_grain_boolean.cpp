// The reference tier's Boolean grain (core/stages/grain_boolean.h) against its definition:
// Nutting's mean, the stock's RMS granularity through a 48 um aperture, the filtered-noise
// model's spectrum, window, thread and instruction set independence, its raster against the
// disks it draws, and bad input.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "core/plate/grain_analysis.h"
#include "core/plate/grain_compare.h"
#include "core/stages/grain.h"
#include "core/stages/grain_boolean.h"
#include "tests/core/plate_test_support.h"
#include "tests/core/test_support.h"

using namespace darkroom;

namespace {

constexpr double kDMin = 0.1;

struct MeanAndError {
    double mean, standard_error;
};

// Mean of per-block means (blocks of `block` px, much wider than the footprint, so nearly
// independent) and its standard error.
MeanAndError block_mean(const Plane& p, int block, double (*f)(double)) {
    std::vector<double> means;
    for (int by = p.window.y0; by + block <= p.window.y1; by += block)
        for (int bx = p.window.x0; bx + block <= p.window.x1; bx += block) {
            double sum = 0;
            for (int y = by; y < by + block; ++y)
                for (int x = bx; x < bx + block; ++x) sum += f(p.at(x, y));
            means.push_back(sum / (block * block));
        }
    double mean = 0, var = 0;
    for (double m : means) mean += m / means.size();
    for (double m : means) var += (m - mean) * (m - mean) / (means.size() - 1);
    return {mean, std::sqrt(var / means.size())};
}

double net_transmittance(double density) { return std::pow(10.0, -(density - kDMin)); }

Plane boolean_patch(const GrainSpec& spec, double pitch_um, double net, int side, uint64_t seed = 1) {
    BooleanGrain g = design_boolean_grain(spec, kDMin, pitch_um, NoiseKey{seed, 0, 0});
    Plane d(Window{0, 0, side, side}, float(kDMin + net));
    apply_boolean_grain(d, g, 0);
    return d;
}

// Standard deviation of density read through disjoint circular apertures of 48 um, averaging
// transmittance within each (as core/sensitometry.cpp measures), and the reading count.
std::pair<double, int> aperture_granularity(const Plane& d, double pitch_um) {
    const double radius_px = 0.5 * kGranularityApertureUm / pitch_um;
    const int step = int(std::ceil(2 * radius_px)) + 1, reach = int(radius_px);
    std::vector<double> readings;
    for (int cy = reach; cy + reach < d.window.y1; cy += step)
        for (int cx = reach; cx + reach < d.window.x1; cx += step) {
            double sum = 0;
            int n = 0;
            for (int y = cy - reach; y <= cy + reach; ++y)
                for (int x = cx - reach; x <= cx + reach; ++x)
                    if (std::hypot(x - cx, y - cy) <= radius_px) sum += std::pow(10.0, -d.at(x, y)), ++n;
            readings.push_back(-std::log10(sum / n));
        }
    double mean = 0, var = 0;
    for (double r : readings) mean += r / readings.size();
    for (double r : readings) var += (r - mean) * (r - mean) / (readings.size() - 1);
    return {std::sqrt(var), int(readings.size())};
}

double pixel_std(const Plane& p) {
    double mean = 0, var = 0;
    for (float v : p.pixels) mean += double(v) / p.pixels.size();
    for (float v : p.pixels) var += (v - mean) * (v - mean) / (p.pixels.size() - 1);
    return std::sqrt(var);
}

}  // namespace

TEST_CASE("the Boolean model's noise power integral has its closed-form limits", "[grain][boolean]") {
    // Sparse grains: exp(c g / pi) - 1 -> c g / pi, and the overlap area integrates to pi^2
    // (the product of the disks' areas), so F(c) -> pi c.
    CHECK(boolean_power_integral(1e-6) / 1e-6 == Approx(M_PI).epsilon(1e-4));
    CHECK(boolean_power_integral(0.0) == 0.0);
    // The raster's lattice sum converges to the integral as the spacing shrinks (aliasing
    // falls about as h^3), the more slowly the denser the grains.
    for (double c : {0.5, 2.3, 6.9}) {
        double exact = boolean_power_integral(c);
        double coarse = std::abs(boolean_power_lattice_sum(c, 0.5) / exact - 1);
        double fine = std::abs(boolean_power_lattice_sum(c, 0.125) / exact - 1);
        CHECK(fine < coarse / 20);
        CHECK(fine < 0.01);
    }
}

TEST_CASE("Boolean grain: the mean transmittance of a flat patch is 10^-net", "[grain][boolean]") {
    const GrainSpec spec{0.03, 1.0, 1.0 / 3.0};
    for (double net : {0.3, 1.0, 2.5}) {
        Plane d = boolean_patch(spec, 8.0, net, 128);
        MeanAndError t = block_mean(d, 8, net_transmittance);
        INFO("net " << net << ": mean T " << t.mean << " +- " << t.standard_error);
        CHECK(std::abs(t.mean - std::pow(10.0, -net)) < 4 * t.standard_error);
        CHECK(t.standard_error < 0.02 * std::pow(10.0, -net));  // the check has teeth
    }
    // Beyond the cap the model is rendered at the cap and the rest added without grain.
    Plane d = boolean_patch(spec, 8.0, BooleanGrain::kNetCap + 0.5, 64);
    MeanAndError t = block_mean(d, 8, [](double v) { return std::pow(10.0, -(v - kDMin - 0.5)); });
    CHECK(std::abs(t.mean - std::pow(10.0, -BooleanGrain::kNetCap)) < 4 * t.standard_error);
}

TEST_CASE("Boolean grain: the RMS granularity through a 48 um aperture is the stock's at every density",
          "[grain][boolean]") {
    // Coarse grain keeps the work small; 4 um pixels draw the aperture to within 0.2 % of its area.
    const double pitch_um = 4.0;
    struct Case {
        double exponent, net;
        int side_px;  // the densest case is the slowest: fewer apertures
    };
    for (Case k : {Case{1.0 / 3.0, 0.5, 640}, Case{1.0 / 3.0, 1.5, 640}, Case{0.7, 0.5, 640}, Case{0.7, 1.5, 640},
                   Case{0.7, 2.5, 480}}) {
        const double exponent = k.exponent, net = k.net;
        const GrainSpec spec{0.03, 1.5, exponent};
        Plane d = boolean_patch(spec, pitch_um, net, k.side_px);
        auto [sigma, readings] = aperture_granularity(d, pitch_um);
        const double expected = spec.rms_granularity * std::pow(net, exponent);
        // The sample standard deviation's relative standard error, 1/sqrt(2(n - 1)), four
        // times over, and 2 % for the raster's aliasing (at most 1 % by design) and the
        // approximations the calibration makes (under 1 % here: see grain_boolean.h).
        const double tolerance = 4.0 / std::sqrt(2.0 * (readings - 1)) + 0.02;
        INFO("exponent " << exponent << ", net " << net << ": sigma_48 " << sigma << ", expected " << expected
                         << " over " << readings << " apertures");
        CHECK(sigma == Approx(expected).epsilon(tolerance));
    }
}

TEST_CASE("Boolean grain: each pixel integrates the grain over its footprint", "[grain][boolean]") {
    // Grain far finer than the pixel: its density variance per pixel is W0 times the
    // integral of the squared footprint, (box * Gaussian)^2, which in each axis is
    // (1 - 2 s / (sqrt(pi) p)) / p, with W0 = (sigma_48 / aperture integral)^2. The
    // filtered-noise model's kernel has the pixel averages' autocorrelation, so it agrees.
    // Fine grain keeps the logarithm linear (the pixels' transmittance varies by 7 %).
    const GrainSpec spec{0.01, 1.5, 0.5};
    const double pitch_um = 12.0, net = 1.0;
    Plane d = boolean_patch(spec, pitch_um, net, 96);
    const double sqrt_w0 = spec.rms_granularity / aperture_rms_per_unit_noise(spec.grain_size_um, 48.0);
    const double per_axis = 1.0 - 2.0 * spec.grain_size_um / (std::sqrt(M_PI) * pitch_um);
    const double expected = sqrt_w0 / pitch_um * per_axis;
    CHECK(pixel_std(d) == Approx(expected).epsilon(0.03));  // 96^2 pixels: 0.7 % standard error
    GrainModel filtered = design_grain(spec, kDMin, pitch_um, NoiseKey{1, 0, 0});
    CHECK(grain_sigma_at(filtered, kDMin + net) == Approx(expected).epsilon(0.01));
}

TEST_CASE("Boolean grain leaves each pixel's mean its own: the image is not blurred by the footprint",
          "[grain][boolean]") {
    // A step from net 0.5 to 1.5 between columns 7 and 8, grain as large as a third of a pixel:
    // the footprint's Gaussian puts about 12 % of the pixels beside the step into the other
    // side, whose disks follow its own density, so the footprint's integral alone would move
    // their mean transmittance by -11 % and +100 %. Averaged down the columns, each pixel's mean
    // transmittance is its own 10^-net, but for the disks of the light side that reach across
    // the step by their radius (a spread at the grains' own scale): 4 % less in column 8.
    const GrainSpec spec{0.01, 1.5, 0.5};
    const double pitch_um = 5.0;
    BooleanGrain g = design_boolean_grain(spec, kDMin, pitch_um, NoiseKey{3, 0, 0});
    const int kRows = 4096;
    Plane d(Window{0, 0, 16, kRows});
    for (int y = 0; y < kRows; ++y)
        for (int x = 0; x < 16; ++x) d.at(x, y) = float(kDMin + (x < 8 ? 0.5 : 1.5));
    apply_boolean_grain(d, g, 2);
    for (int x = 5; x < 11; ++x) {
        double sum = 0, sum2 = 0;
        for (int y = 0; y < kRows; ++y) {
            const double t = net_transmittance(d.at(x, y));
            sum += t, sum2 += t * t;
        }
        const double mean = sum / kRows, standard_error = std::sqrt((sum2 / kRows - mean * mean) / (kRows - 1));
        const double expected = std::pow(10.0, -(x < 8 ? 0.5 : 1.5));
        INFO("column " << x << ": mean T " << mean << " +- " << standard_error << ", expected " << expected);
        CHECK(std::abs(mean - expected) < 4 * standard_error + (x == 8 ? 0.05 : 0.0) * expected);
        CHECK(standard_error < 0.03 * expected);  // the check has teeth: the blur doubles column 8's
    }
}

TEST_CASE("Boolean grain matches the filtered-noise model's plate profile", "[grain][boolean][plate]") {
    // Both models developed over flat patches of net density 0.3-1.5 at a pitch equal to
    // the grain size, analysed as a plate and compared as the benchmark compares tiers.
    // Granularity as a fast 35 mm negative's: disks of 0.2-0.35 um, well below the grain size
    // (the disks' own spectrum would show at the pixel's frequencies otherwise).
    const GrainSpec spec{0.01, 1.5, 0.5};
    const double pitch_um = 1.5;
    const int side = 512;
    Image levels = test::flat_patches(side, side, 1, kDMin + 0.3, kDMin + 1.5, 128);
    Plane boolean_density(levels.window), filtered_density(levels.window);
    for (size_t i = 0; i < levels.pixels.size(); ++i) boolean_density.pixels[i] = filtered_density.pixels[i] = levels.pixels[i];
    apply_boolean_grain(boolean_density, design_boolean_grain(spec, kDMin, pitch_um, NoiseKey{5, 0, 0}), 0);
    apply_grain(filtered_density, design_grain(spec, kDMin, pitch_um, NoiseKey{6, 0, 0}), 0);

    auto analyse = [&](const Plane& p) {
        Image img(p.window, 1);
        img.pixels.assign(p.pixels.begin(), p.pixels.end());
        GrainAnalysisSettings settings;
        return analyze_grain({img.view()}, settings);
    };
    GrainMatch m = compare_grain_profiles(analyse(filtered_density), analyse(boolean_density));
    const ChannelMatch& c = m.channels.at(0);
    INFO("response " << c.response_error_percent << " % over " << c.levels_compared << " levels, NPS "
                     << c.nps_distance_db << " dB, half-power " << c.half_power_a << " vs " << c.half_power_b
                     << " cycles/px");
    CHECK(c.levels_compared >= 4);
    CHECK(m.passes());
}

TEST_CASE("Boolean grain is the same for any window, band and thread count", "[grain][boolean][determinism]") {
    const GrainSpec spec{0.02, 1.0, 0.5};
    // A cell per pixel, and two cells across a pixel.
    for (double pitch_um : {3.0, 12.0}) {
        BooleanGrain g = design_boolean_grain(spec, kDMin, pitch_um, NoiseKey{9, 4, 2});
        // A picture: a density ramp with a hard-edged step, and a few pixels below d_min.
        Plane full(Window{0, 0, 48, 40});
        for (int y = 0; y < 40; ++y)
            for (int x = 0; x < 48; ++x) full.at(x, y) = float(kDMin - 0.05 + 0.04 * x + (y > 20 ? 0.8 : 0.0));
        Plane source = full, threaded = full;
        apply_boolean_grain(full, g, 1);
        apply_boolean_grain(threaded, g, 3);
        CHECK(threaded.pixels == full.pixels);

        // A window equals the full frame's pixels when its plane covers it plus the halo.
        const Window window{13, 7, 31, 26};
        Plane part(window.grown(g.halo_px));
        for (int y = part.window.y0; y < part.window.y1; ++y)
            for (int x = part.window.x0; x < part.window.x1; ++x) part.at(x, y) = source.at(x, y);
        apply_boolean_grain(part, g, 2);
        for (int y = window.y0; y < window.y1; ++y)
            for (int x = window.x0; x < window.x1; ++x) REQUIRE(part.at(x, y) == full.at(x, y));

        // Another seed, frame or layer is another field.
        Plane other = source;
        apply_boolean_grain(other, design_boolean_grain(spec, kDMin, pitch_um, NoiseKey{9, 5, 2}), 1);
        CHECK(other.pixels != full.pixels);
    }
}

TEST_CASE("Boolean grain: bad values give finite densities", "[grain][boolean]") {
    Plane d(Window{0, 0, 8, 8}, float(kDMin + 1.0));
    d.at(1, 1) = std::nanf("");
    d.at(2, 2) = 1e30f;
    d.at(3, 3) = std::numeric_limits<float>::infinity();
    d.at(4, 4) = -std::numeric_limits<float>::infinity();
    d.at(5, 5) = -5.0f;
    Plane zero_size = d;
    apply_boolean_grain(d, design_boolean_grain(GrainSpec{0.02, 1.0, 0.5}, kDMin, 6.0, NoiseKey{}), 1);
    for (float v : d.pixels) CHECK(std::isfinite(v));
    CHECK(d.at(1, 1) < 1.0f);               // NaN: no silver
    CHECK(d.at(2, 2) == Approx(1e30f));     // huge densities keep their size
    // Zero grain size: the footprint is the pixel alone.
    apply_boolean_grain(zero_size, design_boolean_grain(GrainSpec{0.02, 0.0, 0.5}, kDMin, 6.0, NoiseKey{}), 1);
    for (float v : zero_size.pixels) CHECK(std::isfinite(v));
    // Zero granularity, or a spec that is not a number: no grain at all.
    for (GrainSpec spec : {GrainSpec{0.0, 1.0, 0.5}, GrainSpec{std::nan(""), 1.0, 0.5}, GrainSpec{0.02, 1.0, -1.0}}) {
        BooleanGrain g = design_boolean_grain(spec, kDMin, 6.0, NoiseKey{});
        CHECK(g.is_noop());
        Plane flat(Window{0, 0, 4, 4}, 0.7f);
        apply_boolean_grain(flat, g, 1);
        for (float v : flat.pixels) CHECK(v == 0.7f);
    }
}

TEST_CASE("Boolean grain's raster sets exactly the samples its disks cover, on every instruction set",
          "[grain][boolean][simd]") {
    test::IsaScope scope;
    std::mt19937 rng(5);
    const double h = 0.01;  // um
    // Part of a word, a whole word, and three words with a partial last; disks from under a
    // sample to 17 samples in radius (one across two words); few of them, and so many that
    // most are covered before they are drawn (the path that skips them).
    for (int m : {37, 64, 150})
        for (double radius_samples : {0.7, 2.5, 5.5, 17.0})
            for (double coverage : {0.3, 0.999}) {
                INFO("m " << m << ", radius " << radius_samples << " samples, coverage " << coverage);
                const double r = radius_samples * h, grown = m * h + 2 * r;
                const int count = int(std::ceil(-std::log(1 - coverage) * grown * grown / (M_PI * r * r)));
                // Centres over the raster grown by the radius, so that disks cross its edges.
                std::uniform_real_distribution<float> position(float(-r), float(m * h + r));
                std::vector<float> x(static_cast<size_t>(count)), y(static_cast<size_t>(count));
                for (int k = 0; k < count; ++k) x[size_t(k)] = position(rng), y[size_t(k)] = position(rng);

                // The definition, sample by sample near each disk; a sample within rounding of a
                // disk's edge is left out unless another disk covers it.
                std::vector<char> inside(size_t(m) * m, 0), on_edge(size_t(m) * m, 0);
                for (int k = 0; k < count; ++k) {
                    const double cx = x[size_t(k)] / h - 0.5, cy = y[size_t(k)] / h - 0.5, rs = r / h;
                    for (int j = std::max(0, int(cy - rs) - 1); j <= std::min(m - 1, int(cy + rs) + 1); ++j)
                        for (int i = std::max(0, int(cx - rs) - 1); i <= std::min(m - 1, int(cx + rs) + 1); ++i) {
                            const double d2 = (i - cx) * (i - cx) + (j - cy) * (j - cy);
                            if (std::abs(d2 - rs * rs) < 1e-9 * rs * rs)
                                on_edge[size_t(j) * m + i] = 1;
                            else if (d2 < rs * rs)
                                inside[size_t(j) * m + i] = 1;
                        }
                }
                std::vector<std::vector<uint64_t>> rasters;
                for (simd::Isa isa : test::runnable_isas()) {
                    simd::set_isa(isa);
                    for (bool skip_covered : {false, true})
                        rasters.push_back(boolean_disk_raster(x, y, r, h, m, skip_covered));
                }
                for (size_t k = 1; k < rasters.size(); ++k) CHECK(rasters[k] == rasters[0]);
                int checked = 0, wrong = 0, set = 0;
                for (int j = 0; j < m; ++j)
                    for (int i = 0; i < m; ++i) {
                        const bool bit = (rasters[0][size_t(i / 64) * m + j] >> (i % 64)) & 1;
                        set += bit;
                        if (on_edge[size_t(j) * m + i] && !inside[size_t(j) * m + i]) continue;
                        ++checked;
                        wrong += bit != bool(inside[size_t(j) * m + i]);
                    }
                CHECK(wrong == 0);
                CHECK(checked > m * m * 99 / 100);
                CHECK(set > 0);
                if (coverage < 0.5) CHECK(set < m * m);
            }
}

TEST_CASE("Boolean grain is the same on every instruction set", "[grain][boolean][simd][determinism]") {
    test::IsaScope scope;
    const GrainSpec spec{0.02, 1.0, 0.5};
    // A ramp from no silver to past the model's cap, 11 px wide (draws and rows that fill no
    // whole vector), at a cell a pixel and at two cells across a pixel.
    for (double pitch_um : {3.0, 12.0}) {
        BooleanGrain g = design_boolean_grain(spec, kDMin, pitch_um, NoiseKey{3, 1, 2});
        Plane ramp(Window{0, 0, 11, 6});
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 11; ++x) ramp.at(x, y) = float(kDMin + 0.32 * x);
        std::vector<Plane> results;
        for (simd::Isa isa : test::runnable_isas()) {
            simd::set_isa(isa);
            Plane d = ramp;
            apply_boolean_grain(d, g, 2);
            results.push_back(std::move(d));
        }
        for (size_t k = 1; k < results.size(); ++k) CHECK(results[k].pixels == results[0].pixels);
    }
}
