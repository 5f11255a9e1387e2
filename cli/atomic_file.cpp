#include "cli/atomic_file.h"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <set>
#include <thread>
#include <unistd.h>

#include "cli/user_error.h"

namespace darkroom::cli {

namespace fs = std::filesystem;

namespace {

const std::string kTempPrefix = ".darkroom-tmp-";

std::mutex& registry_mutex() {
    static std::mutex m;
    return m;
}
std::set<std::string>& temps_in_flight() {
    static std::set<std::string> temps;
    return temps;
}

std::string host_name() {
    char name[256] = {};
    if (gethostname(name, sizeof name - 1) != 0) return "host";
    std::string host(name);
    std::replace(host.begin(), host.end(), '-', '_');  // '-' separates the fields of the name
    return host;
}

bool process_exists(long pid) { return kill(pid_t(pid), 0) == 0 || errno == EPERM; }

// Held by commits and, from before the interrupt hook runs until exit, by the waiting
// thread; recursive, since the hook commits its own file.
std::recursive_mutex& commit_mutex() {
    static std::recursive_mutex m;
    return m;
}

// The interrupt hook, and a lock held while it is set or runs.
std::mutex& hook_mutex() {
    static std::mutex m;
    return m;
}
std::function<void(int)>& interrupt_hook() {
    static std::function<void(int)> hook;
    return hook;
}

}  // namespace

void install_interrupt_cleanup() {
    static sigset_t signals;
    sigemptyset(&signals);
    // A signal ignored when the program started stays ignored (nohup's SIGHUP, a farm
    // wrapper's or a shell's background job's SIGINT): the caller decided it should not stop us.
    for (int s : {SIGINT, SIGTERM, SIGHUP}) {
        struct sigaction inherited {};
        if (sigaction(s, nullptr, &inherited) == 0 && inherited.sa_handler == SIG_IGN) continue;
        sigaddset(&signals, s);
    }
    pthread_sigmask(SIG_BLOCK, &signals, nullptr);
    std::thread([] {
        int signal_number = 0;
        if (sigwait(&signals, &signal_number) != 0) return;
        // No commit from here on: one in progress finishes (its output and its record) first.
        commit_mutex().lock();
        // The hook first, before the registry is held (it may write a file through a
        // TempFile); its lock is held until exit, so its owner cannot clear it meanwhile.
        hook_mutex().lock();
        if (interrupt_hook()) try {
                interrupt_hook()(signal_number);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "darkroom: %s\n", e.what());
            }
        // Hold the registry until exit: no new temporary can be registered after this.
        registry_mutex().lock();
        int removed = 0;
        for (const std::string& temp : temps_in_flight()) removed += std::remove(temp.c_str()) == 0;
        std::fprintf(stderr, "darkroom: interrupted by signal %d; removed %d partial output%s\n", signal_number,
                     removed, removed == 1 ? "" : "s");
        std::fflush(stderr);
        _exit(128 + signal_number);
    }).detach();
}

void set_interrupt_hook(std::function<void(int)> hook) {
    std::lock_guard<std::mutex> lock(hook_mutex());
    interrupt_hook() = std::move(hook);
}

TempFile::TempFile(const fs::path& target) : target_(target) {
    // The temporary keeps the target's extension so OpenImageIO picks the same format.
    temp_ = target.parent_path() /
            (kTempPrefix + host_name() + "-" + std::to_string(getpid()) + "-" + target.filename().string());
    std::lock_guard<std::mutex> lock(registry_mutex());
    temps_in_flight().insert(temp_.string());
}

TempFile::~TempFile() {
    std::lock_guard<std::mutex> lock(registry_mutex());
    if (!committed_) {
        std::error_code ec;
        fs::remove(temp_, ec);
    }
    temps_in_flight().erase(temp_.string());
}

bool TempFile::create(const std::function<bool()>& create_file) {
    std::lock_guard<std::mutex> lock(registry_mutex());
    return create_file();
}

void TempFile::commit(const std::function<void()>& committed) {
    std::lock_guard<std::recursive_mutex> lock(commit_mutex());
    std::error_code ec;
    fs::rename(temp_, target_, ec);
    if (ec) throw UserError("cannot move the finished output to '" + target_.string() + "': " + ec.message());
    committed_ = true;
    if (committed) committed();
}

void require_folder(const std::string& path) {
    const fs::path folder = fs::path(path).parent_path();
    if (!folder.empty() && !fs::is_directory(folder))
        throw UserError("cannot write '" + path + "': the folder '" + folder.string() + "' does not exist");
}

void write_text_atomically(const std::string& path, const std::string& text) {
    require_folder(path);
    TempFile temp{fs::path(path)};
    {
        std::ofstream out;
        if (!temp.create([&] {
                out.open(temp.path());
                return out.is_open();
            }))
            throw UserError("cannot write '" + path + "': " + std::strerror(errno));
        out << text;
        if (!out.flush()) throw UserError("cannot write '" + path + "': " + std::strerror(errno));
    }
    temp.commit();
}

int remove_stale_temps(const fs::path& directory) {
    const std::string own_prefix = kTempPrefix + host_name() + "-";
    int removed = 0;
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(directory.empty() ? "." : directory, ec)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind(own_prefix, 0) != 0) continue;
        const std::string rest = name.substr(own_prefix.size());
        char* end = nullptr;
        long pid = std::strtol(rest.c_str(), &end, 10);
        if (end == rest.c_str() || *end != '-' || pid == getpid() || process_exists(pid)) continue;
        removed += fs::remove(entry.path(), ec) ? 1 : 0;
    }
    return removed;
}

}  // namespace darkroom::cli
