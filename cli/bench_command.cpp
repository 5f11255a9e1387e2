// darkroom bench: run time against error for every quality tier (bench/bench.h), as a
// table with the tiers as columns, or as JSON.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bench/bench.h"
#include "cli/commands.h"
#include "cli/io_bench.h"
#include "cli/user_error.h"

namespace darkroom::cli {

namespace {

struct BenchCliOptions {
    std::string size = "4096x2160";
    bool json = false;
    int threads = 0;
    int runs = 3;
    std::string film = "kodak-vision3-250d", paper = "kodak-2383";
    std::string tiers = "reference,high,fast,preview";
    bool print_grain = false;
    bool io = false;
    std::string sequence_size = "1920x1080";
    int sequence_frames = 6;
    bool whole_frame = false;
};

std::pair<int, int> parse_size(const std::string& text) {
    int w = 0, h = 0;
    char x = 0, rest = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &rest) != 3 || (x != 'x' && x != 'X') || w < 16 || h < 16)
        throw UserError("--size '" + text + "': expected WIDTHxHEIGHT, each at least 16 (e.g. 4096x2160)");
    return {w, h};
}

std::vector<Quality> parse_tiers(const std::string& text) {
    std::vector<Quality> tiers;
    std::stringstream list(text);
    for (std::string name; std::getline(list, name, ',');) {
        auto q = parse_quality(name);
        if (!q) throw UserError("--tiers: unknown tier '" + name + "' (reference, high, fast, preview)");
        tiers.push_back(*q);
    }
    if (tiers.empty()) throw UserError("--tiers: give at least one tier");
    return tiers;
}

nlohmann::json stages_json(const std::vector<bench::StageTime>& stages, double copy_s) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& s : stages)
        out.push_back({{"stage", s.stage}, {"seconds", s.seconds}, {"copy_ratio", bench::copy_ratio(s.seconds, copy_s)}});
    return out;
}

nlohmann::json report_json(const bench::BenchReport& r) {
    nlohmann::json windows = nlohmann::json::array();
    for (const Window& w : r.sample_windows) windows.push_back({w.x0, w.y0, w.width(), w.height()});
    nlohmann::json doc = {
        {"machine", {{"cpu", r.machine.cpu}, {"cores", r.machine.cores}, {"threads", r.threads}, {"isa", r.isa}}},
        {"frame", {{"width", r.width}, {"height", r.height}, {"scene", "demo"}, {"pixel_pitch_um", r.pixel_pitch_um}}},
        {"film", r.film},
        {"paper", r.paper},
        {"look", "print, grain, MTF, halation and DIR couplers on"},
        {"timed_runs", r.runs},
        {"warmup_runs", 1},
        {"copy_seconds", r.copy_seconds},
        {"copy_runs", r.copy_runs},
        {"copy_median_seconds", r.copy_median_seconds},
        {"copy_bytes", r.copy_bytes()},
        {"copy_in_turn_with_fast", r.copy_in_turn_with_fast},
        {"sample_windows", windows},
        {"mtf_cycles_per_px", r.mtf_cycles_per_px},
        {"grain_wedge",
         {{"patches", r.grain_wedge_patches}, {"patch_px", r.grain_wedge_patch_px}, {"printed_too", r.print_grain}}},
        {"grain_tolerance",
         {{"response_percent", r.grain_tolerance.response_percent},
          {"nps_db", r.grain_tolerance.nps_db},
          {"correlation", r.grain_tolerance.correlation}}},
        {"tiers", nlohmann::json::array()},
        {"disabled_stages", nlohmann::json::array()}};
    for (const auto& t : r.tiers) {
        auto grain_json = [&](const bench::GrainErrors& g) {
            nlohmann::json j = {{"measured", g.measured},
                                {"against", t.quality == Quality::reference ? "reference, another seed" : "reference"},
                                {"response_percent", g.response_percent},
                                {"nps_db", g.nps_db},
                                {"correlation", g.correlation},
                                {"within_tolerance", g.within(r.grain_tolerance)}};
            if (!g.measured) j["problem"] = g.problem;
            return j;
        };
        doc["tiers"].push_back({{"name", t.name},
                                {"compile_seconds", t.compile_seconds},
                                {"seconds", t.seconds},
                                {"copy_ratio", bench::copy_ratio(t.seconds, r.copy_seconds)},
                                {"extrapolated_from_sample_windows", t.extrapolated},
                                {"extrapolated_lower_bound_seconds", t.extrapolated_lower_seconds},
                                {"stages", stages_json(t.stages, r.copy_seconds)},
                                {"errors",
                                 {{"print_de2000_mean", t.print_error.mean},
                                  {"print_de2000_max", t.print_error.max},
                                  {"negative_density_max", t.density_error},
                                  {"mtf_max", t.mtf_error},
                                  {"grain", grain_json(t.grain)},
                                  {"print_grain", grain_json(t.print_grain)}}},
                                {"mtf", t.mtf},
                                {"pareto_optimal", t.pareto_optimal}});
    }
    for (const auto& d : r.disabled)
        doc["disabled_stages"].push_back({{"tier", "fast"},
                                          {"stage_off", d.stage},
                                          {"seconds", d.seconds},
                                          {"copy_ratio", bench::copy_ratio(d.seconds, r.copy_seconds)},
                                          {"stage_seconds_when_on", d.stage_seconds_when_on},
                                          {"saved_seconds", d.saved_seconds},
                                          {"neutral_stage_kept_seconds", d.neutral_seconds},
                                          {"identical_pixels_to_neutral_stage_kept", d.identical_pixels},
                                          {"stages", stages_json(d.stages, r.copy_seconds)}});
    doc["fast_run_variants"] = nlohmann::json::array();
    for (const auto& v : r.fast_run_variants)
        doc["fast_run_variants"].push_back({{"way", v.way},
                                            {"seconds", v.seconds},
                                            {"copy_ratio", bench::copy_ratio(v.seconds, r.copy_seconds)},
                                            {"identical_pixels", v.identical_pixels}});
    doc["edit_latency"] = {{"steady_rerender_seconds", r.steady_rerender_seconds}, {"edits", nlohmann::json::array()}};
    for (const auto& e : r.edits)
        doc["edit_latency"]["edits"].push_back(
            {{"setting", e.setting}, {"seconds", e.seconds}, {"x_steady", e.seconds / r.steady_rerender_seconds}});
    doc["target"] = {{"evaluated", r.target.evaluated},
                     {"tier", "fast"},
                     {"max_copy_ratio", r.target.max_copy_ratio},
                     {"max_mean_de2000", r.target.max_mean_de2000},
                     {"copy_ratio", r.target.copy_ratio},
                     {"mean_de2000", r.target.mean_de2000},
                     {"grain_within_tolerance", r.target.grain_within},
                     {"pass", r.target.passes()}};
    return doc;
}

std::string ms_cell(double seconds, double copy_s) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.1f ms %.1fx", seconds * 1e3, bench::copy_ratio(seconds, copy_s));
    return buf;
}

std::string number_cell(double v, const char* format = "%.4g") {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

void print_row(const std::string& label, const std::vector<std::string>& cells, const std::string& note = "") {
    std::printf("%-26s", label.c_str());
    for (const auto& c : cells) std::printf(" %20s", c.c_str());
    if (!note.empty()) std::printf("   %s", note.c_str());
    std::printf("\n");
}

void print_report(const bench::BenchReport& r) {
    const double copy_s = r.copy_seconds;
    std::printf("darkroom bench: %s printed on %s, the %dx%d demo scene at %.3g um on film (a 4096 px wide frame's "
                "pitch), grain, MTF, halation and DIR couplers on\n",
                r.film.c_str(), r.paper.c_str(), r.width, r.height, r.pixel_pitch_um);
    std::printf("machine: %s, %d cores, %d threads used, %s vectors\n", r.machine.cpu.c_str(), r.machine.cores,
                r.threads, r.isa.c_str());
    std::printf("copy pass (float RGB, same threads, parallel over rows): %.2f ms (%.1f GB/s read and written), "
                "fastest of %d%s; their median %.2f ms. Develop times: fastest of %d runs after 1 warm-up, in ms "
                "and x the fastest copy pass\n\n",
                copy_s * 1e3, r.copy_bytes() / copy_s * 1e-9, r.copy_runs,
                r.copy_in_turn_with_fast ? ", timed in turn with the fast tier's frame" : "", r.copy_median_seconds * 1e3,
                r.runs);

    std::vector<std::string> names;
    for (const auto& t : r.tiers) names.push_back(t.name + (t.extrapolated ? " (*)" : ""));
    print_row("", names);
    auto tier_row = [&](const std::string& label, auto cell, const std::string& note = "") {
        std::vector<std::string> cells;
        for (const auto& t : r.tiers) cells.push_back(cell(t));
        print_row(label, cells, note);
    };
    tier_row("develop, whole frame", [&](const auto& t) { return ms_cell(t.seconds, copy_s); });
    if (r.tiers.front().extrapolated)
        tier_row("  (*) lower bound", [&](const auto& t) {
            return t.extrapolated ? ms_cell(t.extrapolated_lower_seconds, copy_s) : std::string("");
        });
    std::vector<std::string> stages;
    for (const auto& t : r.tiers)
        for (const auto& s : t.stages)
            if (std::find(stages.begin(), stages.end(), s.stage) == stages.end()) stages.push_back(s.stage);
    for (const auto& stage : stages)
        tier_row("  " + stage, [&](const auto& t) {
            for (const auto& s : t.stages)
                if (s.stage == stage) return ms_cell(s.seconds, copy_s);
            return std::string("-");
        });
    tier_row("compile (not in the above)", [&](const auto& t) { return number_cell(t.compile_seconds * 1e3, "%.1f ms"); });
    if (r.tiers.front().extrapolated)
        std::printf("\nerrors against the reference, on %zu sample windows of %dx%d:\n", r.sample_windows.size(),
                    r.sample_windows.front().width(), r.sample_windows.front().height());
    else
        std::printf("\nerrors against the reference, on the whole frame:\n");
    // The reference against itself is no measurement: shown as "-".
    auto error_cell = [](const bench::TierResult& t, double v) {
        return t.quality == Quality::reference ? std::string("-") : number_cell(v);
    };
    tier_row("print CIEDE2000 mean", [&](const auto& t) { return error_cell(t, t.print_error.mean); },
             "grain off in both");
    tier_row("print CIEDE2000 max", [&](const auto& t) { return error_cell(t, t.print_error.max); }, "grain off in both");
    tier_row("negative max |dD|", [&](const auto& t) { return error_cell(t, t.density_error); }, "density, grain off");
    tier_row("MTF max |d response|", [&](const auto& t) { return error_cell(t, t.mtf_error); },
             "sine targets to Nyquist, grain, halation and DIR couplers off");
    // The negative's grain, and the print's where it was measured (--print-grain).
    const bool print_grain = r.print_grain;
    for (const auto& [prefix, grain] : {std::pair{"", &bench::TierResult::grain},
                                       std::pair{"print ", &bench::TierResult::print_grain}}) {
        if (grain == &bench::TierResult::print_grain && !print_grain) continue;
        auto grain_cell = [grain = grain](const bench::TierResult& t, double bench::GrainErrors::*field) {
            const bench::GrainErrors& g = t.*grain;
            return g.measured ? number_cell(g.*field, "%.3g") : std::string("not measured");
        };
        const std::string p = prefix;
        tier_row(p + "grain response error %",
                 [&](const auto& t) { return grain_cell(t, &bench::GrainErrors::response_percent); },
                 "tolerance " + number_cell(r.grain_tolerance.response_percent, "%g"));
        tier_row(p + "grain NPS distance dB", [&](const auto& t) { return grain_cell(t, &bench::GrainErrors::nps_db); },
                 "tolerance " + number_cell(r.grain_tolerance.nps_db, "%g"));
        tier_row(p + "grain correlation diff",
                 [&](const auto& t) { return grain_cell(t, &bench::GrainErrors::correlation); },
                 "tolerance " + number_cell(r.grain_tolerance.correlation, "%g"));
    }
    tier_row("Pareto-optimal", [](const auto& t) { return std::string(t.pareto_optimal ? "yes" : "dominated"); },
             "in (time, mean CIEDE2000)");
    for (const auto& t : r.tiers) {
        if (!t.grain.measured) std::printf("grain of %s not measured: %s\n", t.name.c_str(), t.grain.problem.c_str());
        if (print_grain && !t.print_grain.measured)
            std::printf("print grain of %s not measured: %s\n", t.name.c_str(), t.print_grain.problem.c_str());
    }
    if (r.tiers.front().extrapolated)
        std::printf(
            "\n(*) reference: rendered only on the sample windows; its times are the windows' times x frame pixels /\n"
            "    window pixels, an upper bound (each window also computes its halo); the lower bound divides by the\n"
            "    pixels of the windows with their halos instead.");
    std::printf(
        "\nColour and density errors are measured with grain off in both renders: grain realisations differ\n"
        "between tiers. Grain: a %d-patch wedge (%d px patches, one stop apart, MTF and halation off), each tier's\n"
        "density analysed as a plate and compared with the reference's; the reference column compares the\n"
        "reference with itself under another seed (the measurement's noise floor).%s\n",
        r.grain_wedge_patches, r.grain_wedge_patch_px,
        print_grain ? "\nPrint grain: the same wedge printed, each channel of the print's linear Rec.709 read as a "
                      "density\n(-log10), analysed and compared the same way."
                    : "");

    if (!r.disabled.empty()) {
        std::printf("\nfast tier with one stage off (whole frame):\n");
        print_row("stage off", {"develop", "saved", "stage's time when on", "stage when off", "kept at neutral",
                                "same pixels"});
        for (const auto& d : r.disabled) {
            std::string when_off = "gone";
            for (const auto& s : d.stages)
                if (s.stage == d.stage) when_off = number_cell(s.seconds * 1e3, "%.1f ms");
            print_row("  " + d.stage, {ms_cell(d.seconds, copy_s), number_cell(d.saved_seconds * 1e3, "%.1f ms"),
                                       number_cell(d.stage_seconds_when_on * 1e3, "%.1f ms"), when_off,
                                       ms_cell(d.neutral_seconds, copy_s), d.identical_pixels ? "yes" : "NO"});
        }
        std::printf("(kept at neutral: the stage left in the plan with its neutral value, so that leaving it out is "
                    "seen to save its time and change no pixel)\n");
    }
    if (!r.fast_run_variants.empty()) {
        std::printf("\nfast tier run other ways (whole frame):\n");
        print_row("way", {"develop", "same pixels"});
        for (const auto& v : r.fast_run_variants)
            print_row("  " + v.way, {ms_cell(v.seconds, copy_s), v.identical_pixels ? "yes" : "NO"});
        std::printf("(stage after stage: each stage over whole planes, as the other tiers run; vectors: the "
                    "kernels compiled for a narrower instruction set)\n");
    }
    if (!r.edits.empty()) {
        std::printf("\nfast tier edit latency (compile and develop the whole frame after one setting changed):\n");
        print_row("setting changed", {"compile + develop", "x steady"});
        print_row("  none (steady)", {number_cell(r.steady_rerender_seconds * 1e3, "%.1f ms"), "1.00x"});
        for (const auto& e : r.edits)
            print_row("  " + e.setting, {number_cell(e.seconds * 1e3, "%.1f ms"),
                                         number_cell(e.seconds / r.steady_rerender_seconds, "%.2fx")});
        std::printf("(fastest of %d rounds, each a new value of every setting, timed in turn)\n", r.runs);
    }
    if (!r.target.evaluated)
        std::printf("\ntarget: not evaluated, the fast tier was not run\n");
    else
        std::printf("\ntarget (fast tier, %dx%d, %d threads): %.2fx copy (<= %g), mean CIEDE2000 %.3g (<= %g), "
                    "grain %s tolerances: %s\n",
                    r.width, r.height, r.threads, r.target.copy_ratio, r.target.max_copy_ratio, r.target.mean_de2000,
                    r.target.max_mean_de2000, r.target.grain_within ? "within" : "outside",
                    r.target.passes() ? "PASS" : "FAIL");
}

void run_bench(const BenchCliOptions& o) {
    if (o.io) {
        IoBenchOptions io;
        std::tie(io.frame_width, io.frame_height) = parse_size(o.size);
        std::tie(io.sequence_width, io.sequence_height) = parse_size(o.sequence_size);
        io.sequence_frames = o.sequence_frames;
        io.rounds = o.runs;
        io.threads = o.threads;
        const nlohmann::json report = run_io_bench(io);
        if (o.json)
            std::cout << report.dump(2) << "\n";
        else
            print_io_bench(report);
        return;
    }
    bench::BenchOptions options;
    std::tie(options.width, options.height) = parse_size(o.size);
    options.tiers = parse_tiers(o.tiers);
    options.threads = o.threads;
    options.runs = o.runs;
    options.print_grain = o.print_grain;
    options.whole_frame = o.whole_frame;
    options.progress = [](const std::string& what) { std::cerr << "bench: " << what << "\n"; };
    Stock film, paper;
    try {
        film = find_stock(o.film);
        paper = find_stock(o.paper);
    } catch (const StockError& e) {
        throw UserError(e.what());
    }
    bench::BenchReport report;
    try {
        report = bench::run_benchmark(film, paper, options);
    } catch (const std::invalid_argument& e) {
        throw UserError(e.what());
    }
    if (o.json)
        std::cout << report_json(report).dump(2) << "\n";
    else
        print_report(report);
}

}  // namespace

void add_bench_command(CLI::App& app) {
    auto o = std::make_shared<BenchCliOptions>();
    CLI::App* cmd = app.add_subcommand(
        "bench", "Time every quality tier on a frame and measure its error against the reference tier");
    cmd->add_option("--size", o->size, "Frame size WxH (default 4096x2160)");
    cmd->add_flag("--json", o->json, "Machine-readable output");
    cmd->add_option("--threads", o->threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
    cmd->add_option("--runs", o->runs, "Timed whole-frame runs after one warm-up; the fastest is kept (--io: rounds, the median kept)")
        ->check(CLI::Range(1, 100));
    cmd->add_option("--film", o->film, "Film stock id or .json file (default kodak-vision3-250d)");
    cmd->add_option("--paper", o->paper, "Paper or print film id or .json file (default kodak-2383)");
    cmd->add_option("--tiers", o->tiers,
                    "Comma-separated tiers (default reference,high,fast,preview); the reference always runs");
    cmd->add_flag("--print-grain", o->print_grain,
                  "Also measure the print's grain against the reference's: the grain wedge printed and each channel "
                  "read as a density (the reference's two prints of it take minutes)");
    cmd->add_flag("--io", o->io,
                  "Instead: the program timed from outside on files, program start included: a sequence's frames per "
                  "second with and without overlap, and a --size frame developed against oiiotool copying it");
    cmd->add_option("--sequence-size", o->sequence_size, "--io: the sequence's frame size WxH (default 1920x1080)");
    cmd->add_option("--sequence-frames", o->sequence_frames, "--io: the sequence's frames (default 6)")
        ->check(CLI::Range(1, 1000));
    cmd->add_flag("--whole-frame", o->whole_frame,
                  "Render the reference on the whole frame, not on four 128 px sample windows, and measure every "
                  "tier's errors there (minutes at 1024x683 on two cores; use a --size that small)");
    cmd->callback([o] { run_bench(*o); });
}

}  // namespace darkroom::cli
