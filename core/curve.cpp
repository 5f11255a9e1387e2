#include "core/curve.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace darkroom {

// (Inline: in operator(), whose hi is 0, the walk is left out.)
inline double Curve::at_from(double at, size_t& hi) const {
    if (!(at > x.front())) return y.front();  // also catches NaN: held at the low end
    if (at >= x.back()) return y.back();
    // The upper bound: the first node past `at` (there is one, and it is not the first).
    if (hi == 0) {
        hi = size_t(std::upper_bound(x.begin(), x.end(), at) - x.begin());
    } else {
        while (x[hi] <= at) ++hi;
        while (x[hi - 1] > at) --hi;
    }
    size_t lo = hi - 1;
    double t = (at - x[lo]) / (x[hi] - x[lo]);
    return y[lo] + t * (y[hi] - y[lo]);
}

double Curve::operator()(double at) const {
    size_t hi = 0;
    return at_from(at, hi);
}

void Curve::row(const double* at, double* out, int n) const {
    size_t hi = 0;
    for (int i = 0; i < n; ++i) out[i] = at_from(at[i], hi);
}

double Curve::y_min() const { return *std::min_element(y.begin(), y.end()); }
double Curve::y_max() const { return *std::max_element(y.begin(), y.end()); }

bool Curve::first_x_at(double target, double* at) const {
    if (y.front() >= target) {
        *at = x.front();
        return true;
    }
    for (size_t i = 1; i < x.size(); ++i) {
        if (y[i] >= target) {
            double t = (target - y[i - 1]) / (y[i] - y[i - 1]);
            *at = x[i - 1] + t * (x[i] - x[i - 1]);
            return true;
        }
    }
    return false;
}

bool Curve::first_x_down_to(double target, double* at) const {
    Curve mirrored{x, y};
    for (double& v : mirrored.y) v = -v;
    return mirrored.first_x_at(-target, at);
}

Curve make_curve(std::vector<double> x, std::vector<double> y, const std::string& what) {
    if (x.size() != y.size())
        throw std::invalid_argument(what + ": " + std::to_string(x.size()) + " x values but " +
                                    std::to_string(y.size()) + " y values");
    if (x.empty()) throw std::invalid_argument(what + ": no samples");
    for (size_t i = 0; i < x.size(); ++i)
        if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
            throw std::invalid_argument(what + ": sample " + std::to_string(i) + " is not a finite number");
    std::vector<size_t> order(x.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return x[a] < x[b]; });
    Curve c;
    for (size_t i = 0; i < order.size();) {
        size_t j = i;
        double sum = 0;
        while (j < order.size() && x[order[j]] == x[order[i]]) sum += y[order[j++]];
        c.x.push_back(x[order[i]]);
        c.y.push_back(sum / double(j - i));
        i = j;
    }
    if (c.x.size() == 1) {  // a single sample is a constant function
        c.x.push_back(c.x[0] + 1.0);
        c.y.push_back(c.y[0]);
    }
    return c;
}

std::vector<double> nearest_non_decreasing(const std::vector<double>& y) {
    struct Block {
        double sum;
        size_t count;
        double mean() const { return sum / double(count); }
    };
    std::vector<Block> blocks;
    for (double v : y) {
        blocks.push_back({v, 1});
        while (blocks.size() > 1 && blocks[blocks.size() - 2].mean() > blocks.back().mean()) {
            Block last = blocks.back();
            blocks.pop_back();
            blocks.back().sum += last.sum;
            blocks.back().count += last.count;
        }
    }
    std::vector<double> fit;
    for (const Block& b : blocks) fit.insert(fit.end(), b.count, b.mean());
    return fit;
}

static double softplus(double u) { return u > 30 ? u : std::log1p(std::exp(u)); }

static double parametric_density(const ParametricCurve& p, double a, double log_h) {
    double b = a + (p.d_max - p.d_min) / p.gamma;
    return p.d_min + p.toe * softplus(p.gamma * (log_h - a) / p.toe) -
           p.shoulder * softplus(p.gamma * (log_h - b) / p.shoulder);
}

Curve sample_parametric_curve(const ParametricCurve& p, double speed_point_log_h, double speed_density_over_fog,
                              double log_h_min, double log_h_max) {
    if (!(p.gamma > 0) || !(p.toe > 0) || !(p.shoulder > 0) || !(p.d_max > p.d_min + speed_density_over_fog))
        throw std::invalid_argument("parametric curve: need gamma, toe, shoulder > 0 and d_max above d_min");
    // D is increasing in a's complement: bisect on a so the speed point lands on its density.
    double target = p.d_min + speed_density_over_fog;
    double lo = speed_point_log_h - 10, hi = speed_point_log_h + 10;
    for (int i = 0; i < 200; ++i) {
        double mid = 0.5 * (lo + hi);
        (parametric_density(p, mid, speed_point_log_h) > target ? lo : hi) = mid;
    }
    double a = 0.5 * (lo + hi);
    std::vector<double> xs, ys;
    int n = (int)std::ceil((log_h_max - log_h_min) / 0.01);
    for (int i = 0; i <= n; ++i) {
        double x = log_h_min + (log_h_max - log_h_min) * i / n;
        xs.push_back(x);
        ys.push_back(parametric_density(p, a, x));
    }
    return make_curve(xs, ys, "parametric curve");
}

}  // namespace darkroom
