// darkroom develop: one image or a sequence of frames, oiiotool style.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <thread>
#include <unistd.h>

#include "cli/atomic_file.h"
#include "cli/commands.h"
#include "cli/image_io.h"
#include "cli/look_file.h"
#include "cli/look_options.h"
#include "cli/progress.h"
#include "cli/sequence.h"

namespace darkroom::cli {

namespace {

namespace fs = std::filesystem;

// Frames at once by default: each holds its input, output and the plan's working planes, so
// the count is capped to bound memory on 4K plates.
constexpr int kDefaultMaxFramesAtOnce = 8;

struct RunOptions {
    bool dry_run = false, quiet = false, no_clobber = false, skip_bad_frames = false;
    bool in_place = false;  // -o names the input itself: each frame replaces its input
    int frames_at_once = 0;  // 0: min(threads, frames, kDefaultMaxFramesAtOnce)
    std::string log_path;
};

struct DevelopOptions {
    std::string input, output;
    std::vector<int> window;  // X, Y, W, H
    LookOptions look;
    SequenceOptions sequence;
    WriteOptions write;
    RunOptions run;
    std::string look_path, save_look_path;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Develops and writes one frame; its report goes to `progress` as its output takes its
// name (so a run interrupted then logs every finished output).
void develop_frame(const DevelopOptions& o, const ColourIO& colour, PlanCache& plans, const FrameJob& job,
                   int threads, bool print_plan, FrameReport& report, Progress& progress) {
    auto start = std::chrono::steady_clock::now();
    LoadedImage in = read_image(job.input);
    report.read_seconds = seconds_since(start);
    // An input read in another space than its tag names (an sRGB PNG taken as scene-linear
    // without --iscolorspace), and parts left out: said once, for a sequence's frames share them.
    if (const std::string w = colour.input_tag_warning(job.input, in.spec.get_string_attribute("oiio:ColorSpace"));
        !w.empty())
        progress.warn_once("input tag", report, w);
    if (const std::string w = other_subimages_warning(job.input, in); !w.empty()) progress.warn_once("parts", report, w);
    const int premultiplied_alpha = premultiplied_alpha_channel(in.spec);

    start = std::chrono::steady_clock::now();
    LookOptions look = o.look;
    look.settings.frame = job.frame;
    look.verbose = print_plan;
    look.threads = threads;
    // The film frame is the file's display window: a data window that is a CG element's
    // bounding box, or overscan, is that part of the frame (its pixel pitch and its grain),
    // so the core sees the pixels at their display-window coordinates.
    const int dx = in.spec.x - in.spec.full_x, dy = in.spec.y - in.spec.full_y;
    ConstImageView view = in.pixels.view();
    view.window = view.window.moved(dx, dy);
    view.colour_channels = colour_channel_count(in.spec);
    const Plan plan = plans.plan_for(frame_geometry(view, in.spec.full_width), job.frame);
    const Window out_window = window_flag(o.window, in.pixels.window, "--window").moved(dx, dy);
    // Before the render starts, that a reference render will take long (core/develop.h).
    if (const std::string w = long_reference_render_warning(plan, out_window, "--quality "); !w.empty())
        progress.warn_once("long reference render", report, w);
    for (const std::string& w : non_finite_warnings(plan, view, out_window, premultiplied_alpha)) progress.warn(report, w);
    Image out = develop_image(look, colour, plan, view, out_window, premultiplied_alpha);
    out.window = out.window.moved(-dx, -dy);  // write_image takes the data window's coordinates
    report.develop_seconds = seconds_since(start);

    start = std::chrono::steady_clock::now();
    write_image(job.output, out, in.spec, o.run.in_place ? "" : job.input, o.write, [&] {
        report.write_seconds = seconds_since(start);
        progress.add(report);
    });
}

// One frame, its report added to `progress`; returns its status.
FrameReport::Status process_frame(const DevelopOptions& o, const ColourIO& colour, PlanCache& plans,
                                  const FrameJob& job, int threads, bool print_plan, Progress& progress) {
    FrameReport report;
    report.frame = job.frame;
    report.input = job.input;
    report.output = job.output;
    if (o.run.no_clobber && fs::exists(job.output)) {
        report.status = FrameReport::Status::skipped_existing;
    } else if (o.run.dry_run) {
        report.status = FrameReport::Status::dry_run;
        if (!fs::exists(job.input)) progress.warn(report, "input '" + job.input + "' does not exist");
    } else {
        try {
            develop_frame(o, colour, plans, job, threads, print_plan, report, progress);
            return report.status;  // added as its output took its name
        } catch (const std::exception& e) {
            report.status = FrameReport::Status::failed;
            report.error = e.what();
        }
    }
    progress.add(report);
    return report.status;
}

// Frames run in parallel, each with its share of the threads: whole frames scale better
// than one frame's rows (reading and writing overlap with developing). Without
// --skip-bad-frames the first failure stops new frames from starting.
void run_frames(const DevelopOptions& o, const ColourIO& colour, const std::vector<FrameJob>& jobs, int threads,
                Progress& progress) {
    const int most = o.run.frames_at_once > 0 ? o.run.frames_at_once : std::min(threads, kDefaultMaxFramesAtOnce);
    const int workers = std::max(1, std::min(int(jobs.size()), most));
    const int threads_per_frame = std::max(1, threads / workers);
    if (o.look.verbose)
        std::cerr << "threads: " << threads << " (" << workers << " frame" << (workers > 1 ? "s" : "")
                  << " at once, " << threads_per_frame << " per frame)\n";
    LookOptions plan_look = o.look;
    plan_look.threads = threads_per_frame;
    PlanCache plans(plan_look);  // prints each plan it compiles with -v
    std::atomic<size_t> next{0};
    std::atomic<bool> stop{false};
    auto work = [&] {
        for (size_t i = next++; i < jobs.size() && !stop; i = next++) {
            const FrameReport::Status status =
                process_frame(o, colour, plans, jobs[i], threads_per_frame, o.look.verbose && i == 0, progress);
            if (status == FrameReport::Status::failed && !o.run.skip_bad_frames) stop = true;
        }
    };
    std::vector<std::thread> pool;
    for (int w = 1; w < workers; ++w) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
}

int resolve_threads(int requested) {
    if (requested > 0) return requested;
    return std::max(1u, std::thread::hardware_concurrency());
}

// The folders the outputs go to, each with the first output there.
std::map<fs::path, std::string> output_folders(const std::vector<FrameJob>& jobs) {
    std::map<fs::path, std::string> folders;
    for (const FrameJob& job : jobs) folders.emplace(fs::path(job.output).parent_path(), job.output);
    return folders;
}

void remove_stale_outputs_temps(const std::map<fs::path, std::string>& folders, bool quiet) {
    for (const auto& [dir, output] : folders)
        if (int removed = remove_stale_temps(dir); removed > 0 && !quiet)
            std::cerr << "darkroom: removed " << removed << " partial output(s) left in '"
                      << (dir.empty() ? "." : dir.string()) << "' by an interrupted run\n";
}

std::string failure_summary(const std::vector<FrameReport>& reports, size_t total) {
    std::string text;
    size_t failed = 0;
    for (const FrameReport& r : reports)
        if (r.status == FrameReport::Status::failed) {
            ++failed;
            text += "\n  frame " + std::to_string(r.frame) + " (" + r.input + "): " + r.error;
        }
    if (failed == 0) return "";
    return std::to_string(failed) + " of " + std::to_string(total) + " frames failed, " +
           std::to_string(reports.size() - failed) + " finished" + (reports.size() < total ? ", the rest not started" : "") +
           ":" + text;
}

void check_output_format(const DevelopOptions& o) {
    require_known_compression(o.output, o.write.compression);
    // Densities run past 1 D: a file of integers (PNG whatever -d says, -d uint16) clips them.
    if (o.look.settings.output == OutputMode::density && writes_integers(o.output, o.write))
        throw UserError("--output density writes float densities: give a float format such as .exr or .tif (and -d "
                        "half or float), not '" + o.output + "'" +
                        (o.write.data_type.empty() ? "" : " -d " + o.write.data_type));
}

void run_develop(DevelopOptions& o, CLI::App& cmd) {
    if (!o.look_path.empty()) apply_look_file(cmd, o.look_path);
    if (!o.save_look_path.empty() && o.run.dry_run) std::cout << "dry run: would write the look to " << o.save_look_path << "\n";
    if (!o.save_look_path.empty() && !o.run.dry_run) save_look_file(cmd, o.save_look_path);
    if (o.input.empty() && o.output.empty() && !o.save_look_path.empty()) return;
    if (o.input.empty() || o.output.empty()) throw UserError("develop needs an input image and -o OUTPUT");

    const bool sequence = is_sequence_pattern(o.input) || is_sequence_pattern(o.output);
    if (sequence && cmd.get_option("--frame")->count() > 0)
        throw UserError("--frame is for a single image: each frame of a sequence uses its own frame number");
    const std::vector<FrameJob> jobs = expand_frames(o.input, o.output, o.sequence, o.look.settings.frame);
    check_output_format(o);
    const std::map<fs::path, std::string> folders = output_folders(jobs);
    for (const auto& [folder, output] : folders) require_writable(output);  // a sequence's frames share theirs
    // Only an output named as the input itself replaces it; an output that merely resolves
    // to an input (another spelling of a pattern, a link) is refused frame by frame.
    o.run.in_place = fs::absolute(o.input).lexically_normal() == fs::absolute(o.output).lexically_normal();
    o.write.command_line = command_line();
    o.write.look_json = look_json(cmd).dump();
    const ColourIO colour(o.look.colour, o.look.settings.output, o.look.verbose);
    o.write.colour_space = colour.output_space();
    if (const std::string w = colour.integer_output_warning(o.output, writes_integers(o.output, o.write)); !w.empty())
        std::cerr << "darkroom: warning: " << w << "\n";
    if (!o.run.dry_run) remove_stale_outputs_temps(folders, o.run.quiet);

    // A single image is developed silently, as oiiotool does, unless asked (-v, -n).
    const bool quiet = o.run.quiet || (!sequence && !o.run.dry_run && !o.look.verbose);
    Progress progress(jobs.size(), sequence, quiet, isatty(STDERR_FILENO) && sequence && !o.run.dry_run);
    const int threads = resolve_threads(o.look.threads);
    OIIO::attribute("threads", threads);  // OpenImageIO's own pool (EXR decoding) keeps to --threads too
    {
        // Interrupted (Ctrl-C, a farm's kill), the log still tells which frames were finished.
        InterruptHookScope log_on_interrupt([&](int signal_number) {
            if (!o.run.log_path.empty())
                write_run_log(o.run.log_path, progress.reports(), progress.elapsed_seconds(), command_line(),
                              signal_number);
        });
        run_frames(o, colour, jobs, threads, progress);
    }
    progress.finish();
    const std::vector<FrameReport> reports = progress.reports();
    if (!o.run.log_path.empty()) write_run_log(o.run.log_path, reports, progress.elapsed_seconds(), command_line());

    if (!sequence && reports.front().status == FrameReport::Status::failed) throw UserError(reports.front().error);
    if (std::string summary = failure_summary(reports, jobs.size()); !summary.empty()) throw UserError(summary);
}

void add_run_flags(CLI::App& cmd, DevelopOptions& o) {
    auto run_option = [](CLI::Option* opt) { return opt->configurable(false); };
    run_option(cmd.add_option("input", o.input, "Input image or sequence (plate.####.exr, plate.%04d.exr, plate.@@@@.exr)"));
    run_option(cmd.add_option("-o,--out", o.output, "Output image or sequence"));
    run_option(cmd.add_option("--window", o.window, "Render only this window X,Y,W,H of the input (from its first pixel)")
                   ->delimiter(',')
                   ->expected(4));
    run_option(cmd.add_option("--frames", o.sequence.frames, "Frames of a sequence: 1-100, 1-100x2, 1,5,9-12"));
    run_option(cmd.add_option("--framepadding", o.sequence.framepadding, "Digits of the frame number for '#' wildcards")
                   ->check(CLI::Range(1, 16)));
    run_option(cmd.add_option("-d", o.write.data_type, "Output data type")->check(CLI::IsMember(output_data_types())));
    run_option(cmd.add_option("--compression", o.write.compression, "Output compression (e.g. zip, piz, dwaa:45)"));
    run_option(cmd.add_flag("-n", o.run.dry_run, "Dry run: say what would be done, write nothing"));
    run_option(cmd.add_flag("-q", o.run.quiet, "Quiet: only errors and warnings"));
    run_option(cmd.add_flag("--no-clobber", o.run.no_clobber, "Do not overwrite existing outputs (resumes a stopped run)"));
    run_option(cmd.add_flag("--skip-bad-frames", o.run.skip_bad_frames,
                            "Go on past frames that fail (the exit status still reports them)"));
    run_option(cmd.add_option("--frames-at-once", o.run.frames_at_once,
                              "Frames developed in parallel, sharing --threads (0: as many as threads, up to 8)")
                   ->check(CLI::Range(0, 1024)));
    run_option(cmd.add_option("--log", o.run.log_path, "Write per-frame timings, warnings and errors to this JSON file"));
    add_look_file_flags(cmd, o.look_path, o.save_look_path);
}

}  // namespace

void add_develop_command(CLI::App& app) {
    auto o = std::make_shared<DevelopOptions>();
    CLI::App* cmd = app.add_subcommand("develop", "Develop an image or a sequence through film (and paper)");
    add_run_flags(*cmd, *o);
    add_look_flags(*cmd, o->look);
    cmd->callback([o, cmd] { run_develop(*o, *cmd); });
}

}  // namespace darkroom::cli
