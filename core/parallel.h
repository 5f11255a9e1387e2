// A minimal row-parallel loop on std::thread, so core needs no thread library and an
// OFX host can still hand us its own threads (by calling with threads = 1 per tile).
//
// Work is split into contiguous row bands; each output row is computed by exactly one
// thread with the same code path, so results never depend on the thread count.
#pragma once

#include <algorithm>
#include <exception>
#include <functional>
#include <thread>
#include <vector>

namespace darkroom {

// threads <= 0 means all hardware threads.
inline int resolve_thread_count(int threads) {
    if (threads > 0) return threads;
    return std::max(1u, std::thread::hardware_concurrency());
}

// Calls body(begin, end) on disjoint sub-ranges of [begin, end). Exceptions propagate.
inline void parallel_for(int begin, int end, int threads, const std::function<void(int, int)>& body) {
    int n = end - begin;
    if (n <= 0) return;
    int workers = std::min(resolve_thread_count(threads), n);
    if (workers == 1) {
        body(begin, end);
        return;
    }
    std::vector<std::thread> pool;
    std::vector<std::exception_ptr> errors(workers);
    auto run = [&](int w) {
        try {
            body(begin + (int)((long long)n * w / workers), begin + (int)((long long)n * (w + 1) / workers));
        } catch (...) {
            errors[w] = std::current_exception();
        }
    };
    // The calling thread takes the last range itself: one thread fewer to start and join.
    for (int w = 0; w + 1 < workers; ++w) pool.emplace_back(run, w);
    run(workers - 1);
    for (auto& t : pool) t.join();
    for (auto& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace darkroom
