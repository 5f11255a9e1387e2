#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/stages/grain.h"
#include "core/stages/tables.h"

using namespace darkroom;

static double std_dev(const std::vector<double>& v) {
    double mean = 0, var = 0;
    for (double x : v) mean += x / v.size();
    for (double x : v) var += (x - mean) * (x - mean) / (v.size() - 1);
    return std::sqrt(var);
}

TEST_CASE("the aperture integral reduces to Selwyn's law for point-like grain", "[grain]") {
    // sigma^2 A = W0 with A = pi d^2 / 4 (seed paper eq. 8, G = sigma sqrt(2A)); the
    // quadrature and the tail's mean together are within 1e-6 of it.
    for (double d : {24.0, 48.0, 96.0})
        CHECK(aperture_rms_per_unit_noise(0.0, d) == Approx(std::sqrt(4.0 / (M_PI * d * d))).epsilon(1e-6));
    // Larger grain clumps average less within the same aperture.
    CHECK(aperture_rms_per_unit_noise(5.0, 48.0) < aperture_rms_per_unit_noise(0.0, 48.0));
    // Far larger than the aperture, the reading is the field's own variance: 1/(4 pi s^2).
    CHECK(aperture_rms_per_unit_noise(500.0, 48.0) == Approx(std::sqrt(1.0 / (4 * M_PI * 500.0 * 500.0))).epsilon(0.02));
}

TEST_CASE("grain on a uniform patch reproduces the RMS granularity through a 48 um aperture", "[grain]") {
    GrainSpec spec{0.015, 1.5, 1.0 / 3.0};
    const double pitch_um = 2.0, d_min = 0.2;
    GrainModel g = design_grain(spec, d_min, pitch_um, NoiseKey{3, 0, 0});
    Plane d(Window{0, 0, 1200, 1200}, float(d_min + 1.0));
    apply_grain(d, g, 2);

    std::vector<double> pixels(d.pixels.begin(), d.pixels.end());
    CHECK(std_dev(pixels) == Approx(g.pixel_sigma_at_unit_density()).epsilon(0.02));

    // Mean density over disjoint 48 um apertures (24 px across).
    std::vector<double> readings;
    for (int cy = 12; cy + 12 < 1200; cy += 24)
        for (int cx = 12; cx + 12 < 1200; cx += 24) {
            double sum = 0;
            int n = 0;
            for (int y = cy - 12; y <= cy + 12; ++y)
                for (int x = cx - 12; x <= cx + 12; ++x)
                    if (std::hypot(x - cx, y - cy) <= 12.0) sum += d.at(x, y), ++n;
            readings.push_back(sum / n);
        }
    CHECK(std_dev(readings) == Approx(spec.rms_granularity).epsilon(0.08));
}

TEST_CASE("granularity scales with net density to the given exponent", "[grain]") {
    GrainSpec spec{0.02, 0.0, 1.0 / 3.0};
    GrainModel g = design_grain(spec, 0.1, 5.0, NoiseKey{1, 0, 0});
    Plane at1(Window{0, 0, 400, 400}, 1.1f), at8(Window{0, 0, 400, 400}, 8.1f), at0(Window{0, 0, 400, 400}, 0.1f);
    apply_grain(at1, g, 1);
    apply_grain(at8, g, 1);
    apply_grain(at0, g, 1);
    std::vector<double> a(at1.pixels.begin(), at1.pixels.end()), b(at8.pixels.begin(), at8.pixels.end());
    CHECK(std_dev(b) / std_dev(a) == Approx(2.0).epsilon(0.01));  // 8^(1/3)
    for (float v : at0.pixels) CHECK(v == 0.1f);                   // no silver, no grain
}

TEST_CASE("grain is the same for any window of the frame", "[grain][determinism]") {
    GrainModel g = design_grain(GrainSpec{0.02, 3.0, 0.5}, 0.0, 2.0, NoiseKey{9, 4, 2});
    Plane full(Window{0, 0, 64, 48}, 1.0f), part(Window{13, 7, 41, 30}, 1.0f);
    apply_grain(full, g, 3);
    apply_grain(part, g, 1);
    for (int y = 7; y < 30; ++y)
        for (int x = 13; x < 41; ++x) REQUIRE(part.at(x, y) == full.at(x, y));
}

TEST_CASE("the fast tiers' grain kernel drops only taps the field's correlation does not need", "[grain]") {
    // The autocorrelation over lag 0 of a kernel, at lags 0 ... n (0 past its length).
    auto correlation = [](const std::vector<float>& k, size_t lags) {
        std::vector<double> a(lags + 1, 0.0);
        for (size_t lag = 0; lag <= lags; ++lag)
            for (size_t j = 0; j + lag < k.size(); ++j) a[lag] += double(k[j]) * k[j + lag];
        for (size_t lag = lags + 1; lag-- > 0;) a[lag] /= a[0];
        return a;
    };
    // Vision3-like grain at a 4K frame's pitch (whose outer taps are ~0.2 % of the centre), and
    // larger grain at a finer pitch.
    const auto [size_um, pitch_um] = GENERATE(std::pair{1.0, 6.2}, std::pair{1.44, 3.1}, std::pair{3.0, 2.0});
    const GrainSpec spec{0.006, size_um, 0.5};
    const GrainModel full = design_grain(spec, 0.2, pitch_um, NoiseKey{}, false);
    const GrainModel fast = design_grain(spec, 0.2, pitch_um, NoiseKey{}, true);
    CAPTURE(size_um, pitch_um, full.kernel.size(), fast.kernel.size());
    CHECK(fast.kernel.size() % 2 == 1);
    CHECK(fast.radius == int(fast.kernel.size() / 2));
    CHECK(fast.kernel.size() <= full.kernel.size());
    double sum = 0;
    for (float v : fast.kernel) sum += v;
    CHECK(sum == Approx(1.0).epsilon(1e-6));  // the 48 um reading kept
    const std::vector<double> a_full = correlation(full.kernel, full.kernel.size() - 1);
    const std::vector<double> a_fast = correlation(fast.kernel, full.kernel.size() - 1);
    for (size_t lag = 0; lag < a_full.size(); ++lag) CHECK(std::abs(a_fast[lag] - a_full[lag]) <= kFastGrainCorrelationTolerance);
    if (pitch_um > 6) CHECK(fast.kernel.size() == 3);  // the two outer taps of five go
    // One pair more would break the tolerance (or none is left).
    if (fast.kernel.size() > 1) {
        std::vector<float> shorter(fast.kernel.begin() + 1, fast.kernel.end() - 1);
        double s = 0;
        for (float v : shorter) s += v;
        for (float& v : shorter) v = float(v / s);
        const std::vector<double> a_short = correlation(shorter, full.kernel.size() - 1);
        double worst = 0;
        for (size_t lag = 0; lag < a_full.size(); ++lag) worst = std::max(worst, std::abs(a_short[lag] - a_full[lag]));
        CHECK(worst > kFastGrainCorrelationTolerance);
    }
}

TEST_CASE("the fast tiers' develop and grain in one pass: the table's density plus its amplitude times the field",
          "[grain][tables]") {
    // A Vision3-like toe-to-shoulder curve against log10 H, and hashed-noise grain at 6 um.
    const Curve curve = make_curve({-3.0, -2.0, -1.0, 0.0, 1.0}, {0.2, 0.3, 1.0, 1.8, 2.2}, "curve");
    const double exponent = GENERATE(1.0 / 3.0, 0.5);
    const GrainModel g = design_grain(GrainSpec{0.006, 1.0, exponent}, 0.2, 6.0, NoiseKey{5, 2, 1}, true);
    const LogAxisTable table(curve, 8, [&](double d) { return g.amplitude_at(d); });
    const Window w{-9, 4, 131, 70};
    Plane plane(w);
    for (int y = w.y0; y < w.y1; ++y)
        for (int x = w.x0; x < w.x1; ++x) plane.at(x, y) = float(std::pow(10.0, -3.5 + 4.8 * ((x * 31 + y * 17) % 97) / 96.0));
    const Plane exposure = plane;
    develop_with_grain(plane, table, g, 3);
    const Plane field = grain_field(g, w, 1);
    double worst = 0;  // |amplitude - amplitude_at(density)| / amplitude_at(net density 1)
    for (int y = w.y0; y < w.y1; ++y) {
        std::vector<float> density(w.width()), amplitude(w.width());
        table.apply_row(exposure.row(y), density.data(), amplitude.data(), w.width());
        for (int x = w.x0; x < w.x1; ++x) {
            const int i = x - w.x0;
            // The definition, in the same float operations.
            REQUIRE(plane.at(x, y) == std::max(g.d_min, density[i] + amplitude[i] * field.at(x, y)));
            REQUIRE(density[i] == table(exposure.at(x, y)));
            worst = std::max(worst, std::abs(amplitude[i] - g.amplitude_at(density[i])) / g.amplitude_at(g.d_min + 1.0));
        }
    }
    // The amplitude is sampled at the table's exposures and interpolated in H, not in the
    // density: it errs most just above the toe, where (D - d_min)^exponent rises from 0 with
    // unbounded slope (2 % of the unit-density amplitude for a cube root, 0.3 % for a square root).
    CHECK(worst < 0.03);
    // A table without the second function gives the same densities and no amplitude.
    const LogAxisTable plain(curve, 8);
    std::vector<float> density(w.width()), amplitude(w.width(), 1.0f), again(w.width());
    plain.apply_row(exposure.row(w.y0), density.data(), amplitude.data(), w.width());
    table.apply_row(exposure.row(w.y0), again.data(), w.width());
    CHECK(density == again);
    CHECK(std::all_of(amplitude.begin(), amplitude.end(), [](float a) { return a == 0.0f; }));
}

TEST_CASE("a grain that mixes white noises filters their weighted sum: correlated fields of unit-variance noise",
          "[grain]") {
    // Two fast grains of one kernel; the second filters 0.6 of the first's white noise plus 0.8
    // of its own (fold_paper_grain's Cholesky row). The filter is linear, so its field is 0.6
    // times the first's field plus 0.8 times the field of its own noise alone (to rounding),
    // and the two fields correlate by 0.6 with equal variances.
    const GrainModel first = design_grain(GrainSpec{0.01, 2.0}, 0.1, 4.0, NoiseKey{7, 3, 0}, true);
    GrainModel own = design_grain(GrainSpec{0.01, 2.0}, 0.1, 4.0, NoiseKey{7, 3, 1}, true), mixed = own;
    mixed.mixed_noise = {{first.key, 0.6f}, {own.key, 0.8f}};
    const Window w{-50, 20, 206, 276};
    GrainNoiseStream both({&first, &mixed}, w), alone({&own}, w);
    double sum_aa = 0, sum_bb = 0, sum_ab = 0;
    for (int y = w.y0; y < w.y1; ++y) {
        const float* const* rows = both.row(y);
        const float* own_row = alone.row(y)[0];
        for (int i = 0; i < w.width(); ++i) {
            REQUIRE(rows[1][i] == Approx(0.6 * rows[0][i] + 0.8 * own_row[i]).margin(1e-5));
            sum_aa += double(rows[0][i]) * rows[0][i], sum_bb += double(rows[1][i]) * rows[1][i];
            sum_ab += double(rows[0][i]) * rows[1][i];
        }
    }
    const double pixels = double(w.width()) * w.height();
    CHECK(std::sqrt(sum_bb / sum_aa) == Approx(1.0).margin(0.02));
    CHECK(sum_ab / std::sqrt(sum_aa * sum_bb) == Approx(0.6).margin(0.02));
    CHECK(std::sqrt(sum_aa / pixels) == Approx(first.field_sigma()).epsilon(0.03));
}
