// The benchmark's measurements, each a plain definition so that tests can check it
// against a closed form: colour and density errors between two renders of the same
// window, the response of a sampled sine (for MTF), a plain copy pass (the unit every
// time is divided by), and a description of the machine.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/image.h"

namespace darkroom::bench {

struct ColourError {
    double mean = 0, max = 0;  // CIEDE2000
    long long pixels = 0;
};

// CIEDE2000 (core/spectral.h) per pixel between two linear Rec.709 (D65) images, channels
// 0-2, over the pixels of `test`'s window (which `reference` must cover). Each colour goes
// to XYZ and to CIELAB relative to the D65 white (RGB 1, 1, 1 has L* = 100).
ColourError colour_error(const ConstImageView& test, const ConstImageView& reference);

// The largest |test - reference| over channels 0-2 and the pixels of `test`'s window.
double max_abs_difference(const ConstImageView& test, const ConstImageView& reference);

// The amplitude of the sinusoid of `cycles_per_px` in `samples` (sample i at i + 0.5 +
// phase_offset_px, the pixel centre), from its projection onto exp(-2 pi i f x) over the
// largest whole number of periods from the start, less the mean. A system's MTF at f is
// sine_amplitude(output) / sine_amplitude(input) with the same offsets (the estimator's own
// gain cancels, including at Nyquist where the projection sees only the sine's peaks).
double sine_amplitude(const std::vector<double>& samples, double cycles_per_px, double phase_offset_px = 0);

// A plain parallel copy of channels 0-2 of `src` into `dst` (same window), rows split
// over `threads` as the develop stages split them: the unit of the benchmark's times.
// Returns the seconds the copy took.
double copy_pass_seconds(const ConstImageView& src, const ImageView& dst, int threads);

// Benchmark times are also given as multiples of the copy pass.
inline double copy_ratio(double seconds, double copy_seconds) { return seconds / copy_seconds; }

// For points (seconds, error), whether each is Pareto-optimal: no other point is at least
// as fast and as accurate and strictly better in one of the two.
std::vector<bool> pareto_optimal(const std::vector<std::pair<double, double>>& seconds_error);

struct Machine {
    std::string cpu;  // model name from /proc/cpuinfo ("unknown" when not readable)
    int cores = 0;    // hardware threads the system reports
};
Machine describe_machine();

}  // namespace darkroom::bench
