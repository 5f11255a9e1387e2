#include "core/stages/grain.h"

#include <cmath>
#include <map>
#include <mutex>

#include "core/parallel.h"
#include "core/stages/filters.h"

namespace darkroom {

namespace {

double aperture_integral(double s_um, double d_um) {
    // Integrand in u = pi d f: the aperture term [2 J1(u)/u]^2 decays as u^-3, so integrate to
    // u_max and add the tail's mean (4/(pi u^3)) analytically, damped by the grain spectrum.
    const double u_max = 600.0;
    const int steps = 120000;
    auto integrand = [&](double u) {
        double f = u / (M_PI * d_um);
        double airy = u < 1e-8 ? 1.0 : 2.0 * std::cyl_bessel_j(1.0, u) / u;
        return 2.0 * M_PI * f * std::exp(-4.0 * M_PI * M_PI * s_um * s_um * f * f) * airy * airy / (M_PI * d_um);
    };
    double sum = 0.5 * (integrand(0) + integrand(u_max));
    for (int i = 1; i < steps; ++i) sum += integrand(u_max * i / steps);
    sum *= u_max / steps;
    double f_max = u_max / (M_PI * d_um);
    double tail = 8.0 / (M_PI * M_PI * M_PI * d_um * d_um * d_um * f_max);
    sum += tail * std::exp(-4.0 * M_PI * M_PI * s_um * s_um * f_max * f_max);
    return std::sqrt(sum);
}

}  // namespace

// The integral takes about a second (Bessel functions on a fine grid) and every plan of
// every frame needs it for the same few grain sizes: computed once per (size, aperture).
double aperture_rms_per_unit_noise(double s_um, double d_um) {
    static std::mutex mutex;
    static std::map<std::pair<double, double>, double> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto key = std::make_pair(s_um, d_um);
    auto it = cache.find(key);
    if (it == cache.end()) it = cache.emplace(key, aperture_integral(s_um, d_um)).first;
    return it->second;
}

bool GrainModel::is_noop() const { return pixel_sigma_at_unit_density() < kNoOpSigma; }

double GrainModel::pixel_sigma_at_unit_density() const {
    double k2 = 0;
    for (float k : kernel) k2 += double(k) * k;
    return sigma_per_pixel * k2;  // separable: sum over the 2D kernel of k^2 = (sum k1^2)^2
}

GrainModel design_grain(const GrainSpec& spec, double d_min, double pitch_um, NoiseKey key) {
    GrainModel g;
    g.d_min = float(d_min);
    g.density_exponent = spec.density_exponent;
    g.key = key;
    double unit_noise_sigma48 = aperture_rms_per_unit_noise(spec.grain_size_um, kGranularityApertureUm);
    g.sigma_per_pixel = spec.rms_granularity / unit_noise_sigma48 / pitch_um;
    // Gaussian of std s/pitch pixels, integrated over each pixel's extent.
    g.kernel = pixel_integrated_gaussian(spec.grain_size_um / pitch_um);
    g.radius = int(g.kernel.size() / 2);
    return g;
}

Plane grain_field(const GrainModel& g, const Window& w, int threads) {
    const int r = g.radius, side = 2 * r + 1;
    // Horizontal pass over the rows the vertical pass needs, then vertical. Each filtered
    // value is summed in a fixed order from noise at absolute coordinates.
    Window hw{w.x0, w.y0 - r, w.x1, w.y1 + r};
    Plane horizontal(hw), field(w);
    parallel_for(hw.y0, hw.y1, threads, [&](int y_begin, int y_end) {
        std::vector<float> noise(w.width() + 2 * r);
        for (int y = y_begin; y < y_end; ++y) {
            for (int i = 0; i < (int)noise.size(); ++i) noise[i] = standard_normal(g.key, w.x0 - r + i, y);
            float* out = horizontal.row(y);
            for (int x = 0; x < w.width(); ++x) {
                double acc = 0;
                for (int k = 0; k < side; ++k) acc += double(g.kernel[k]) * noise[x + k];
                out[x] = float(acc);
            }
        }
    });
    parallel_for(w.y0, w.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            float* out = field.row(y);
            for (int x = 0; x < w.width(); ++x) {
                double acc = 0;
                for (int k = 0; k < side; ++k) acc += double(g.kernel[k]) * horizontal.row(y - r + k)[x];
                out[x] = float(acc);
            }
        }
    });
    return field;
}

double grain_sigma_at(const GrainModel& g, double density) {
    double net = std::max(0.0, density - g.d_min);
    return g.pixel_sigma_at_unit_density() * std::pow(net, g.density_exponent);
}

void apply_grain(Plane& density, const GrainModel& g, int threads) {
    const Plane field = grain_field(g, density.window, threads);
    parallel_for(density.window.y0, density.window.y1, threads, [&](int y_begin, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            float* d = density.row(y);
            const float* n = field.row(y);
            for (int x = 0; x < density.window.width(); ++x) {
                double net = std::max(0.0, double(d[x]) - g.d_min);
                // Held at d_min: a Gaussian fluctuation wider than the net density would
                // otherwise take away more silver (or dye) than developed, giving densities
                // below base+fog or below 0 (transmitting or reflecting more than falls on it).
                d[x] = float(std::max(double(g.d_min), d[x] + g.sigma_per_pixel * std::pow(net, g.density_exponent) * n[x]));
            }
        }
    });
}

}  // namespace darkroom
