// A command's images or frame sequences run as a batch, in oiiotool's conventions, for the
// commands that turn input images into output images one frame at a time (develop, grain
// apply): the input and output names and their sequences, how each output is written, and
// the run's flags (dry run, quiet, no clobber, skip bad frames, frames at once, log); each
// frame reported as it ends (a bar on a terminal, a line per frame otherwise), a failure
// naming its frame, an interrupted run logging what was finished.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "cli/atomic_file.h"
#include "cli/image_io.h"
#include "cli/progress.h"
#include "cli/sequence.h"

namespace darkroom::cli {

struct RunOptions {
    bool dry_run = false, quiet = false, no_clobber = false, skip_bad_frames = false;
    bool in_place = false;   // -o names the input itself: each frame replaces its input
    int frames_at_once = 0;  // 0: min(threads, frames, kDefaultMaxFramesAtOnce)
    bool overlap = true;     // each frame written while the next is read and developed
    std::string log_path;
};

struct BatchOptions {
    std::string input, output;
    SequenceOptions sequence;
    WriteOptions write;
    RunOptions run;
};

// The flags above on `cmd` (not read from look files: they are the run's, not the look's).
void add_batch_flags(CLI::App& cmd, BatchOptions& o, const std::string& input_help, const std::string& output_help);

// --layer on `cmd`: the layer or part of a layered or multi-part input that `verb` reads.
void add_layer_flag(CLI::App& cmd, std::optional<std::string>& layer, const std::string& verb);

// For a command line CLI11 refused, when `cmd` (with the flags above) was given a second
// name and no -o, as oiiotool's habit `develop in.exr out.exr` does: how to name the output.
// Empty otherwise.
std::string output_flag_hint(const CLI::App& cmd);

double seconds_since(std::chrono::steady_clock::time_point start);

// That job's output can hold the parts of `input` (refused before the work, as
// require_holds_parts), and a warning once a run where it cannot keep their uint32 channels.
void check_output_holds_parts(const FrameJob& job, const LoadedImage& input, FrameReport& report,
                              Progress& progress);

// A frame's output, once the frame is developed: written under its temporary name
// (write_image_to_temp), which the batch commits in frame order.
using FrameWrite = std::function<std::unique_ptr<TempFile>()>;
// One frame's work: read job.input and develop it with `threads`; `first` for the run's first
// frame (where -v prints what a run's frames share). Returns how to write job.output, which
// the batch runs while the next frame is read and developed.
using FrameWork =
    std::function<FrameWrite(const FrameJob& job, int threads, bool first, FrameReport& report, Progress& progress)>;
// What the frames share, made once the threads each frame gets are known.
using PrepareFrames = std::function<FrameWork(int threads_per_frame)>;
// A dry run's look at a frame: the warnings and refusals the run would give from its input's
// header (read_image_header), before its pixels.
using DryRunCheck = std::function<void(const FrameJob& job, FrameReport& report, Progress& progress)>;

// Expands o's names into frames (a single image is frame `single_frame`; `frame_flag_given`:
// --frame was given, which a sequence refuses), checks every output can be written before any
// frame is read, runs the frames (in parallel, sharing `threads`, 0 = all cores; each frame's
// write overlapping the next frame's read and develop) and throws UserError naming each frame
// that failed. Frames are reported, and their outputs take their names, in frame order. `verbose` prints how the threads are split. A dry
// run (-n) runs `dry_run_check` on each frame (else reads its input's header), and warns of what it refuses.
void run_batch(BatchOptions& o, int single_frame, bool frame_flag_given, int threads, bool verbose,
               const PrepareFrames& prepare, const DryRunCheck& dry_run_check = {});

}  // namespace darkroom::cli
