#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "core/curve.h"

using namespace darkroom;

TEST_CASE("curves interpolate linearly between samples and hold their ends", "[curve]") {
    Curve c = make_curve({0, 1, 3}, {0.2, 1.2, 2.2}, "c");
    CHECK(c(0.5) == Approx(0.7));
    CHECK(c(2.0) == Approx(1.7));
    CHECK(c(-5) == Approx(0.2));
    CHECK(c(10) == Approx(2.2));
    CHECK(c(std::nan("")) == Approx(0.2));
    CHECK(c(-INFINITY) == Approx(0.2));
    CHECK(c(INFINITY) == Approx(2.2));
}

TEST_CASE("a curve's row of values is its value at each, bit for bit, the values in any order (the print table's)",
          "[curve][tables]") {
    // The row walks from one value's segment to the next's; each value alone is found by a
    // binary search. Rows falling (as the print table's), rising, jumping at random, on the
    // nodes themselves, past the ends and NaN, on a curve of 601 samples.
    ParametricCurve p;
    const Curve c = sample_parametric_curve(p, -2.0, 0.2, -5.0, 1.0);
    REQUIRE(c.x.size() > 500);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-5.5, 1.5);
    std::vector<double> at;
    for (int i = 0; i < 400; ++i) at.push_back(1.5 - 7.0 * i / 399);
    for (int i = 0; i < 400; ++i) at.push_back(-5.5 + 7.0 * i / 399);
    for (int i = 0; i < 2000; ++i) at.push_back(u(rng));
    for (size_t i = 0; i < c.x.size(); i += 7) at.push_back(c.x[i]);
    for (size_t i = c.x.size(); i-- > 0;) at.push_back(c.x[i]);
    for (double v : {-double(INFINITY), double(INFINITY), double(NAN), -1.0, double(NAN), -1.0001}) at.push_back(v);
    std::vector<double> row(at.size());
    c.row(at.data(), row.data(), int(at.size()));
    int differing = 0;
    for (size_t i = 0; i < at.size(); ++i) {
        const double one = c(at[i]);
        differing += std::memcmp(&one, &row[i], sizeof one) != 0;
    }
    CHECK(differing == 0);
}

TEST_CASE("unsorted samples are sorted and duplicate x merged", "[curve]") {
    Curve c = make_curve({3, 0, 1, 1}, {2.2, 0.2, 1.0, 1.4}, "c");
    REQUIRE(c.x == std::vector<double>{0, 1, 3});
    CHECK(c.y[1] == Approx(1.2));
}

TEST_CASE("degenerate curves: a single sample is constant and bad samples are rejected", "[curve]") {
    Curve one = make_curve({1.0}, {0.7}, "c");
    CHECK(one(-3) == 0.7);
    CHECK(one(9) == 0.7);
    CHECK_THROWS_WITH(make_curve({}, {}, "density_curve"), Catch::Contains("density_curve") && Catch::Contains("no samples"));
    CHECK_THROWS_WITH(make_curve({0, NAN}, {1, 2}, "c"), Catch::Contains("not a finite number"));
    CHECK_THROWS_WITH(make_curve({0, 1}, {1}, "c"), Catch::Contains("2 x values but 1 y values"));
}

TEST_CASE("first_x_at finds the first crossing of a non-monotonic curve", "[curve]") {
    Curve c = make_curve({0, 1, 2, 3}, {0, 2, 1, 3}, "c");
    double at;
    REQUIRE(c.first_x_at(1.0, &at));
    CHECK(at == Approx(0.5));
    CHECK_FALSE(c.first_x_at(5.0, &at));
}

TEST_CASE("parametric curve: speed point, straight-line slope and limits", "[curve]") {
    ParametricCurve p{0.6, 0.25, 2.4, 0.1, 0.15};
    const double speed_log_h = std::log10(0.8 / 400.0);
    Curve c = sample_parametric_curve(p, speed_log_h, 0.1, speed_log_h - 3, speed_log_h + 8);
    CHECK(c(speed_log_h) == Approx(0.35).margin(1e-3));  // 0.1 over base+fog at the ISO speed point
    CHECK(c(speed_log_h - 3) == Approx(0.25).margin(1e-3));
    CHECK(c(speed_log_h + 8) == Approx(2.4).margin(1e-3));
    // In the middle of the straight part the slope is gamma.
    double mid = speed_log_h + 0.5 * (2.15 / 0.6);
    CHECK((c(mid + 0.1) - c(mid - 0.1)) / 0.2 == Approx(0.6).epsilon(0.01));
}

TEST_CASE("nearest_non_decreasing is the isotonic least-squares fit", "[curve]") {
    // Closed forms: a falling pair pools to its mean; a pooled block that still falls
    // against the one before pools with it too.
    using V = std::vector<double>;
    CHECK(nearest_non_decreasing(V{1, 3, 2, 4}) == V{1, 2.5, 2.5, 4});
    CHECK(nearest_non_decreasing(V{3, 2, 1}) == V{2, 2, 2});
    CHECK(nearest_non_decreasing(V{0, 4, 3, 0.5, 5}) == V{0, 2.5, 2.5, 2.5, 5});
    CHECK(nearest_non_decreasing(V{0, 1, 1, 2}) == V{0, 1, 1, 2});  // already rising: unchanged
    CHECK(nearest_non_decreasing(V{}).empty());
    // Least squares: no non-decreasing sequence on a grid around the fit is closer.
    const V y{0.2, 0.5, 0.45, 0.9, 0.85, 0.8, 1.4};
    const V fit = nearest_non_decreasing(y);
    auto distance = [&](const V& v) {
        double d = 0;
        for (size_t i = 0; i < y.size(); ++i) d += (v[i] - y[i]) * (v[i] - y[i]);
        return d;
    };
    for (size_t i = 1; i < fit.size(); ++i) REQUIRE(fit[i] >= fit[i - 1]);
    for (size_t i = 0; i < fit.size(); ++i)
        for (double step : {-0.01, 0.01}) {
            V moved = fit;
            moved[i] += step;
            if (std::is_sorted(moved.begin(), moved.end())) CHECK(distance(moved) > distance(fit));
        }
}
