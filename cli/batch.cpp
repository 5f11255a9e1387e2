#include "cli/batch.h"

#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <unistd.h>

#include "cli/atomic_file.h"
#include "cli/commands.h"

namespace darkroom::cli {

namespace {

namespace fs = std::filesystem;

// Frames at once by default: each holds its input, output and working planes, so the count
// is capped to bound memory on 4K plates.
constexpr int kDefaultMaxFramesAtOnce = 8;

// Frames finish in any order (several run at once, each written while the next develops)
// and are reported, their outputs taking their names, in frame order: the run prints and
// logs the lines of frames run one after another, an output appears only after those of the
// frames before it, and an interrupted run's log lists exactly the outputs under their names.
class InFrameOrder {
public:
    explicit InFrameOrder(Progress& progress) : progress_(progress) {}

    // Frame `index` (of the run's jobs) is finished: its report, and its output to name where
    // it was written.
    void finish(size_t index, FrameReport report, std::unique_ptr<TempFile> output) {
        std::lock_guard<std::mutex> lock(mutex_);
        waiting_.emplace(index, Finished{std::move(report), std::move(output)});
        for (auto at = waiting_.find(next_); at != waiting_.end(); at = waiting_.find(++next_)) {
            report_frame(at->second);
            waiting_.erase(at);
        }
    }

    // After the run: the frames that still wait for one never started (a failure stopped
    // the run as another worker took that frame), in frame order too.
    void finish_waiting() {
        std::lock_guard<std::mutex> lock(mutex_);
        for (auto& [index, finished] : waiting_) report_frame(finished);
        waiting_.clear();
    }

private:
    struct Finished {
        FrameReport report;
        std::unique_ptr<TempFile> output;
    };
    void report_frame(Finished& f) {
        try {
            if (f.output) return f.output->commit([&] { progress_.add(f.report); });
        } catch (const UserError& e) {  // (the rename failed)
            f.report.status = FrameReport::Status::failed;
            f.report.error = e.what();
        }
        progress_.add(f.report);
    }

    Progress& progress_;
    std::mutex mutex_;
    size_t next_ = 0;
    std::map<size_t, Finished> waiting_;
};

// A frame's read and develop, with the write that is left to do; no write for a frame that
// failed, is skipped or is a dry run (its report then says so).
FrameWrite start_frame(const RunOptions& run, const FrameWork& work, const DryRunCheck& dry_run_check,
                       const FrameJob& job, int threads, bool first, FrameReport& report, Progress& progress) {
    if (run.no_clobber && fs::exists(job.output)) {
        report.status = FrameReport::Status::skipped_existing;
    } else if (run.dry_run) {
        report.status = FrameReport::Status::dry_run;
        // The header alone: what the run would refuse or warn of, without reading the pixels.
        try {
            if (dry_run_check)
                dry_run_check(job, report, progress);
            else
                read_image_header(job.input);
        } catch (const UserError& e) {
            progress.warn(report, e.what());
        }
    } else {
        try {
            return work(job, threads, first, report, progress);
        } catch (const std::exception& e) {
            report.status = FrameReport::Status::failed;
            report.error = e.what();
        }
    }
    return {};
}

// Frames run in parallel, each with its share of the threads: whole frames scale better
// than one frame's rows. Each worker writes a frame on a thread of its own while it reads
// and develops the next, so a worker holds at most two frames. Without --skip-bad-frames
// the first failure stops new frames from starting.
void run_frames(const RunOptions& run, const std::vector<FrameJob>& jobs, int threads, bool verbose,
                const PrepareFrames& prepare, const DryRunCheck& dry_run_check, Progress& progress) {
    int most = run.frames_at_once > 0 ? run.frames_at_once : std::min(threads, kDefaultMaxFramesAtOnce);
    bool overlap = run.overlap;
    // No more frames in flight than the memory holds, by the first frame's headers.
    try {
        const double memory = double(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
        const int fit = int(std::min(1024.0, memory / file_memory_bytes(jobs.front().input)));
        overlap = overlap && fit >= 2;
        const int frames_per_worker = overlap ? 2 : 1;
        if (!run.dry_run && fit >= 1 && fit < most * frames_per_worker) {
            const int workers_fit = std::max(1, fit / frames_per_worker);
            if (run.frames_at_once > 0)
                std::cerr << "darkroom: warning: --frames-at-once " << run.frames_at_once << ": only " << fit
                          << " of these frames fit in memory at once; running " << workers_fit << "\n";
            most = workers_fit;
        }
    } catch (const UserError&) {
        // (a frame that cannot be read fails as it runs)
    }
    const int workers = std::max(1, std::min(int(jobs.size()), most));
    const int threads_per_frame = std::max(1, threads / workers);
    if (verbose)
        std::cerr << "threads: " << threads << " (" << workers << " frame" << (workers > 1 ? "s" : "")
                  << " at once, " << threads_per_frame << " per frame)"
                  << (overlap ? ", each frame written while the next is read and developed" : "") << "\n";
    const FrameWork work = prepare(threads_per_frame);
    InFrameOrder in_order(progress);
    std::atomic<size_t> next{0};
    std::atomic<bool> stop{false};
    auto finish = [&](size_t index, FrameReport report, std::unique_ptr<TempFile> output) {
        if (report.status == FrameReport::Status::failed && !run.skip_bad_frames) stop = true;
        in_order.finish(index, std::move(report), std::move(output));
    };
    auto worker = [&] {
        std::thread writing;  // the previous frame's write
        for (size_t i = next++; i < jobs.size() && !stop; i = next++) {
            const FrameJob& job = jobs[i];
            FrameReport report;
            report.frame = job.frame;
            report.input = job.input;
            report.output = job.output;
            report.start_seconds = progress.elapsed_seconds();
            FrameWrite write = start_frame(run, work, dry_run_check, job, threads_per_frame, i == 0, report, progress);
            if (!write) {
                report.end_seconds = progress.elapsed_seconds();
                finish(i, std::move(report), nullptr);
                continue;
            }
            auto write_frame = [&finish, &progress, i, report = std::move(report), write = std::move(write)]() mutable {
                const auto start = std::chrono::steady_clock::now();
                std::unique_ptr<TempFile> output;
                try {
                    output = write();
                    report.write_seconds = seconds_since(start);
                } catch (const std::exception& e) {
                    report.status = FrameReport::Status::failed;
                    report.error = e.what();
                }
                write = nullptr;  // the frame's pixels, freed before it waits for the frames before it
                report.end_seconds = progress.elapsed_seconds();
                finish(i, std::move(report), std::move(output));
            };
            if (writing.joinable()) writing.join();
            if (overlap)
                writing = std::thread(std::move(write_frame));
            else
                write_frame();
        }
        if (writing.joinable()) writing.join();
    };
    std::vector<std::thread> pool;
    for (int w = 1; w < workers; ++w) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
    in_order.finish_waiting();
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

}  // namespace

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void check_output_holds_parts(const FrameJob& job, const LoadedImage& input, FrameReport& report,
                              Progress& progress) {
    require_holds_parts(job.output, job.input, input);
    if (const std::string w = uint32_channels_warning(job.output, input); !w.empty())
        progress.warn_once("uint32", report, w);
}

void add_batch_flags(CLI::App& cmd, BatchOptions& o, const std::string& input_help, const std::string& output_help) {
    auto run_option = [](CLI::Option* opt) { return opt->configurable(false); };
    run_option(cmd.add_option("input", o.input, input_help + " (plate.####.exr, plate.%04d.exr, plate.@@@@.exr)"));
    run_option(cmd.add_option("-o,--out", o.output, output_help));
    run_option(cmd.add_option("--frames", o.sequence.frames, "Frames of a sequence: 1-100, 1-100x2, 1,5,9-12"));
    run_option(cmd.add_option("--framepadding", o.sequence.framepadding, "Digits of the frame number for '#' wildcards")
                   ->check(CLI::Range(1, 16)));
    run_option(cmd.add_option("-d", o.write.data_type,
                              "Output data type (uint10, uint12: that many bits where the format stores them, DPX "
                              "and TIFF, else 16; default: the input's, where the format stores it)")
                   ->check(CLI::IsMember(output_data_types())));
    run_option(cmd.add_option("--compression", o.write.compression, "Output compression (e.g. zip, piz, dwaa:45)"));
    run_option(cmd.add_flag("-n", o.run.dry_run, "Dry run: say what would be done, write nothing"));
    run_option(cmd.add_flag("-q", o.run.quiet, "Quiet: only errors and warnings"));
    run_option(cmd.add_flag("--no-clobber", o.run.no_clobber, "Do not overwrite existing outputs (resumes a stopped run)"));
    run_option(cmd.add_flag("--skip-bad-frames", o.run.skip_bad_frames,
                            "Go on past frames that fail (the exit status still reports them)"));
    run_option(cmd.add_option("--frames-at-once", o.run.frames_at_once,
                              "Frames run in parallel, sharing --threads (0: as many as threads, up to 8)")
                   ->check(CLI::Range(0, 1024)));
    run_option(cmd.add_flag_callback(
        "--no-overlap", [&o] { o.run.overlap = false; },
        "Read, develop and write each frame in turn (by default a frame is written while the next is read and "
        "developed)"));
    run_option(cmd.add_option("--log", o.run.log_path, "Write per-frame timings, warnings and errors to this JSON file"));
}

void add_layer_flag(CLI::App& cmd, std::optional<std::string>& layer, const std::string& verb) {
    cmd.add_option("--layer", layer,
                   "The layer or part of a layered or multi-part input (a render's AOVs) to " + verb +
                       ", e.g. 'diffuse' (default: the channels without a layer name, of whichever part has "
                       "them, else the only layer with colour); the others pass through")
        ->configurable(false);
}

std::string output_flag_hint(const CLI::App& cmd) {
    const CLI::Option* input = cmd.get_option_no_throw("input");
    const CLI::Option* output = cmd.get_option_no_throw("-o");
    const std::vector<std::string> extra = cmd.remaining();
    if (!input || !output || input->count() != 1 || output->count() != 0 || extra.size() != 1 || extra[0][0] == '-')
        return "";
    std::string command = cmd.get_name();
    for (const CLI::App* parent = cmd.get_parent(); parent && parent->get_parent(); parent = parent->get_parent())
        command = parent->get_name() + " " + command;
    return "'" + extra[0] + "' is a second input: name the output with -o, as in 'darkroom " + command + " " +
           input->as<std::string>() + " -o " + extra[0] + "'";
}

void run_batch(BatchOptions& o, int single_frame, bool frame_flag_given, int threads, bool verbose,
               const PrepareFrames& prepare, const DryRunCheck& dry_run_check) {
    const bool sequence = is_sequence_pattern(o.input) || is_sequence_pattern(o.output);
    if (sequence && frame_flag_given)
        throw UserError("--frame is for a single image: each frame of a sequence uses its own frame number");
    const ExpandedFrames expanded = expand_frames(o.input, o.output, o.sequence, single_frame);
    const std::vector<FrameJob>& jobs = expanded.jobs;
    require_known_compression(o.output, o.write.compression);
    require_format_holds(o.output, o.write.data_type);
    const std::map<fs::path, std::string> folders = output_folders(jobs);
    for (const auto& [folder, output] : folders) require_writable(output);  // a sequence's frames share theirs
    if (!o.run.log_path.empty()) require_folder(o.run.log_path);  // (else found after every frame is written)
    // Only an output named as the input itself replaces it; an output that merely resolves
    // to an input (another spelling of a pattern, a link) is refused frame by frame.
    o.run.in_place = fs::absolute(o.input).lexically_normal() == fs::absolute(o.output).lexically_normal();
    o.write.command_line = command_line();
    if (!o.run.dry_run) remove_stale_outputs_temps(folders, o.run.quiet);

    // A frame missing on disk is more often a render that failed than a range meant so.
    if (!expanded.missing_frames.empty())
        std::cerr << "darkroom: warning: the input sequence '" << o.input << "' has frames " << jobs.front().frame
                  << "-" << jobs.back().frame << " on disk but not " << expanded.missing_frames
                  << ", which are left out\n";

    // A single image is made silently, as oiiotool does, unless asked (-v, -n).
    const bool quiet = o.run.quiet || (!sequence && !o.run.dry_run && !verbose);
    Progress progress(jobs.size(), sequence, quiet, isatty(STDERR_FILENO) && sequence && !o.run.dry_run);
    threads = resolve_threads(threads);
    // OpenImageIO's own pool and OpenEXR's (which compresses and decompresses an EXR's blocks,
    // by default one a core) keep to --threads too, as oiiotool's --threads sets both.
    OIIO::attribute("threads", threads);
    OIIO::attribute("exr_threads", threads);
    {
        // Interrupted (Ctrl-C, a farm's kill), the bar's line ends before the interrupt's message
        // and the log still tells which frames were finished.
        InterruptHookScope log_on_interrupt([&](int signal_number) {
            progress.finish();
            if (!o.run.log_path.empty())
                write_run_log(o.run.log_path, progress.reports(), progress.elapsed_seconds(), command_line(),
                              signal_number);
        });
        run_frames(o.run, jobs, threads, verbose, prepare, dry_run_check, progress);
    }
    progress.finish();
    const std::vector<FrameReport> reports = progress.reports();
    if (!o.run.log_path.empty()) write_run_log(o.run.log_path, reports, progress.elapsed_seconds(), command_line());

    if (!sequence && reports.front().status == FrameReport::Status::failed) throw UserError(reports.front().error);
    if (std::string summary = failure_summary(reports, jobs.size()); !summary.empty()) throw UserError(summary);
}

}  // namespace darkroom::cli
