// Outputs appear complete or not at all: each is written to a hidden temporary name beside
// its target and renamed over it when complete.
//
// Temporary names are ".darkroom-tmp-<host>-<pid>-<target name>". While the program runs,
// every temporary file in flight is registered here; SIGINT, SIGTERM and SIGHUP remove them
// all before the program exits (status 128 + signal). A run killed without a chance to clean
// (SIGKILL, power loss) leaves its temporaries; remove_stale_temps() deletes those of this
// host whose process is gone, so a re-run cleans up after it.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace darkroom::cli {

// Blocks the termination signals in the calling thread (and so in every thread it starts
// afterwards) and starts a thread that waits for them, removes the temporaries in flight
// and exits. A signal ignored when the program started (nohup, trap '' HUP) is left
// ignored. Call once, first thing in main, before any other thread exists.
void install_interrupt_cleanup();

// What to do on such a signal before the temporaries are removed (the develop command writes
// its --log of the frames finished so far), on the waiting thread; an empty function clears
// it. Setting or clearing waits for a hook that is running to finish.
void set_interrupt_hook(std::function<void(int signal_number)> hook);

// Clears the interrupt hook when it goes out of scope (before what the hook refers to does).
struct InterruptHookScope {
    explicit InterruptHookScope(std::function<void(int signal_number)> hook) { set_interrupt_hook(std::move(hook)); }
    ~InterruptHookScope() { set_interrupt_hook({}); }
    InterruptHookScope(const InterruptHookScope&) = delete;
    InterruptHookScope& operator=(const InterruptHookScope&) = delete;
};

// A temporary file beside `target`, registered for removal on interrupt. Destroying it
// without commit() removes the file.
class TempFile {
public:
    explicit TempFile(const std::filesystem::path& target);
    ~TempFile();
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;

    const std::filesystem::path& path() const { return temp_; }
    // Runs `create_file` (which creates the temporary at path()) while an interrupt's cleanup
    // cannot run, and returns its result: a file created after the cleanup swept the
    // registry, but before the process exited, would outlive it.
    bool create(const std::function<bool()>& create_file);
    // Renames the temporary over the target, then runs `committed` (what records the output
    // as finished), both before or both after an interrupt's hook: the hook (the develop
    // command's --log) never sees a finished output unrecorded. Throws UserError if the
    // rename fails.
    void commit(const std::function<void()>& committed = {});

private:
    std::filesystem::path target_, temp_;
    bool committed_ = false;
};

// Throws UserError naming `path` when the folder it would go in does not exist, so that a
// command can refuse before it does the work.
void require_folder(const std::string& path);

// Writes `text` to `path` through a TempFile; UserError naming `path` and why if it cannot.
void write_text_atomically(const std::string& path, const std::string& text);

// Removes this host's temporaries in `directory` whose process no longer runs; returns how
// many it removed.
int remove_stale_temps(const std::filesystem::path& directory);

}  // namespace darkroom::cli
