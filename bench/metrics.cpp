#include "bench/metrics.h"

#include <chrono>
#include <cmath>
#include <complex>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "core/parallel.h"
#include "core/spectral.h"

namespace darkroom::bench {

namespace {

Lab rec709_to_lab(const float* rgb, const Xyz& white) {
    return xyz_to_lab(linear_srgb_to_xyz({double(rgb[0]), double(rgb[1]), double(rgb[2])}), white);
}

void require_cover(const ConstImageView& test, const ConstImageView& reference) {
    if (!reference.window.contains(test.window) || test.channels < 3 || reference.channels < 3)
        throw std::invalid_argument("benchmark: the reference render does not cover the tested window in RGB");
}

}  // namespace

ColourError colour_error(const ConstImageView& test, const ConstImageView& reference) {
    require_cover(test, reference);
    const Xyz white = linear_srgb_to_xyz({1.0, 1.0, 1.0});
    ColourError e;
    double sum = 0;
    for (int y = test.window.y0; y < test.window.y1; ++y)
        for (int x = test.window.x0; x < test.window.x1; ++x) {
            double de = ciede2000(rec709_to_lab(test.at(x, y), white), rec709_to_lab(reference.at(x, y), white));
            sum += de;
            e.max = std::max(e.max, de);
            ++e.pixels;
        }
    e.mean = e.pixels ? sum / e.pixels : 0.0;
    return e;
}

double max_abs_difference(const ConstImageView& test, const ConstImageView& reference) {
    require_cover(test, reference);
    double worst = 0;
    for (int y = test.window.y0; y < test.window.y1; ++y)
        for (int x = test.window.x0; x < test.window.x1; ++x)
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, std::abs(double(test.at(x, y)[c]) - double(reference.at(x, y)[c])));
    return worst;
}

double sine_amplitude(const std::vector<double>& samples, double cycles_per_px, double phase_offset_px) {
    const int periods = int(std::floor(samples.size() * cycles_per_px + 1e-9));
    if (periods < 1) throw std::invalid_argument("sine_amplitude: fewer samples than one period");
    const int n = std::min<int>(samples.size(), int(std::lround(periods / cycles_per_px)));
    double mean = 0;
    for (int i = 0; i < n; ++i) mean += samples[i] / n;
    std::complex<double> acc = 0;
    for (int i = 0; i < n; ++i)
        acc += (samples[i] - mean) * std::polar(1.0, -2 * M_PI * cycles_per_px * (i + 0.5 + phase_offset_px));
    return 2.0 * std::abs(acc) / n;
}

double copy_pass_seconds(const ConstImageView& src, const ImageView& dst, int threads) {
    if (!(src.window == dst.window) || src.channels < 3 || dst.channels < 3)
        throw std::invalid_argument("copy pass: source and destination differ in window or channels");
    const Window w = src.window;
    auto start = std::chrono::steady_clock::now();
    parallel_for(w.y0, w.y1, threads, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = w.x0; x < w.x1; ++x) {
                const float* s = src.at(x, y);
                float* d = dst.at(x, y);
                d[0] = s[0], d[1] = s[1], d[2] = s[2];
            }
    });
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<bool> pareto_optimal(const std::vector<std::pair<double, double>>& points) {
    std::vector<bool> optimal(points.size(), true);
    for (size_t i = 0; i < points.size(); ++i)
        for (const auto& other : points) {
            bool no_worse = other.first <= points[i].first && other.second <= points[i].second;
            bool better = other.first < points[i].first || other.second < points[i].second;
            if (no_worse && better) optimal[i] = false;
        }
    return optimal;
}

Machine describe_machine() {
    Machine m{"unknown", int(std::thread::hardware_concurrency())};
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);)
        if (line.rfind("model name", 0) == 0) {
            size_t colon = line.find(':');
            if (colon != std::string::npos) m.cpu = line.substr(line.find_first_not_of(' ', colon + 1));
            break;
        }
    return m;
}

}  // namespace darkroom::bench
