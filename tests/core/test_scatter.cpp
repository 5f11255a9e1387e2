#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "core/fft.h"
#include "core/stages/filters.h"
#include "core/stages/scatter.h"
#include "test_support.h"

using namespace darkroom;

// Response of the discrete kernel to a sine along x, as a sine target measures it.
static double kernel_response(const ScatterKernel& k, double cycles_per_px) {
    int side = 2 * k.radius + 1;
    double re = 0;
    for (int y = -k.radius; y <= k.radius; ++y)
        for (int x = -k.radius; x <= k.radius; ++x)
            re += k.taps[(y + k.radius) * side + x + k.radius] * std::cos(2 * M_PI * cycles_per_px * x);
    return re;
}

TEST_CASE("the scatter kernel's response to a sine target follows the MTF", "[scatter]") {
    const Curve mtf = test::test_film().layers[0].mtf;
    const double pitch_um = 2.0;
    ScatterKernel k = design_scatter_kernel(mtf, pitch_um);
    REQUIRE(k.radius > 0);
    double sum = 0;
    for (float t : k.taps) sum += t;
    CHECK(sum == Approx(1.0).margin(1e-6));
    for (double f : {5.0, 10.0, 20.0, 40.0, 60.0, 80.0, 120.0, 200.0}) {
        INFO("frequency " << f << " cycles/mm");
        CHECK(kernel_response(k, f * pitch_um / 1000.0) == Approx(mtf_response(mtf, f)).margin(0.01));
    }
}

TEST_CASE("scattering a sine image reduces its modulation by the MTF", "[scatter]") {
    const Curve mtf = test::test_film().layers[0].mtf;
    const double pitch_um = 2.5, f = 40.0;  // 10 pixels per cycle
    ScatterKernel k = design_scatter_kernel(mtf, pitch_um);
    Window frame{0, 0, 200, 40};
    Plane src(frame), dst(Window{50, 10, 150, 30});
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 200; ++x) src.at(x, y) = float(1.0 + 0.5 * std::sin(2 * M_PI * (x + 0.5) / 10.0));  // peaks on pixels
    scatter(src, dst, k, frame, 2);
    double amplitude = 0;
    for (int x = 50; x < 150; ++x) amplitude = std::max(amplitude, std::abs(dst.at(x, 20) - 1.0));
    CHECK(amplitude / 0.5 == Approx(mtf_response(mtf, f)).margin(0.01));
}

TEST_CASE("an MTF flat to Nyquist designs no kernel", "[scatter]") {
    const Curve mtf = test::test_film().layers[0].mtf;
    CHECK(mtf_deviation_to_nyquist(mtf, 2.0) > 0.1);
    // At 100 um pixels the MTF is not flat to Nyquist, but the PSF sampled at pixel centres
    // keeps less than 1e-3 of its weight outside the centre pixel: the kernel is identity.
    CHECK(mtf_deviation_to_nyquist(mtf, 100.0) > kMtfNoOpTolerance);
    CHECK(design_scatter_kernel(mtf, 100.0).is_identity());
    CHECK_FALSE(design_scatter_kernel(mtf, 20.0).is_identity());
    Curve flat = make_curve({0, 100}, {1.0, 1.0}, "flat");
    CHECK(design_scatter_kernel(flat, 1.0).is_identity());
}

TEST_CASE("MTF extrapolation beyond the last sample never rises", "[scatter]") {
    Curve mtf = make_curve({0, 50, 100}, {1.0, 0.6, 0.3}, "m");
    CHECK(mtf_response(mtf, 150) == Approx(0.15).margin(1e-9));  // log-linear: halves every 50
    Curve rising = make_curve({0, 50, 100}, {1.0, 0.6, 0.7}, "m");
    CHECK(mtf_response(rising, 400) == Approx(0.7));
}

TEST_CASE("the separable form of a scatter kernel gives the direct convolution's pixels", "[scatter]") {
    // Flat to 10 c/mm, then falling: a kernel with long ringing tails (Vision3-like, at 12 um).
    Curve mtf = make_curve({0, 5, 10, 20, 40, 60, 80}, {1, 1, 1, 0.95, 0.75, 0.55, 0.4}, "mtf");
    ScatterKernel k = design_scatter_kernel(mtf, 12.0);
    REQUIRE(k.radius > 20);
    REQUIRE(!k.separable.empty());
    CHECK(k.separable.size() < size_t(k.radius) / 2);  // far cheaper than (2r+1)^2 taps
    // The terms rebuild every tap within the tolerance, up to one common scale that makes
    // their gain exactly 1 (the terms left out would otherwise change the image's mean).
    const int side = 2 * k.radius + 1;
    std::vector<double> rebuilt(side * side, 0.0);
    double largest = 0, gain = 0, tap_product = 0, tap_square = 0;
    for (float t : k.taps) largest = std::max(largest, double(std::abs(t)));
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            double& sum = rebuilt[i * side + j];
            for (size_t t = 0; t < k.separable.size(); ++t)
                sum += k.separable_sign[t] * double(k.separable[t][i]) * k.separable[t][j];
            gain += sum;
            tap_product += sum * k.taps[i * side + j];
            tap_square += double(k.taps[i * side + j]) * k.taps[i * side + j];
        }
    CHECK(gain == Approx(1.0).margin(1e-5));
    const double scale = tap_product / tap_square;
    CHECK(scale == Approx(1.0).margin(1e-3));
    double worst = 0;
    for (int i = 0; i < side * side; ++i) worst = std::max(worst, std::abs(rebuilt[i] - scale * k.taps[i]));
    CHECK(worst <= 1.5 * kSeparableTolerance * largest);
    // And convolve to the direct sum's pixels, edges included.
    Window frame{0, 0, 150, 90};
    Plane src(frame), separable(frame), direct(frame);
    for (int y = 0; y < 90; ++y)
        for (int x = 0; x < 150; ++x) src.at(x, y) = float((x / 7 + y / 5) % 3) + 0.1f * float(x % 11);
    scatter(src, separable, k, frame, 2);
    ScatterKernel taps_only = k;
    taps_only.separable.clear();
    scatter(src, direct, taps_only, frame, 2);
    for (size_t i = 0; i < src.pixels.size(); ++i) REQUIRE(separable.pixels[i] == Approx(direct.pixels[i]).margin(1e-4));  // inputs up to 3.1
    // Each thread filters its rows through its own ring of horizontal results: one thread or seven
    // change no pixel.
    for (int threads : {1, 7}) {
        Plane again(frame);
        scatter(src, again, k, frame, threads);
        CHECK(again.pixels == separable.pixels);
    }
}

// The largest |tap - rebuilt tap| of a kernel's separable terms, after the common scale
// that gives them unit gain.
static double separable_residual(const ScatterKernel& k) {
    const std::vector<double> rebuilt = k.applied_taps();
    double product = 0, square = 0;
    for (size_t i = 0; i < rebuilt.size(); ++i) {
        product += rebuilt[i] * k.taps[i];
        square += double(k.taps[i]) * k.taps[i];
    }
    double worst = 0;
    for (size_t i = 0; i < rebuilt.size(); ++i) worst = std::max(worst, std::abs(rebuilt[i] - product / square * k.taps[i]));
    return worst;
}

TEST_CASE("a design limited to k separable terms keeps the k largest, where the tolerance alone would sum directly",
          "[scatter]") {
    Curve mtf = make_curve({0, 5, 10, 20, 40, 60, 80}, {1, 1, 1, 0.95, 0.75, 0.55, 0.4}, "mtf");
    // A tolerance no 5x5 kernel's 2 cheap terms reach (tapered to zero at 3 px, the taps reach
    // 2 px): the direct sum.
    CHECK(design_scatter_kernel(mtf, 6.0, {3, 1e-12}).separable.empty());
    const ScatterKernel one = design_scatter_kernel(mtf, 6.0, {3, 1e-12, 1});
    const ScatterKernel two = design_scatter_kernel(mtf, 6.0, {3, 1e-12, 2});
    REQUIRE(one.separable.size() == 1);
    REQUIRE(two.separable.size() == 2);
    REQUIRE(one.radius == 2);
    // The same first (largest) term, up to the unit-gain scale.
    const double scale = two.separable[0][2] / one.separable[0][2];
    for (int i = 0; i < 5; ++i) CHECK(two.separable[0][i] == Approx(scale * one.separable[0][i]).margin(1e-7));
    // Each term takes off the residual's largest part; at most 2 terms are cheaper than 25 taps.
    CHECK(separable_residual(two) < 0.5 * separable_residual(one));
    CHECK(design_scatter_kernel(mtf, 6.0, {3, 1e-12, 3}).separable.empty());
    for (const ScatterKernel& k : {one, two}) {
        double gain = 0;
        for (size_t t = 0; t < k.separable.size(); ++t) {
            double sum = 0;
            for (float v : k.separable[t]) sum += v;
            gain += k.separable_sign[t] * sum * sum;
        }
        CHECK(gain == Approx(1.0).margin(1e-5));  // the image's mean is kept
    }
}

TEST_CASE("a compact PSF as a centre delta and one term: as close as two terms, and applied as designed", "[scatter]") {
    // Vision3-like at a 4K frame's pitch, tapered to zero at 3 px as the fast tier designs it: a
    // sharp centre (0.7 of the weight) over a smooth spread.
    const Curve mtf = make_curve({0, 5, 10, 20, 40, 60, 80}, {1, 1, 1, 0.95, 0.75, 0.55, 0.4}, "mtf");
    const ScatterKernel two = design_scatter_kernel(mtf, 6.0, {3, 1e-3, 2});
    const ScatterKernel centred = design_scatter_kernel(mtf, 6.0, {3, 1e-3, 2, true});
    REQUIRE(two.separable.size() == 2);
    REQUIRE(centred.separable.size() == 1);
    CHECK(centred.centre > 0.3f);
    const int side = 2 * centred.radius + 1;
    CHECK(centred.centre < centred.taps[size_t(centred.radius) * side + centred.radius]);
    // Every tap within the tolerance, as the two terms are; the gain exactly 1.
    double largest = 0, gain = 0, worst = 0, worst_two = 0;
    const std::vector<double> applied = centred.applied_taps(), applied_two = two.applied_taps();
    for (size_t i = 0; i < applied.size(); ++i) {
        largest = std::max(largest, double(std::abs(centred.taps[i])));
        gain += applied[i];
        worst = std::max(worst, std::abs(applied[i] - centred.taps[i]));
        worst_two = std::max(worst_two, std::abs(applied_two[i] - two.taps[i]));
    }
    CHECK(gain == Approx(1.0).margin(1e-6));
    CHECK(worst <= 1.5e-3 * largest);
    CHECK(worst <= 2 * worst_two);
    // The stream (one pass, or a plane at a time) applies the centre with the term: the direct
    // sum of the applied taps' pixels, edges included, whatever the threads.
    const Window frame{0, 0, 150, 90};
    Plane src(frame), streamed(frame), direct(frame);
    for (int y = 0; y < 90; ++y)
        for (int x = 0; x < 150; ++x) src.at(x, y) = float((x / 7 + y / 5) % 3) + 0.1f * float(x % 11);
    scatter(src, streamed, centred, frame, 2);
    ScatterKernel taps_only = centred;
    taps_only.taps.assign(applied.begin(), applied.end());
    taps_only.separable.clear();
    scatter(src, direct, taps_only, frame, 2);
    for (size_t i = 0; i < src.pixels.size(); ++i) REQUIRE(streamed.pixels[i] == Approx(direct.pixels[i]).margin(1e-5));
    for (int threads : {1, 7}) {
        Plane again(frame);
        scatter(src, again, centred, frame, threads);
        CHECK(again.pixels == streamed.pixels);
    }
}

TEST_CASE("a PSF tapered to zero at R px keeps its taps to R - 1 px, where they end, and its response", "[scatter]") {
    // A wide PSF (a soft MTF at a 4K frame's pitch) for the fast and preview tiers' radii.
    const Curve mtf = make_curve({0, 5, 10, 20, 40, 60, 80}, {1, 0.95, 0.85, 0.6, 0.3, 0.15, 0.08}, "soft");
    const ScatterKernel whole = design_scatter_kernel(mtf, 6.0, {0, 0.0});
    for (int max_radius : {2, 3}) {
        INFO("tapered to zero at " << max_radius << " px");
        REQUIRE(whole.radius > max_radius);
        const ScatterKernel k = design_scatter_kernel(mtf, 6.0, {max_radius, 0.0});
        // The ring at R - 1 carries weight (the ring at R, all zero, is not kept).
        REQUIRE(k.radius == max_radius - 1);
        const int side = 2 * k.radius + 1;
        double ring = 0;
        for (int i = 0; i < side; ++i) ring += std::abs(k.taps[size_t(i)]) + std::abs(k.taps[size_t(i) * side]);
        CHECK(ring > 1e-4);
        // The taper's definition: the PSF's taps times the raised cosine from R / 2 to R, to unit sum.
        const int r = whole.radius, whole_side = 2 * r + 1;
        std::vector<double> tapered;
        double sum = 0;
        for (int y = -k.radius; y <= k.radius; ++y)
            for (int x = -k.radius; x <= k.radius; ++x) {
                const double rho = std::hypot(x, y) / max_radius;
                const double weight = rho >= 1.0   ? 0.0
                                      : rho <= 0.5 ? 1.0
                                                   : 0.5 * (1.0 + std::cos(M_PI * (rho - 0.5) / 0.5));
                tapered.push_back(weight * whole.taps[size_t(y + r) * whole_side + (x + r)]);
                sum += tapered.back();
            }
        for (size_t i = 0; i < tapered.size(); ++i) CHECK(k.taps[i] == Approx(tapered[i] / sum).margin(1e-6));
    }
}

TEST_CASE("a kernel's separable terms are its eigen-terms: orthogonal, even, largest first", "[scatter]") {
    // The high tier's design of a Vision3-like MTF at a 4K frame's pitch: dozens of terms,
    // whose small eigenvalues come in nearly opposite pairs that power iteration mixes up.
    const Curve mtf = make_curve({0, 5, 10, 20, 40, 60, 80}, {1, 1, 1, 0.95, 0.75, 0.55, 0.4}, "mtf");
    const ScatterKernel k = design_scatter_kernel(mtf, 6.0);
    REQUIRE(k.separable.size() > 10);
    const int side = 2 * k.radius + 1;
    auto dot = [&](size_t a, size_t b) {
        double sum = 0;
        for (int i = 0; i < side; ++i) sum += double(k.separable[a][i]) * k.separable[b][i];
        return sum;
    };
    for (size_t a = 0; a < k.separable.size(); ++a) {
        for (int i = 0; i < side; ++i) REQUIRE(k.separable[a][i] == k.separable[a][side - 1 - i]);
        // |e_a|^2 is |eigenvalue_a| (the terms are scaled by sqrt|eigenvalue|).
        if (a > 0) CHECK(dot(a, a) <= dot(a - 1, a - 1) * (1 + 1e-6));
        for (size_t b = 0; b < a; ++b) CHECK(std::abs(dot(a, b)) <= 1e-5 * std::sqrt(dot(a, a) * dot(b, b)));
    }
}

TEST_CASE("an MTF with no response at 0 is refused, not designed into a 0/0 kernel", "[scatter]") {
    const Curve zero = make_curve({0, 50}, {0, 0}, "zero");
    CHECK_THROWS_WITH(design_scatter_kernel(zero, 5.0), Catch::Contains("response at 0 cycles/mm must be positive"));
    const Curve falling_from_zero = make_curve({0, 10, 50}, {0, 0.5, 0.2}, "dip");
    CHECK_THROWS_AS(design_scatter_kernel(falling_from_zero, 5.0), std::invalid_argument);
}

TEST_CASE("the kernel cache gives the design of the same inputs, beyond its size bound too", "[scatter]") {
    const Curve mtf = make_curve({0, 20, 60}, {1, 0.8, 0.3}, "mtf");
    const ScatterKernel first = design_scatter_kernel(mtf, 6.0);
    for (size_t i = 0; i <= kMaxCachedKernels; ++i) design_scatter_kernel(mtf, 6.5 + 0.01 * double(i));  // fills and empties it
    const ScatterKernel again = design_scatter_kernel(mtf, 6.0);
    CHECK(again.taps == first.taps);
    CHECK(again.separable == first.separable);
}

TEST_CASE("a PSF's taps are even in x and in y and the same transposed, on one thread or several", "[scatter]") {
    // The direct taps (no separable terms). max_terms is unused without them, so the two
    // designs have other cache keys and are each computed, on 1 and on 3 threads.
    const Curve mtf = test::test_film().layers[0].mtf;
    for (double pitch_um : {2.0, 6.0}) {
        INFO("pitch " << pitch_um << " um");
        const ScatterKernel one = design_scatter_kernel(mtf, pitch_um, {0, 0.0, 0}, 1);
        const ScatterKernel three = design_scatter_kernel(mtf, pitch_um, {0, 0.0, 5}, 3);
        CHECK(three.taps == one.taps);
        const int r = one.radius, side = 2 * r + 1;
        REQUIRE(r > 1);
        auto tap = [&](int x, int y) { return one.taps[size_t(y + r) * side + x + r]; };
        int asymmetric = 0;
        for (int y = -r; y <= r; ++y)
            for (int x = -r; x <= r; ++x)
                if (tap(x, y) != tap(-x, y) || tap(x, y) != tap(x, -y) || tap(x, y) != tap(y, x)) ++asymmetric;
        CHECK(asymmetric == 0);
    }
}

TEST_CASE("row and column convolutions sum their taps in the documented order, in vector blocks and the tail",
          "[scatter][filters]") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 3);
    // Three blocks of eight vectors of the widest lanes (16), a single vector and a scalar tail.
    const int width = 128 * 3 + 16 + 13;
    // 3, 5, 7 and 11 taps have loops compiled for them (the fast tiers' grain, MTF and the
    // couplers' coarse Gaussian; with AVX-512 a row's inputs shifted in registers); 9 any count.
    for (int n : {3, 5, 7, 9, 11})
        for (bool symmetric : {true, false}) {
            const int half = n / 2;
            std::vector<float> taps(n);
            for (int k = 0; k < n; ++k) taps[k] = symmetric ? 0.2f / float(1 + std::abs(k - half)) : u(rng);
            INFO(n << " taps, symmetric " << symmetric);
            std::vector<float> in(width + n + 3), out(width);
            for (float& v : in) v = u(rng);
            convolve_row(in.data(), taps, width, out.data());
            std::vector<const float*> rows;
            for (int k = 0; k < n + 3; ++k) rows.push_back(in.data() + k);  // the same sums, as a column pass
            std::vector<float> column(width, 0.5f), column_written(width, 0.5f);
            float *column_row = column.data(), *column_written_row = column_written.data();
            convolve_columns(rows.data(), taps, width, &column_row, 1, true);
            convolve_columns(rows.data(), taps, width, &column_written_row, 1, false);
            // 1, 2 and 4 rows at once: row o reads rows o to o + n - 1, i.e. `in` o further along.
            // With a centre, each row o also adds 0.3 times the row `in` + 3 - o (any row of its own).
            const float centre = 0.3f;
            const float* centre_rows[4];
            for (int o = 0; o < 4; ++o) centre_rows[o] = in.data() + 3 - o;
            std::vector<float> group_added[3][4], group_written[3][4], group_centred[3][4];
            const int group_rows[3] = {1, 2, 4};
            for (int g = 0; g < 3; ++g) {
                float *added[4], *written[4], *centred[4];
                for (int o = 0; o < group_rows[g]; ++o) {
                    group_added[g][o].assign(width, 0.5f), group_written[g][o].assign(width, 0.5f);
                    group_centred[g][o].assign(width, 0.5f);
                    added[o] = group_added[g][o].data(), written[o] = group_written[g][o].data();
                    centred[o] = group_centred[g][o].data();
                }
                convolve_columns(rows.data(), taps, width, added, group_rows[g], true);
                convolve_columns(rows.data(), taps, width, written, group_rows[g], false);
                convolve_columns(rows.data(), taps, width, centred, group_rows[g], true, centre, centre_rows);
            }
            for (int x = 0; x < width; ++x) {
                // The definition at x + o, in float from `start`: mirrored taps folded when symmetric, else in order.
                auto definition = [&](float start, int o = 0) {
                    float sum = start;
                    const float* at = in.data() + x + o;
                    if (symmetric) {
                        for (int k = 0; k < half; ++k) sum += taps[k] * (at[k] + at[n - 1 - k]);
                        return sum + taps[half] * at[half];
                    }
                    for (int k = 0; k < n; ++k) sum += taps[k] * at[k];
                    return sum;
                };
                REQUIRE(out[x] == definition(0.0f));
                REQUIRE(column[x] == definition(0.5f));
                REQUIRE(column_written[x] == definition(0.0f));
                for (int g = 0; g < 3; ++g)
                    for (int o = 0; o < group_rows[g]; ++o) {
                        INFO(group_rows[g] << " rows at once, row " << o);
                        REQUIRE(group_added[g][o][x] == definition(0.5f, o));
                        REQUIRE(group_written[g][o][x] == definition(0.0f, o));
                        // (as a one-tap pass added to the stored sum would add it)
                        REQUIRE(group_centred[g][o][x] == definition(0.5f, o) + centre * centre_rows[o][x]);
                    }
                double exact = 0;
                for (int k = 0; k < n; ++k) exact += double(taps[k]) * in[x + k];
                CHECK(out[x] == Approx(exact).margin(1e-5));
            }
        }
}

// Any kernel, without symmetry in x and y, as singular-value terms: every term the kernel has
// gives its taps back; fewer leave out at most the energy asked; a separable kernel is one term.
TEST_CASE("separable_approximation: a kernel's singular-value terms, largest first, within the energy asked",
          "[filters]") {
    const int r = 3, side = 2 * r + 1;
    std::vector<double> taps(side * side);
    uint32_t state = 12345;
    for (double& t : taps) {
        state = state * 1664525u + 1013904223u;  // (a fixed pseudo-random kernel)
        t = double(state >> 8) / double(1 << 24) - 0.3;
    }
    auto applied = [&](const SeparableFilter& f) {  // the taps the terms sum to
        std::vector<double> sum(side * side, 0.0);
        for (size_t t = 0; t < f.terms.size(); ++t)
            for (int y = 0; y < side; ++y)
                for (int x = 0; x < side; ++x)
                    sum[y * side + x] += f.signs[t] * double(f.vertical_terms[t][y]) * f.terms[t][x];
        return sum;
    };
    double energy = 0;
    for (double t : taps) energy += t * t;
    const SeparableFilter every = separable_approximation(taps, r, 0.0);
    CHECK(every.terms.size() == size_t(side));
    const std::vector<double> back = applied(every);
    for (int i = 0; i < side * side; ++i) CHECK(back[i] == Approx(taps[i]).margin(1e-5));
    for (double fraction : {0.3, 0.05, 1e-3}) {
        const SeparableFilter some = separable_approximation(taps, r, fraction);
        const std::vector<double> sum = applied(some);
        double left = 0;
        for (int i = 0; i < side * side; ++i) left += (sum[i] - taps[i]) * (sum[i] - taps[i]);
        INFO(fraction << ": " << some.terms.size() << " terms");
        CHECK(left <= fraction * energy * (1 + 1e-4));
        CHECK(some.terms.size() < size_t(side));
        // One term fewer would not do: the largest terms but the last kept leave out more.
        SeparableFilter fewer = every;
        fewer.terms.resize(some.terms.size() - 1);
        fewer.vertical_terms.resize(some.terms.size() - 1);
        fewer.signs.resize(some.terms.size() - 1);
        const std::vector<double> fewer_sum = applied(fewer);
        double fewer_left = 0;
        for (int i = 0; i < side * side; ++i) fewer_left += (fewer_sum[i] - taps[i]) * (fewer_sum[i] - taps[i]);
        CHECK(fewer_left > fraction * energy);
    }
    std::vector<double> outer(side * side);
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) outer[y * side + x] = (1.0 + x) * (2.0 - 0.5 * y);
    const SeparableFilter one = separable_approximation(outer, r, 1e-12);
    CHECK(one.terms.size() == 1);
    const std::vector<double> outer_back = applied(one);
    for (int i = 0; i < side * side; ++i) CHECK(outer_back[i] == Approx(outer[i]).epsilon(1e-5));
}

// Three planes of width x height uniform random values.
static std::vector<std::vector<float>> random_planes(int width, int height, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<std::vector<float>> planes(3, std::vector<float>(size_t(width) * height));
    for (auto& plane : planes)
        for (float& v : plane) v = u(rng);
    return planes;
}

TEST_CASE("a separable stream gives the same rows however many it sums at once, wherever it starts and stops",
          "[scatter][filters]") {
    const int width = 37, height = 29;
    const std::vector<std::vector<float>> image = random_planes(width, height, 11);
    // Three planes: two 7-tap terms (symmetric, and not) with a centre; a 3-tap term; the identity.
    const std::vector<float> three = {0.25f, 0.5f, 0.25f};
    const std::vector<SeparableFilter> filters = {
        SeparableFilter{{{0.02f, 0.08f, 0.2f, 0.4f, 0.2f, 0.08f, 0.02f}, {0.1f, 0, 0.3f, 0.4f, 0.2f, 0, 0}}, {1.0f, -1.0f}, 0.25f},
        SeparableFilter{{three}, {1.0f}}, SeparableFilter{}};
    auto stream_rows = [&](int together, int first, int last, int step) {
        std::vector<std::vector<float>> rows;  // rows first, first + step, ... below last, three planes each
        SeparableStream s(width, filters, 0, height, last, [&](int y, float* const* padded) {
            for (int p = 0; p < 3; ++p) {
                for (int x = 0; x < width; ++x) padded[p][x + 3] = image[p][size_t(y) * width + x];
                hold_frame_edges(padded[p], -3, width + 3, Window{0, 0, width, height});
            }
        }, together);
        for (int y = first; y < last; y += step) {
            float* const* r = s.row(y);
            for (int p = 0; p < 3; ++p) rows.emplace_back(r[p], r[p] + width);
        }
        return rows;
    };
    for (int first : {0, 5})
        for (int last : {height, 18, 19})  // (at 19, from 0 or 5, a last group of three: two rows and one)
            for (int step : {1, 3}) {
                INFO("rows " << first << " to " << last << " step " << step);
                const auto one_at_a_time = stream_rows(1, first, last, step);
                CHECK(stream_rows(2, first, last, step) == one_at_a_time);
                CHECK(stream_rows(4, first, last, step) == one_at_a_time);
                // The definitions on the first row: the 3-tap plane's sum (rows and columns clamped
                // to the frame), the identity's input.
                for (int x = 0; x < width; ++x) {
                    double sum = 0;
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx)
                            sum += double(three[dy + 1]) * three[dx + 1] *
                                   image[1][size_t(std::clamp(first + dy, 0, height - 1)) * width + std::clamp(x + dx, 0, width - 1)];
                    CHECK(one_at_a_time[1][x] == Approx(sum).margin(1e-6));
                    CHECK(one_at_a_time[2][x] == image[2][size_t(first) * width + x]);
                }
            }
    CHECK_THROWS_AS(SeparableStream(width, filters, 0, height, height, [](int, float* const*) {}, 5),
                    std::invalid_argument);
}

TEST_CASE("a separable stream's rows stay as given for as many rows as it keeps", "[scatter][filters]") {
    const int width = 23, height = 31;
    const std::vector<std::vector<float>> image = random_planes(width, height, 12);
    // A 5-tap term with a centre, a 3-tap term, the identity (whose rows are its input rows).
    const std::vector<SeparableFilter> filters = {
        SeparableFilter{{{0.1f, 0.2f, 0.4f, 0.2f, 0.1f}}, {1.0f}, 0.5f},
        SeparableFilter{{{0.25f, 0.5f, 0.25f}}, {1.0f}}, SeparableFilter{}};
    auto source = [&](int y, float* const* padded) {
        for (int p = 0; p < 3; ++p) {
            for (int x = 0; x < width; ++x) padded[p][x + 2] = image[p][size_t(y) * width + x];
            hold_frame_edges(padded[p], -2, width + 2, Window{0, 0, width, height});
        }
    };
    // Each row as a stream that keeps none gives it, at once.
    std::vector<std::vector<float>> expected;
    SeparableStream plain(width, filters, 0, height, height, source);
    for (int y = 0; y < height; ++y) {
        float* const* r = plain.row(y);
        for (int p = 0; p < 3; ++p) expected.emplace_back(r[p], r[p] + width);
    }
    for (int together : {1, 2, 4})
        for (int kept : {1, 6, 11}) {
            INFO(together << " rows together, " << kept << " kept");
            SeparableStream s(width, filters, 0, height, height, source, together, kept);
            std::vector<std::vector<float*>> given;  // each row's planes, as the stream gave them
            for (int y = 0; y < height; ++y) {
                float* const* r = s.row(y);
                given.emplace_back(r, r + 3);
                // Every row asked for from kept - 1 rows back is still as it was given.
                for (int back = std::max(0, y - kept + 1); back <= y; ++back)
                    for (int p = 0; p < 3; ++p)
                        CHECK(std::vector<float>(given[size_t(back)][size_t(p)], given[size_t(back)][size_t(p)] + width) ==
                              expected[size_t(back) * 3 + size_t(p)]);
            }
        }
}

TEST_CASE("the radix-2 FFT is the DFT up to rounding, and its inverse undoes it", "[scatter][fft]") {
    const int n = 128;
    std::mt19937 random(3);
    std::uniform_real_distribution<double> uniform(-1, 1);
    std::vector<std::complex<double>> x(n), transformed;
    for (auto& v : x) v = {uniform(random), uniform(random)};
    transformed = x;
    Fft fft(n);
    fft.forward(transformed.data());
    double worst = 0;
    for (int k = 0; k < n; ++k) {
        std::complex<double> sum = 0;
        for (int j = 0; j < n; ++j) sum += x[size_t(j)] * std::polar(1.0, -2.0 * M_PI * double((long long)j * k % n) / n);
        worst = std::max(worst, std::abs(sum - transformed[size_t(k)]));
    }
    CHECK(worst < 1e-12);  // values up to sqrt(2) x n: about 100 roundings of 1e-16 x 180
    fft.inverse(transformed.data());
    worst = 0;
    for (int j = 0; j < n; ++j) worst = std::max(worst, std::abs(transformed[size_t(j)] / double(n) - x[size_t(j)]));
    CHECK(worst < 1e-14);
    CHECK_THROWS_WITH(Fft(96), Catch::Contains("not a power of two"));
}

TEST_CASE("a kernel summed by FFT gives the direct 2D sum's pixels up to rounding, the frame's bits in any window",
          "[scatter][fft]") {
    // An asymmetric kernel, so that a flipped or shifted tap would show; wide enough for the FFT.
    const int r = kMinFftRadius + 4, side = 2 * r + 1;
    ScatterKernel k;
    k.radius = r;
    std::mt19937 random(9);
    std::uniform_real_distribution<float> uniform(0, 1);
    for (int i = 0; i < side * side; ++i) k.taps.push_back(uniform(random) / float(side * side));
    // A frame of several tiles (88 px at this radius: a 128 px grid less 2r), edges clamped.
    const Window frame{-30, 7, 290, 260};
    Plane src(frame), fft(frame), direct(frame);
    for (int y = frame.y0; y < frame.y1; ++y)
        for (int x = frame.x0; x < frame.x1; ++x) src.at(x, y) = float(std::abs(x / 7 + y / 5) % 3) + 0.1f * float((x + 40) % 11);
    scatter(src, fft, k, frame, 2);
    scatter_direct(src, direct, k, frame, 2);
    double worst = 0;
    for (size_t i = 0; i < src.pixels.size(); ++i)
        worst = std::max(worst, double(std::abs(fft.pixels[i] - direct.pixels[i])) / std::abs(direct.pixels[i]));
    CHECK(worst <= 3e-7);  // two float roundings (the outputs are about 1.5)
    // Windows that cut tiles (of the grid [0, 88) + 88 k), at the frame's edges and inside
    // it, one pixel, rows and columns: each pixel is the frame's bits, from the input window
    // that scatter_input_window names (the tiles' whole grids), and from no less.
    for (const Window& window : {Window{-5, 7, 240, 230}, Window{100, 100, 101, 101}, Window{200, 210, 230, 260},
                                 Window{-30, 150, 290, 151}, Window{215, 7, 217, 260}}) {
        const Window input = scatter_input_window(k, window, frame);
        CHECK(input.contains(window.grown(r).intersected(frame)));
        Plane needed(input), part(window);
        for (int y = input.y0; y < input.y1; ++y)
            for (int x = input.x0; x < input.x1; ++x) needed.at(x, y) = src.at(x, y);
        scatter(needed, part, k, frame, 3);
        for (int y = window.y0; y < window.y1; ++y)
            for (int x = window.x0; x < window.x1; ++x) REQUIRE(part.at(x, y) == fft.at(x, y));
        // Each cuts a tile: only the kernel's reach around it would cut the tile's grid.
        const Plane reach(window.grown(r).intersected(frame));
        CHECK_THROWS_WITH(scatter(reach, part, k, frame, 1), Catch::Contains("does not cover the FFT tiles"));
    }
    // A value that is not finite stays where the direct sum puts it (the FFT would spread it).
    src.at(100, 100) = NAN;
    scatter(src, fft, k, frame, 2);
    scatter_direct(src, direct, k, frame, 2);
    CHECK(std::isnan(fft.at(100 + r, 100)));
    CHECK(fft.at(101 + r, 100) == direct.at(101 + r, 100));
}
