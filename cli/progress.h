// What a batch run tells its user while it runs and leaves behind when it ends: a progress
// bar on a terminal (frames done, frames per second, time left), one plain line per frame
// otherwise, and with --log a JSON file of per-frame timings, warnings and errors.
#pragma once

#include <chrono>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace darkroom::cli {

struct FrameReport {
    enum class Status { developed, skipped_existing, dry_run, failed };
    int frame = 0;
    std::string input, output;
    Status status = Status::developed;
    double read_seconds = 0, develop_seconds = 0, write_seconds = 0;
    // In flight (its pixels held) from `start_seconds` to `end_seconds` after the run began.
    double start_seconds = 0, end_seconds = 0;
    std::vector<std::string> warnings;
    std::string error;  // when failed
};

const char* to_string(FrameReport::Status status);

class Progress {
public:
    // `terminal`: draw a bar on stderr; otherwise print a line per frame on stdout.
    // `sequence`: messages name the frame ("frame 12:"); a single image's name no frame, and
    // its failure is left to the caller (it is the run's error).
    Progress(size_t total_frames, bool sequence, bool quiet, bool terminal);
    // Ends the bar's line if finish() has not: a run that throws leaves no prompt after the bar.
    ~Progress() { finish(); }
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    // Thread-safe, and printed even when quiet. A warning is printed when it arises (a render
    // that will take hours says so before it starts) and kept in the frame's report for the log.
    void warn(FrameReport& report, const std::string& warning);
    // The same, the first time a warning of this `kind` arises in the run only (a sequence's
    // frames share their colour tag, their parts, a render's cost).
    void warn_once(const std::string& kind, FrameReport& report, const std::string& warning);
    // A frame's report, when it is finished (or failed, or skipped).
    void add(FrameReport report);
    // Ends the bar's line, once: when the run ends, or when it is interrupted, before what
    // the interrupt prints. No bar is drawn after it.
    void finish();

    std::vector<FrameReport> reports() const;
    double elapsed_seconds() const;

private:
    void draw_bar() const;

    mutable std::mutex mutex_;
    size_t total_;
    bool sequence_, quiet_, terminal_;
    bool finished_ = false;
    std::chrono::steady_clock::time_point start_;
    std::vector<FrameReport> reports_;
    std::set<std::string> warned_kinds_;
};

// The --log file: every frame's report and a summary, written atomically. A run stopped by
// a signal logs the frames finished before it, and the signal's number in the summary.
void write_run_log(const std::string& path, const std::vector<FrameReport>& reports, double elapsed_seconds,
                   const std::string& command_line, int interrupted_by_signal = 0);

}  // namespace darkroom::cli
