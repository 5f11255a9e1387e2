// `darkroom bench`: run time against error for every quality tier (core/quality.h).
//
// Timing: each tier develops the whole frame (the demo scene, core/demo_scene.h) through
// the look (film to print, grain, MTF and halation on; at the pixel pitch of a 4096 px
// wide frame whatever the size, so a smaller frame is a piece of the benchmark's frame), one warm-up run then `runs` timed
// runs, the fastest kept with its per-stage times (Plan::run's StageTimes). A plain copy
// of the same float RGB buffer on the same threads is timed in the same run, so every
// time is also a multiple of the copy (its fastest of 20 runs, timed in turn with the fast
// tier's frame runs where that tier is benchmarked: in the same moments as the target's
// frame, on a machine whose speed drifts). By default the reference tier renders only the
// sample windows (a window equals that window of the full frame) and its frame time is
// extrapolated from them by pixel count, between bounds (each window also computes its
// halo); with whole_frame it renders the frame (minutes at 1024x683).
//
// Errors against the reference tier, on the sample windows of the same frame (or the whole
// frame):
// - print colour: mean and max CIEDE2000, grain off in both (grain realisations differ
//   between tiers, so per-pixel colour is compared without it);
// - negative: max |density difference| of the density output, grain off;
// - MTF: sine targets at the frame's pixel pitch on the density output (grain and
//   halation off), read back to exposure through the layer's H&D curve; the error is the
//   largest |MTF - reference MTF| over layers and frequencies up to Nyquist;
// - grain: a wedge of flat patches with grain on, each tier's density analysed by the
//   plate-matching analysis (core/plate/grain_analysis.h) and compared with the
//   reference's (core/plate/grain_compare.h). The reference is also compared with itself
//   under another seed: that is the measurement's noise floor. With print_grain, the same
//   wedge printed as well, each channel of the print read as a density (what a plate
//   scanned from the print shows).
// Disabled stages: the fast tier again with grain, MTF, halation and DIR couplers off in turn, each left
// out of the plan and, for comparison, kept in it at its neutral value. Then the fast tier
// stage after stage and at each narrower instruction set the processor runs. Then its edit
// latency: one setting changed at a time (EditLatency).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "bench/metrics.h"
#include "core/develop.h"
#include "core/plate/grain_compare.h"
#include "core/quality.h"

namespace darkroom::bench {

struct BenchOptions {
    int width = 4096, height = 2160;  // the benchmark's frame
    int threads = 0;                  // 0 = all cores
    std::vector<Quality> tiers{std::begin(kQualities), std::end(kQualities)};  // reference is always run
    int runs = 3;                     // timed whole-frame runs after one warm-up; the fastest is kept
    int sample_windows = 4;           // along the frame's diagonal, one per band of the demo scene
    int sample_window_px = 128;
    // The reference on the whole frame instead (timed, not extrapolated), and every tier's
    // errors measured on it: one window, the frame.
    bool whole_frame = false;
    // Also the print's grain (measure_wedge_grain with the paper): the reference's paper grain
    // makes its two prints of the wedge take minutes, so only when asked.
    bool print_grain = false;
    uint64_t seed = 0;
    std::function<void(const std::string&)> progress;  // told what runs next (may be empty)
};

struct StageTime {
    std::string stage;
    double seconds = 0;
};

struct GrainErrors {
    bool measured = false;
    std::string problem;  // why not, when not measured
    double response_percent = 0, nps_db = 0, correlation = 0;  // worst channel
    bool within(const GrainMatchTolerance& t) const {
        return measured && response_percent <= t.response_percent && nps_db <= t.nps_db &&
               correlation <= t.correlation;
    }
};

struct TierResult {
    Quality quality = Quality::high;
    std::string name;
    double compile_seconds = 0;
    double seconds = 0;        // the whole frame's develop time (extrapolated when flagged)
    bool extrapolated = false;
    // When extrapolated: `seconds` scales the windows' time by frame pixels / window pixels
    // (an upper bound: the windows also compute their halos); this one by frame pixels /
    // the pixels of the windows with their halos (a lower bound).
    double extrapolated_lower_seconds = 0;
    std::vector<StageTime> stages;
    ColourError print_error;   // CIEDE2000 against the reference, grain off
    double density_error = 0;  // max |D - D_reference| of the negative, grain off
    double mtf_error = 0;      // max |MTF - MTF_reference|
    std::vector<std::vector<double>> mtf;  // measured, per layer per frequency
    GrainErrors grain;         // against the reference (for the reference: another seed)
    GrainErrors print_grain;   // the same for the printed wedge, when asked (BenchOptions::print_grain)
    bool pareto_optimal = false;  // in (seconds, mean print CIEDE2000) among the tiers run
};

// The fast tier with one stage turned off.
struct DisabledStage {
    std::string stage;         // as StageTimes names it
    double seconds = 0;
    std::vector<StageTime> stages;
    // The fast tier's full run is timed again in turn with this one (a run of each per round,
    // and of the neutral one below), so that what is saved is measured in the same moments:
    double stage_seconds_when_on = 0;  // that stage's time in that full run (grain: its share of develop + grain)
    double saved_seconds = 0;          // that full run less this one
    // The same settings with the stage kept in the plan at its neutral value
    // (PlanStructure::skip_noop_stages = false): what leaving it out saves, and whether
    // the two give the same pixels (they must).
    double neutral_seconds = 0;
    bool identical_pixels = false;
};

// The fast tier's frame run another way: stage after stage over whole planes
// (PlanStructure::one_pass = false), or at narrower vectors (core/simd.h): what one pass and
// wide vectors save; the pixels must be the fast tier's own.
struct RunVariant {
    std::string way;
    double seconds = 0;
    bool identical_pixels = false;
};

// Edit latency: the fast tier's time to compile and develop the frame after one setting of
// the look changed (a slider dragged in a host), against compiling the same look again and
// developing it (the steady re-render), timed in turn, each round another value.
struct EditLatency {
    std::string setting;
    double seconds = 0;  // fastest of the rounds
};

struct TargetCheck {
    bool evaluated = false;    // the fast tier was benchmarked
    double max_copy_ratio = 10, max_mean_de2000 = 0.5;
    double copy_ratio = 0, mean_de2000 = 0;
    bool grain_within = false;  // the negative's grain, and the print's where measured
    bool passes() const {
        return evaluated && copy_ratio <= max_copy_ratio && mean_de2000 <= max_mean_de2000 && grain_within;
    }
};

struct BenchReport {
    Machine machine;
    int threads = 0;
    int width = 0, height = 0;
    std::string film, paper;
    int runs = 0;
    int copy_runs = 0;  // the copy pass: fastest of this many after a warm-up
    double copy_seconds = 0;
    double copy_median_seconds = 0;  // (the machine's memory speed moves: the ratios use the fastest)
    // What one copy pass reads and writes: the frame's float RGB, once each.
    double copy_bytes() const { return 2.0 * double(width) * height * 3 * sizeof(float); }
    bool copy_in_turn_with_fast = false;  // timed in the rounds of the fast tier's frame runs
    std::vector<Window> sample_windows;
    double pixel_pitch_um = 0;
    std::vector<double> mtf_cycles_per_px;
    int grain_wedge_patches = 0, grain_wedge_patch_px = 0;
    bool print_grain = false;  // the printed wedge's grain measured too (BenchOptions::print_grain)
    GrainMatchTolerance grain_tolerance;
    std::vector<TierResult> tiers;  // reference first
    std::vector<DisabledStage> disabled;
    std::string isa;                  // the instruction set the tiers ran on (core/simd.h)
    std::vector<RunVariant> fast_run_variants;
    double steady_rerender_seconds = 0;  // compile the same look and develop (fastest of the rounds)
    std::vector<EditLatency> edits;
    TargetCheck target;
};

// The MTF the density output shows at the given frequencies (cycles per pixel, up to 0.5),
// per film layer, at `pitch_um` with grain, halation and DIR couplers off: one-row sine targets of
// modulation 0.1 around mid-grey exposure, read back to exposure through each layer's H&D
// curve and divided by the input's modulation measured the same way (sine_amplitude).
// `frame`: the benchmarked frame, which the target is an image of (at its origin), so that
// the preview tier's proxy factor is the frame's (quality.h); empty: the target is the frame.
std::vector<std::vector<double>> measure_density_mtf(const Stock& film, Quality quality, double pitch_um,
                                                     const std::vector<double>& cycles_per_px, int threads,
                                                     const FrameGeometry& frame = {});

// The grain of a wedge of flat square patches one stop apart around mid grey (grain on, MTF
// and halation off, so each patch is flat) at `pitch_um` on film, analysed as a plate would be
// (core/plate/grain_analysis.h): the negative's density or, with a paper, the print's, each
// channel of its linear Rec.709 read as a density, -log10 (the print at the paper's format's
// pitch for a 4096 px wide frame), seen as `viewing` says; `frame` as measure_density_mtf's.
GrainProfile measure_wedge_grain(const Stock& film, const Stock* paper, Quality quality, uint64_t seed,
                                 double pitch_um, int threads, PrintViewing viewing = PrintViewing::media_relative,
                                 const FrameGeometry& frame = {});

// Where the reference renders and every tier's colour and density errors are measured: the
// sample windows (clipped to the frame), or the whole frame.
std::vector<Window> reference_windows(const BenchOptions& options);

// Throws std::invalid_argument for unusable options or stocks.
BenchReport run_benchmark(const Stock& film, const Stock& paper, const BenchOptions& options);

}  // namespace darkroom::bench
