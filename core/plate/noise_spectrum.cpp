#include "core/plate/noise_spectrum.h"

#include <algorithm>
#include <cmath>

namespace darkroom {

namespace {

int grid_size_for(int radius) {
    int n = 64;
    while (n < 4 * radius) n *= 2;
    return n;
}

}  // namespace

std::vector<double> power_spectrum_2d(const GrainChannel& ch, int n) {
    const int r = ch.acf_radius;
    std::vector<double> cosine(n);  // cos(2 pi k / n), indexed by k mod n
    for (int k = 0; k < n; ++k) cosine[k] = std::cos(2.0 * M_PI * k / n);
    auto wrap = [n](long long k) { return (int)(((k % n) + n) % n); };
    std::vector<double> nps((size_t)n * n, 0.0);
    for (int v = 0; v < n; ++v)
        for (int u = 0; u < n; ++u) {
            double sum = 0;
            for (int dy = -r; dy <= r; ++dy)
                for (int dx = -r; dx <= r; ++dx) sum += ch.acf(dx, dy) * cosine[wrap((long long)u * dx + (long long)v * dy)];
            nps[(size_t)v * n + u] = sum;
        }
    return nps;
}

RadialSpectrum radial_power_spectrum(const GrainChannel& ch, int n) {
    n = std::max(n, grid_size_for(ch.acf_radius));
    std::vector<double> nps = power_spectrum_2d(ch, n);
    const int bins = n / 2;
    std::vector<double> sum(bins + 1, 0.0);
    std::vector<int> count(bins + 1, 0);
    for (int v = 0; v < n; ++v)
        for (int u = 0; u < n; ++u) {
            double fu = (u <= n / 2 ? u : u - n), fv = (v <= n / 2 ? v : v - n);
            int bin = (int)std::lround(std::hypot(fu, fv));
            if (bin > bins) continue;
            sum[bin] += nps[(size_t)v * n + u];
            ++count[bin];
        }
    RadialSpectrum out;
    for (int b = 0; b <= bins; ++b) {
        out.cycles_per_px.push_back(double(b) / n);
        out.power.push_back(sum[b] / count[b]);
    }
    return out;
}

double half_power_frequency(const RadialSpectrum& s) {
    const double half = 0.5 * s.power.front();
    for (size_t i = 1; i < s.power.size(); ++i)
        if (s.power[i] <= half) {
            double t = (s.power[i - 1] - half) / (s.power[i - 1] - s.power[i]);
            return s.cycles_per_px[i - 1] + t * (s.cycles_per_px[i] - s.cycles_per_px[i - 1]);
        }
    return 0.5;
}

double noise_equivalent_area_px2(const GrainChannel& ch) {
    double sum = 0;
    for (double a : ch.autocorrelation) sum += a;
    return sum;
}

GrainKernel design_grain_kernel(const GrainChannel& ch) {
    const int r = ch.acf_radius;
    if (r == 0) return {};
    const int n = grid_size_for(r);
    std::vector<double> amplitude = power_spectrum_2d(ch, n);
    // A measured autocorrelation can give slightly negative power where the true NPS is
    // near 0; no filter has negative power, so those frequencies get none.
    for (double& a : amplitude) a = std::sqrt(std::max(a, 0.0));
    std::vector<double> cosine(n);
    for (int k = 0; k < n; ++k) cosine[k] = std::cos(2.0 * M_PI * k / n);
    auto wrap = [n](long long k) { return (int)(((k % n) + n) % n); };
    const int side = 2 * r + 1;
    std::vector<double> full((size_t)side * side);
    for (int y = -r; y <= r; ++y)
        for (int x = -r; x <= r; ++x) {
            double sum = 0;
            for (int v = 0; v < n; ++v)
                for (int u = 0; u < n; ++u)
                    sum += amplitude[(size_t)v * n + u] * cosine[wrap((long long)u * x + (long long)v * y)];
            full[(size_t)(y + r) * side + x + r] = sum / ((double)n * n);
        }
    // Energy inside each square radius; keep the smallest holding 99.999 % of it.
    double total = 0;
    for (double k : full) total += k * k;
    int keep = r;
    for (int q = 0; q < r; ++q) {
        double inside = 0;
        for (int y = -q; y <= q; ++y)
            for (int x = -q; x <= q; ++x) inside += full[(size_t)(y + r) * side + x + r] * full[(size_t)(y + r) * side + x + r];
        if (inside >= 0.99999 * total) {
            keep = q;
            break;
        }
    }
    GrainKernel kernel;
    kernel.radius = keep;
    kernel.taps.clear();
    double energy = 0;
    for (int y = -keep; y <= keep; ++y)
        for (int x = -keep; x <= keep; ++x) {
            double k = full[(size_t)(y + r) * side + x + r];
            kernel.taps.push_back(k);
            energy += k * k;
        }
    for (double& k : kernel.taps) k /= std::sqrt(energy);
    return kernel;
}

}  // namespace darkroom
