#include "bench/bench.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "core/demo_scene.h"
#include "core/simd.h"
#include "core/parallel.h"
#include "core/plate/grain_analysis.h"

namespace darkroom::bench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::vector<StageTime> stage_list(const StageTimes& t, double scale = 1.0) {
    std::vector<StageTime> out;
    for (const auto& [stage, s] : t.seconds) out.push_back({stage, s * scale});
    return out;
}

double stage_seconds(const std::vector<StageTime>& stages, const std::string& name) {
    for (const StageTime& s : stages)
        if (s.stage == name) return s.seconds;
    return 0.0;
}

// A stage's time in the fast tier's run (`on`), given the run with that stage off. Grain is
// timed with develop there when they run as one pass (kDevelopAndGrainStage): its share is
// that pass less develop's own time in the run without grain.
double stage_seconds_when_on(const std::vector<StageTime>& on, const std::vector<StageTime>& off,
                             const std::string& stage) {
    double seconds = stage_seconds(on, stage);
    const double fused = stage_seconds(on, kDevelopAndGrainStage);
    if (stage == "grain" && fused > 0) seconds += fused - stage_seconds(off, "develop");
    return seconds;
}

// The benchmark's frame is this wide; every frame size is benchmarked at its pixel pitch.
constexpr int kTargetWidthPx = 4096;

// The look the benchmark develops: film to print with grain, MTF and halation on, at the
// target frame's pixel pitch on film and paper, so a smaller --size is a piece of that
// frame (per-pixel costs and errors as at 4K), not the whole format at a coarser pitch.
DevelopSettings look(Quality q, uint64_t seed, const Stock& film, const Stock& paper, int width_px) {
    DevelopSettings s;
    s.quality = q;
    s.seed = seed;
    s.frame_width_mm = film.frame_width_mm * width_px / kTargetWidthPx;
    s.print_width_mm = paper.frame_width_mm * width_px / kTargetWidthPx;
    return s;
}

// Settings for the measurement targets, whose pixels are exposures (lux-seconds) and whose
// result is the negative's density, at the benchmarked frame's pixel pitch.
DevelopSettings density_target(Quality q, uint64_t seed, double pitch_um, int target_width_px) {
    DevelopSettings s;
    s.quality = q;
    s.seed = seed;
    s.output = OutputMode::density;
    s.input_units = InputUnits::lux_seconds;
    s.frame_width_mm = pitch_um * target_width_px / 1000.0;
    return s;
}

// A measurement target of width x height pixels as an image of `frame` at its origin (empty:
// the target is its own frame): the film frame's width sets the pitch, its size the
// preview's proxy factor.
FrameGeometry target_geometry(int width, int height, const FrameGeometry& frame) {
    if (frame.width == 0) return {width, height};
    return {width, height, false, 0, 0, frame.film_width_px(), frame.film_height_px()};
}

// Renders `window` of the frame from the full-frame input `in`.
Image render(const Plan& plan, const ConstImageView& in, const Window& window, int threads,
             StageTimes* times = nullptr) {
    Image out(window, 3);
    plan.run(in, out.view(), threads, times);
    return out;
}

// Whole-frame develops, the fastest of `runs` after a warm-up each. Several plans are run in
// turn, a run of each per round, so that times compared with each other (a stage off against
// on) are taken in the same moments of a shared machine, not minutes apart.
struct Timed {
    double seconds = 0;
    std::vector<StageTime> stages;
};
struct Timing {
    const Plan& plan;
    Image& out;
};
// The copy pass of the scene into `out`, `per_round` times at the start of each round: its
// times after the warm-up round.
struct CopyInTurn {
    Image& out;
    int per_round = 0;
    std::vector<double> seconds;
    // Into the report: the fastest, the median (how far the machine's memory speed moved
    // between moments) and how many runs.
    void report(BenchReport& r) const {
        std::vector<double> sorted = seconds;
        std::sort(sorted.begin(), sorted.end());
        const size_t n = sorted.size();
        r.copy_runs = int(n);
        r.copy_seconds = sorted.front();
        r.copy_median_seconds = n % 2 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
    }
};
std::vector<Timed> time_in_turn(const std::vector<Timing>& timings, const Image& scene, int runs, int threads,
                                CopyInTurn* copy = nullptr) {
    std::vector<Timed> best(timings.size(), Timed{INFINITY, {}});
    for (int r = 0; r <= runs; ++r) {
        for (int k = 0; copy && k < copy->per_round; ++k) {
            const double s = copy_pass_seconds(scene.view(), copy->out.view(), threads);
            if (r > 0) copy->seconds.push_back(s);
        }
        for (size_t i = 0; i < timings.size(); ++i) {
            StageTimes times;
            auto start = Clock::now();
            timings[i].plan.run(scene.view(), timings[i].out.view(), threads, &times);
            double s = seconds_since(start);
            if (r > 0 && s < best[i].seconds) best[i] = {s, stage_list(times)};
        }
    }
    return best;
}
Timed time_frame(const Plan& plan, const Image& scene, Image& out, int runs, int threads,
                 CopyInTurn* copy = nullptr) {
    return time_in_turn({{plan, out}}, scene, runs, threads, copy)[0];
}

}  // namespace

// Sample windows along the frame's diagonal, window i centred in band i of the demo scene
// (grey ramp, step wedge, fine detail, colour chart).
static std::vector<Window> sample_windows(int width, int height, int count, int side_px) {
    const int w = std::min(side_px, width), h = std::min(side_px, height);
    std::vector<Window> out;
    for (int i = 0; i < count; ++i) {
        int cx = int((i + 0.5) * width / count), cy = int((i + 0.5) * height / count);
        int x0 = std::clamp(cx - w / 2, 0, width - w), y0 = std::clamp(cy - h / 2, 0, height - h);
        out.push_back({x0, y0, x0 + w, y0 + h});
    }
    return out;
}

std::vector<Window> reference_windows(const BenchOptions& o) {
    if (o.whole_frame) return {Window{0, 0, o.width, o.height}};
    return sample_windows(o.width, o.height, o.sample_windows, o.sample_window_px);
}

namespace {

// The copy pass is cheap: timed many times, so that its fastest run is the machine's
// speed and not a moment of contention; in turn with the fast tier's frame runs where that
// tier is benchmarked (a shared machine's speed drifts over the minutes between).
constexpr int kCopyRuns = 20;

constexpr int kWedgePatches = 7, kWedgePatchPx = 128, kWedgeBlockPx = 32;

GrainErrors grain_errors(const GrainProfile& reference, const GrainProfile& test) {
    GrainErrors e;
    GrainMatch m = compare_grain_profiles(reference, test);
    e.measured = true;
    for (const ChannelMatch& c : m.channels) {
        e.response_percent = std::max(e.response_percent, c.response_error_percent);
        e.nps_db = std::max(e.nps_db, c.nps_distance_db);
    }
    e.correlation = m.max_correlation_difference;
    return e;
}

}  // namespace

GrainProfile measure_wedge_grain(const Stock& film, const Stock* paper, Quality q, uint64_t seed, double pitch_um,
                                 int threads, PrintViewing viewing, const FrameGeometry& frame) {
    const int width = kWedgePatches * kWedgePatchPx;
    const FrameGeometry geometry = target_geometry(width, kWedgePatchPx, frame);
    DevelopSettings s = density_target(q, seed, pitch_um, geometry.film_width_px());
    s.mtf = false;
    s.halation = 0;
    s.print_viewing = viewing;
    if (paper) {
        s.output = OutputMode::print;
        s.print_width_mm = paper->frame_width_mm * geometry.film_width_px() / kTargetWidthPx;
    }
    Plan plan = Plan::compile(film, paper, s, geometry, threads);
    Image wedge(width, kWedgePatchPx, 3);
    const double h0 = mid_grey_exposure_lux_s(film.iso_speed);
    for (int y = 0; y < kWedgePatchPx; ++y)
        for (int x = 0; x < width; ++x) {
            float h = float(h0 * std::exp2(x / kWedgePatchPx - kWedgePatches / 2));
            for (int c = 0; c < 3; ++c) wedge.at(x, y)[c] = h;
        }
    Image density = render(plan, wedge.view(), wedge.window, threads);
    if (paper)
        for (float& v : density.pixels) v = float(-std::log10(std::max(v, 1e-30f)));
    GrainAnalysisSettings a;
    a.channels = 3;
    a.block_size_px = kWedgeBlockPx;
    a.level_bins = kWedgePatches;
    a.threads = threads;
    return analyze_grain({density.view()}, a);
}

// MTF on the density output: one-row sine targets of modulation 0.1 around a mid-grey
// exposure (a one-row frame: rows clamp at the frame edge, so the 2D PSF acts as its line
// spread function), read back to exposure through each layer's H&D curve, measured in the
// middle half, away from the clamped ends. The frame is wide enough that the middle half
// is further than the kernel's halo from both ends.
std::vector<std::vector<double>> measure_density_mtf(const Stock& film, Quality q, double pitch_um,
                                                     const std::vector<double>& cycles_per_px, int threads,
                                                     const FrameGeometry& frame) {
    int width = 2048;
    DevelopSettings s = density_target(q, 0, pitch_um, target_geometry(width, 1, frame).film_width_px());
    s.grain = false;
    s.halation = 0;
    s.dir_couplers = 0;  // (their edge effect raises the density's modulation: the stock's MTF is optical)
    Plan plan = Plan::compile(film, nullptr, s, target_geometry(width, 1, frame), threads);
    int halo = plan.halo_px();
    if (halo >= width / 4) {
        width = 4 * ((halo / 64 + 1) * 64);
        s.frame_width_mm = pitch_um * target_geometry(width, 1, frame).film_width_px() / 1000.0;
        plan = Plan::compile(film, nullptr, s, target_geometry(width, 1, frame), threads);
    }
    const double h0 = mid_grey_exposure_lux_s(film.iso_speed), modulation = 0.1;
    const int x0 = width / 4, n = width / 2;
    std::vector<std::vector<double>> mtf(film.layers.size());
    for (double f : cycles_per_px) {
        Image target(width, 1, 3);
        std::vector<double> input(n);
        for (int x = 0; x < width; ++x) {
            double h = h0 * (1.0 + modulation * std::sin(2 * M_PI * f * (x + 0.5)));
            for (int c = 0; c < 3; ++c) target.at(x, 0)[c] = float(h);
            if (x >= x0 && x < x0 + n) input[x - x0] = double(target.at(x, 0)[0]);
        }
        const double input_modulation = sine_amplitude(input, f, x0) / h0;
        Image density = render(plan, target.view(), target.window, threads);
        for (size_t l = 0; l < film.layers.size(); ++l) {
            const Curve& curve = film.layers[l].density_curve;
            std::vector<double> exposure(n);
            double mean = 0;
            for (int i = 0; i < n; ++i) {
                double log_h;
                if (!curve.first_x_at(density.at(x0 + i, 0)[l], &log_h)) log_h = curve.x_max();
                exposure[i] = std::pow(10.0, log_h);
                mean += exposure[i] / n;
            }
            mtf[l].push_back(sine_amplitude(exposure, f, x0) / mean / input_modulation);
        }
    }
    return mtf;
}

namespace {

// Each round compiles and develops the look unchanged, then with each setting changed to a
// value no round before used (so no table it builds is kept from an earlier one).
void measure_edit_latency(const Stock& film, const Stock& paper, const DevelopSettings& look, const FrameGeometry& frame,
                          const Image& scene, int rounds, int threads, BenchReport& r) {
    using Edit = void (*)(DevelopSettings&, double);
    const std::pair<const char*, Edit> edits[] = {
        {"none (steady)", [](DevelopSettings&, double) {}},
        {"exposure", [](DevelopSettings& d, double k) { d.exposure_ev += 0.1 * k; }},
        {"print exposure", [](DevelopSettings& d, double k) { d.print_exposure_ev += 0.1 * k; }},
        {"printer lights", [](DevelopSettings& d, double k) { d.printer_lights = {25 + k, 25, 25 - k}; }},
        {"filtration", [](DevelopSettings& d, double k) { d.filtration_ymc = {10 * k, 5 * k, 0}; }},
        {"grain amount", [](DevelopSettings& d, double k) { d.grain_amount = {1 + 0.1 * k, 1 + 0.1 * k, 1 + 0.1 * k}; }},
    };
    std::vector<double> fastest(std::size(edits), 1e30);
    Image out(scene.window, 3);
    for (int round = 1; round <= rounds; ++round)
        for (size_t e = 0; e < std::size(edits); ++e) {
            DevelopSettings d = look;
            edits[e].second(d, round);
            const auto start = Clock::now();
            Plan::compile(film, &paper, d, frame, threads).run(scene.view(), out.view(), threads);
            fastest[e] = std::min(fastest[e], seconds_since(start));
        }
    r.steady_rerender_seconds = fastest[0];
    for (size_t e = 1; e < std::size(edits); ++e) r.edits.push_back({edits[e].first, fastest[e]});
}

}  // namespace

BenchReport run_benchmark(const Stock& film, const Stock& paper, const BenchOptions& o) {
    if (o.width < 16 || o.height < 16 || (long long)o.width * o.height > (1LL << 27))
        throw std::invalid_argument("benchmark frame size must be 16x16 to 134 million pixels");
    if (o.runs < 1 || o.sample_windows < 1 || o.sample_window_px < 8)
        throw std::invalid_argument("benchmark needs 1+ runs and 1+ sample windows of 8+ pixels");
    auto say = [&](const std::string& what) {
        if (o.progress) o.progress(what);
    };

    BenchReport r;
    r.machine = describe_machine();
    r.isa = simd::isa_name(simd::isa());
    r.threads = resolve_thread_count(o.threads);
    r.width = o.width, r.height = o.height;
    r.film = film.id, r.paper = paper.id;
    r.runs = o.runs;
    r.sample_windows = reference_windows(o);
    r.pixel_pitch_um = film.frame_width_mm * 1000.0 / kTargetWidthPx;
    for (int k : {1, 2, 4, 8, 12, 16, 20, 24, 28, 32}) r.mtf_cycles_per_px.push_back(k / 64.0);
    r.grain_wedge_patches = kWedgePatches, r.grain_wedge_patch_px = kWedgePatchPx;
    r.print_grain = o.print_grain;

    std::vector<Quality> tiers{Quality::reference};
    for (Quality q : o.tiers)
        if (std::find(tiers.begin(), tiers.end(), q) == tiers.end()) tiers.push_back(q);

    const Image scene = demo_scene(o.width, o.height);
    const FrameGeometry frame{o.width, o.height};
    // One compile before any is timed: the first pays for one-time set-up (the spectral
    // upsampling basis), which is no tier's cost.
    Plan::compile(film, &paper, look(Quality::high, o.seed, film, paper, o.width), frame, o.threads);
    Image out(o.width, o.height, 3), copied(o.width, o.height, 3);
    r.copy_in_turn_with_fast = std::find(tiers.begin(), tiers.end(), Quality::fast) != tiers.end();
    if (!r.copy_in_turn_with_fast) {
        say("copy pass");
        CopyInTurn copy{copied, kCopyRuns, {}};
        time_in_turn({}, scene, 1, o.threads, &copy);
        copy.report(r);
    }

    // Per tier, the sample windows' print and density (grain off) and the measurements.
    struct WindowRenders {
        std::vector<Image> print, density;
    };
    std::vector<WindowRenders> renders(tiers.size());
    GrainProfile reference_grain, reference_print_grain;
    for (size_t t = 0; t < tiers.size(); ++t) {
        const Quality q = tiers[t];
        TierResult tr;
        tr.quality = q;
        tr.name = quality_name(q);
        DevelopSettings s = look(q, o.seed, film, paper, o.width);
        auto start = Clock::now();
        Plan plan = Plan::compile(film, &paper, s, frame, o.threads);
        tr.compile_seconds = seconds_since(start);
        if (q == Quality::reference) {
            say(tr.name + (o.whole_frame ? std::string(": the whole frame")
                                         : ": " + std::to_string(r.sample_windows.size()) + " sample windows"));
            StageTimes times;
            long long pixels = 0, with_halo = 0;
            for (const Window& w : r.sample_windows) {
                render(plan, scene.view(), w, o.threads, &times);
                pixels += w.pixel_count();
                with_halo += plan.input_window(w).pixel_count();
            }
            const double frame_pixels = double(frame.width) * frame.height;
            tr.stages = stage_list(times, frame_pixels / pixels);
            for (const StageTime& st : tr.stages) tr.seconds += st.seconds;
            // Every stage computes at least the window and at most the window with its
            // whole halo, so the frame's time lies between the two extrapolations.
            tr.extrapolated = !o.whole_frame;
            // (The ratio first: it is at most 1, so the bound never exceeds the time by a
            // rounding, as seconds * pixels / with_halo can when the two counts are equal.)
            tr.extrapolated_lower_seconds = tr.seconds * (double(pixels) / double(with_halo));
        } else {
            const bool with_copy = q == Quality::fast;
            say(tr.name + ": whole frame, " + std::to_string(o.runs + 1) + " runs" +
                (with_copy ? ", the copy pass in turn" : ""));
            CopyInTurn copy{copied, (kCopyRuns + o.runs - 1) / o.runs, {}};  // (kCopyRuns or more in all)
            Timed timed = time_frame(plan, scene, out, o.runs, o.threads, with_copy ? &copy : nullptr);
            tr.seconds = timed.seconds;
            tr.stages = timed.stages;
            if (with_copy) copy.report(r);
        }

        say(tr.name + ": errors on the sample windows, MTF, grain wedge" + (o.print_grain ? ", printed grain wedge" : ""));
        DevelopSettings no_grain = s;
        no_grain.grain = false;
        Plan print_plan = Plan::compile(film, &paper, no_grain, frame, o.threads);
        no_grain.output = OutputMode::density;
        Plan density_plan = Plan::compile(film, nullptr, no_grain, frame, o.threads);
        for (const Window& w : r.sample_windows) {
            renders[t].print.push_back(render(print_plan, scene.view(), w, o.threads));
            renders[t].density.push_back(render(density_plan, scene.view(), w, o.threads));
        }
        const WindowRenders& ref = renders[0];
        ColourError worst;
        double de_sum = 0;
        for (size_t i = 0; i < r.sample_windows.size(); ++i) {
            ColourError e = colour_error(renders[t].print[i].view(), ref.print[i].view());
            de_sum += e.mean * e.pixels;
            worst.pixels += e.pixels;
            worst.max = std::max(worst.max, e.max);
            tr.density_error = std::max(tr.density_error,
                                        max_abs_difference(renders[t].density[i].view(), ref.density[i].view()));
        }
        worst.mean = de_sum / worst.pixels;
        tr.print_error = worst;

        tr.mtf = measure_density_mtf(film, q, r.pixel_pitch_um, r.mtf_cycles_per_px, o.threads, frame);
        if (!r.tiers.empty())  // the reference's own error stays 0
            for (size_t l = 0; l < tr.mtf.size(); ++l)
                for (size_t k = 0; k < tr.mtf[l].size(); ++k)
                    tr.mtf_error = std::max(tr.mtf_error, std::abs(tr.mtf[l][k] - r.tiers[0].mtf[l][k]));

        // The wedge's grain against the reference's, on the negative or (with a paper) the print;
        // the reference's against another realisation of itself: the measurement's noise floor.
        auto grain_against_reference = [&](const Stock* print_paper, GrainProfile& reference) {
            GrainErrors e;
            try {
                auto measure = [&](uint64_t seed) {
                    return measure_wedge_grain(film, print_paper, q, seed, r.pixel_pitch_um, o.threads,
                                               PrintViewing::media_relative, frame);
                };
                if (q == Quality::reference) reference = measure(o.seed);
                return grain_errors(reference, measure(q == Quality::reference ? o.seed + 1 : o.seed));
            } catch (const std::exception& ex) {
                e.problem = ex.what();
            }
            return e;
        };
        tr.grain = grain_against_reference(nullptr, reference_grain);
        if (o.print_grain)
            tr.print_grain = grain_against_reference(&paper, reference_print_grain);
        else
            tr.print_grain.problem = "not asked (--print-grain)";
        r.tiers.push_back(std::move(tr));

        if (q == Quality::fast) {
            const TierResult& fast = r.tiers.back();
            Image fast_pixels(o.width, o.height, 3), out_neutral(o.width, o.height, 3), on_out(o.width, o.height, 3);
            plan.run(scene.view(), fast_pixels.view(), o.threads);
            struct Off {
                const char* stage;
                void (*turn_off)(DevelopSettings&);
            };
            const Off offs[] = {{"grain", [](DevelopSettings& d) { d.grain = false; }},
                                {"scatter", [](DevelopSettings& d) { d.mtf = false; }},
                                {"halation", [](DevelopSettings& d) { d.halation = 0; }},
                                {"DIR couplers", [](DevelopSettings& d) { d.dir_couplers = 0; }}};
            for (const Off& off : offs) {
                say(std::string("fast without ") + off.stage + ", in turn with it and with it at neutral");
                DevelopSettings d = s;
                off.turn_off(d);
                const Plan off_plan = Plan::compile(film, &paper, d, frame, o.threads);
                PlanStructure all_stages;
                all_stages.skip_noop_stages = false;
                const Plan neutral_plan = Plan::compile(film, &paper, d, frame, o.threads, all_stages);
                const std::vector<Timed> t =
                    time_in_turn({{plan, on_out}, {off_plan, out}, {neutral_plan, out_neutral}}, scene, o.runs, o.threads);
                const Timed &on = t[0], &timed = t[1], &neutral = t[2];
                r.disabled.push_back({off.stage, timed.seconds, timed.stages,
                                      stage_seconds_when_on(on.stages, timed.stages, off.stage),
                                      on.seconds - timed.seconds, neutral.seconds, out.pixels == out_neutral.pixels});
            }
            say("fast stage after stage");
            PlanStructure staged;
            staged.one_pass = false;
            Timed timed =
                time_frame(Plan::compile(film, &paper, s, frame, o.threads, staged), scene, out_neutral, o.runs, o.threads);
            r.fast_run_variants.push_back({"stage after stage", timed.seconds, fast_pixels.pixels == out_neutral.pixels});
            const simd::Isa widest = simd::isa();
            for (simd::Isa isa : {simd::Isa::avx2, simd::Isa::baseline}) {
                if (int(isa) >= int(widest)) continue;
                say(std::string("fast on ") + simd::isa_name(isa));
                simd::set_isa(isa);
                timed = time_frame(plan, scene, out_neutral, o.runs, o.threads);
                simd::set_isa(widest);
                r.fast_run_variants.push_back({std::string(simd::isa_name(isa)) + " vectors", timed.seconds,
                                               fast_pixels.pixels == out_neutral.pixels});
            }
            say("fast edit latency");
            measure_edit_latency(film, paper, s, frame, scene, o.runs, o.threads, r);
            r.target.evaluated = true;
            r.target.copy_ratio = copy_ratio(fast.seconds, r.copy_seconds);
            r.target.mean_de2000 = fast.print_error.mean;
            r.target.grain_within = fast.grain.within(r.grain_tolerance) &&
                                    (!o.print_grain || fast.print_grain.within(r.grain_tolerance));
        }
    }
    std::vector<std::pair<double, double>> points;
    for (const TierResult& t : r.tiers) points.emplace_back(t.seconds, t.print_error.mean);
    std::vector<bool> optimal = pareto_optimal(points);
    for (size_t t = 0; t < r.tiers.size(); ++t) r.tiers[t].pareto_optimal = optimal[t];
    return r;
}

}  // namespace darkroom::bench
