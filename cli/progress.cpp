#include "cli/progress.h"

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli/atomic_file.h"

namespace darkroom::cli {

const char* to_string(FrameReport::Status status) {
    switch (status) {
        case FrameReport::Status::developed: return "developed";
        case FrameReport::Status::skipped_existing: return "skipped (exists)";
        case FrameReport::Status::dry_run: return "dry run";
        case FrameReport::Status::failed: return "failed";
    }
    return "";
}

namespace {

std::string clock_time(double seconds) {
    long s = long(seconds + 0.5);
    char text[32];
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    return text;
}

}  // namespace

Progress::Progress(size_t total_frames, bool sequence, bool quiet, bool terminal)
    : total_(total_frames), sequence_(sequence), quiet_(quiet), terminal_(terminal),
      start_(std::chrono::steady_clock::now()) {}

double Progress::elapsed_seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::warn_once(const std::string& kind, FrameReport& report, const std::string& warning) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!warned_kinds_.insert(kind).second) return;
    }
    warn(report, warning);
}

void Progress::warn(FrameReport& report, const std::string& warning) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (terminal_ && !quiet_) std::cerr << "\r\033[K";
    const std::string frame = sequence_ ? "frame " + std::to_string(report.frame) + ": " : "";
    std::cerr << "darkroom: " << frame << "warning: " << warning << "\n";
    report.warnings.push_back(warning);
    if (terminal_ && !quiet_) draw_bar();
}

void Progress::add(FrameReport r) {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool failed = r.status == FrameReport::Status::failed;
    if (failed && sequence_) {
        if (terminal_ && !quiet_) std::cerr << "\r\033[K";
        std::cerr << "darkroom: frame " << r.frame << " (" << r.input << ") failed: " << r.error << "\n";
    }
    if (!quiet_ && !terminal_ && !failed) {
        if (sequence_) std::printf("frame %d: ", r.frame);
        std::printf("%s -> %s: %s", r.input.c_str(), r.output.c_str(), to_string(r.status));
        if (r.status == FrameReport::Status::developed)
            std::printf(" in %.2f s", r.read_seconds + r.develop_seconds + r.write_seconds);
        std::printf("\n");
        std::fflush(stdout);
    }
    reports_.push_back(std::move(r));
    if (terminal_ && !quiet_) draw_bar();
}

void Progress::draw_bar() const {
    if (finished_) return;
    const size_t done = reports_.size();
    const double elapsed = elapsed_seconds();
    const double fps = elapsed > 0 ? done / elapsed : 0;
    const int width = 30, filled = total_ ? int(width * done / total_) : width;
    std::string bar = "[" + std::string(filled, '#') + std::string(width - filled, '-') + "]";
    std::fprintf(stderr, "\r\033[K%s %zu/%zu frames  %.2f fps  %s left", bar.c_str(), done, total_, fps,
                 fps > 0 ? clock_time((total_ - done) / fps).c_str() : "?");
    std::fflush(stderr);
}

void Progress::finish() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (terminal_ && !quiet_ && !finished_) std::fprintf(stderr, "\n");
    finished_ = true;
}

std::vector<FrameReport> Progress::reports() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return reports_;
}

void write_run_log(const std::string& path, const std::vector<FrameReport>& reports, double elapsed_seconds,
                   const std::string& command_line, int interrupted_by_signal) {
    nlohmann::json frames = nlohmann::json::array();
    size_t failed = 0;
    for (const FrameReport& r : reports) {
        failed += r.status == FrameReport::Status::failed;
        nlohmann::json f = {{"frame", r.frame},
                            {"input", r.input},
                            {"output", r.output},
                            {"status", to_string(r.status)},
                            {"read_seconds", r.read_seconds},
                            {"develop_seconds", r.develop_seconds},
                            {"write_seconds", r.write_seconds},
                            {"start_seconds", r.start_seconds},
                            {"end_seconds", r.end_seconds},
                            {"warnings", r.warnings}};
        if (!r.error.empty()) f["error"] = r.error;
        frames.push_back(f);
    }
    nlohmann::json log = {{"command", command_line},
                          {"frames", frames},
                          {"summary",
                           {{"frames", reports.size()},
                            {"failed", failed},
                            {"elapsed_seconds", elapsed_seconds},
                            {"frames_per_second", elapsed_seconds > 0 ? reports.size() / elapsed_seconds : 0.0}}}};
    if (interrupted_by_signal) log["summary"]["interrupted_by_signal"] = interrupted_by_signal;
    write_text_atomically(path, log.dump(2) + "\n");
}

}  // namespace darkroom::cli
