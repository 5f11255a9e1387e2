#include "core/plane_memory.h"

#include <deque>
#include <mutex>
#include <new>

#include <pthread.h>

namespace darkroom {

namespace {

constexpr std::align_val_t kAlignment{64};
// Sizes are rounded up to a multiple of this, so that planes whose windows differ by a few
// pixels (a frame and its halos) share blocks.
constexpr size_t kGranuleBytes = size_t(1) << 18;

// A 4K fast-tier frame frees about 0.35 GB of planes in a run; an 8K frame four times that.
// Under AddressSanitizer nothing is kept, so that a plane used after it is freed is caught.
#if defined(__SANITIZE_ADDRESS__)
constexpr size_t kDefaultLimitBytes = 0;
#else
constexpr size_t kDefaultLimitBytes = size_t(2) << 30;
#endif

size_t size_class(size_t bytes) { return (bytes + kGranuleBytes - 1) / kGranuleBytes * kGranuleBytes; }

struct Pool {
    std::mutex mutex;
    std::deque<std::pair<size_t, void*>> kept;  // (size class, block), longest unused first
    size_t kept_bytes = 0;
    size_t limit_bytes = kDefaultLimitBytes;

    // Frees the longest-unused blocks until at most `bytes` are kept (mutex held).
    void trim_to(size_t bytes) {
        while (kept_bytes > bytes) {
            ::operator delete(kept.front().second, kAlignment);
            kept_bytes -= kept.front().first;
            kept.pop_front();
        }
    }
};

Pool& pool() {
    // Never destroyed: planes may be freed during static destruction.
    static Pool* p = [] {
        Pool* created = new Pool;
        // A fork while another thread holds the lock would leave the child's copy of it held
        // for ever (Python's multiprocessing forks): hold it across fork, as malloc does.
        pthread_atfork([] { pool().mutex.lock(); }, [] { pool().mutex.unlock(); }, [] { pool().mutex.unlock(); });
        return created;
    }();
    return *p;
}

}  // namespace

void* take_plane_memory(size_t bytes) {
    const size_t size = size_class(bytes);
    Pool& p = pool();
    {
        std::lock_guard<std::mutex> lock(p.mutex);
        // The most recently freed block of the class: its pages are the likeliest in cache.
        for (auto it = p.kept.rbegin(); it != p.kept.rend(); ++it)
            if (it->first == size) {
                void* block = it->second;
                p.kept_bytes -= size;
                p.kept.erase(std::next(it).base());
                return block;
            }
    }
    return ::operator new(size, kAlignment);
}

void give_plane_memory(void* block, size_t bytes) noexcept {
    const size_t size = size_class(bytes);
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.mutex);
    if (size > p.limit_bytes) {
        ::operator delete(block, kAlignment);
        return;
    }
    p.trim_to(p.limit_bytes - size);
    p.kept.emplace_back(size, block);
    p.kept_bytes += size;
}

size_t release_plane_memory() noexcept {
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.mutex);
    const size_t kept = p.kept_bytes;
    p.trim_to(0);
    return kept;
}

size_t kept_plane_memory_bytes() noexcept {
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.mutex);
    return p.kept_bytes;
}

size_t plane_memory_limit_bytes() noexcept {
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.mutex);
    return p.limit_bytes;
}

void set_plane_memory_limit_bytes(size_t bytes) noexcept {
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.mutex);
    p.limit_bytes = bytes;
    p.trim_to(bytes);
}

}  // namespace darkroom
