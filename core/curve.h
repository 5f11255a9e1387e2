// Sampled 1D functions: H&D curves (log10 H -> D), MTFs (cycles/mm -> response).
//
// A curve is a list of (x, y) samples with strictly increasing x, evaluated by linear
// interpolation as the seed paper does, and held constant beyond its ends. Curves given by
// users may be unsorted or degenerate: `make_curve` sorts, merges duplicate x (by mean),
// and rejects what cannot be a function (empty, non-finite).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace darkroom {

struct Curve {
    std::vector<double> x, y;

    double operator()(double at) const;
    // operator() of n values, bit for bit, each one's segment found by walking from the one
    // before's (the first's by a binary search): for rows of values that change little from
    // one to the next (the print table's, where the binary search was most of its build).
    void row(const double* at, double* out, int n) const;
    double x_min() const { return x.front(); }
    double x_max() const { return x.back(); }
    double y_min() const;
    double y_max() const;
    // Smallest x at which the curve reaches `target`, searching left to right; the curve
    // need not be monotonic. Returns false if it never does.
    bool first_x_at(double target, double* at) const;
    // Smallest x at which the curve falls to `target` (a reversal film's curve).
    bool first_x_down_to(double target, double* at) const;

private:
    // The curve at `at`, its segment's upper node found from `hi` (0: by a binary search), and
    // kept in `hi` for the next value.
    double at_from(double at, size_t& hi) const;
};

// Sorts and validates samples; throws std::invalid_argument naming `what` on bad data.
Curve make_curve(std::vector<double> x, std::vector<double> y, const std::string& what);

// The non-decreasing sequence nearest to y in least squares (isotonic regression by pool
// adjacent violators: each run that falls is replaced by its mean). Digitised data-sheet
// curves dip by a few 1e-4 D where the trace is flat; this removes the dips and nothing else.
std::vector<double> nearest_non_decreasing(const std::vector<double>& y);

// The parametric characteristic curve: a straight line of slope `gamma` between a toe and
// a shoulder, each rounded by a softplus of width `toe`/`shoulder` (in density units):
//   D(x) = Dmin + toe*sp(gamma*(x - a)/toe) - shoulder*sp(gamma*(x - b)/shoulder),
// sp(u) = ln(1 + e^u), b = a + (Dmax - Dmin)/gamma. It rises from Dmin to Dmax, has slope
// gamma in its straight part, and `a` is placed so that D(log10(speed_point_h)) equals
// Dmin + speed_density_over_fog: the exposure the stock's ISO speed defines.
struct ParametricCurve {
    double gamma = 0.6;
    double d_min = 0.2, d_max = 2.4;
    double toe = 0.15, shoulder = 0.2;
};

// Samples the parametric form on [log_h_min, log_h_max] (step 0.01) after anchoring it.
Curve sample_parametric_curve(const ParametricCurve& p, double speed_point_log_h, double speed_density_over_fog,
                              double log_h_min, double log_h_max);

}  // namespace darkroom
