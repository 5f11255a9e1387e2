#include <catch2/catch.hpp>
#include <atomic>
#include <csignal>
#include <cstdint>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "core/image.h"
#include "core/plane_memory.h"

using namespace darkroom;

namespace {

// Sets the pool's limit for one test and restores it, with nothing kept before or after.
struct PoolLimit {
    size_t saved = plane_memory_limit_bytes();
    explicit PoolLimit(size_t bytes) {
        release_plane_memory();
        set_plane_memory_limit_bytes(bytes);
    }
    ~PoolLimit() {
        set_plane_memory_limit_bytes(saved);
        release_plane_memory();
    }
};

constexpr size_t kMiB = size_t(1) << 20;

}  // namespace

TEST_CASE("a freed large plane's memory serves the next plane of its size, and small planes are not kept",
          "[plane_memory]") {
    PoolLimit limit(64 * kMiB);
    const float* first;
    {
        Plane a = Plane::unset(Window{0, 0, 1024, 1024});  // 4 MiB
        first = a.pixels.data();
        CHECK(reinterpret_cast<uintptr_t>(first) % 64 == 0);
        CHECK(kept_plane_memory_bytes() == 0);
    }
    CHECK(kept_plane_memory_bytes() == 4 * kMiB);
    {
        // A window a few pixels smaller (a frame less its halo) is the same size class.
        Plane b(Window{5, 5, 1024, 1024}, 0.25f);
        CHECK(b.pixels.data() == first);
        CHECK(kept_plane_memory_bytes() == 0);
        // The reused memory holds the old plane's values; a filled plane is still filled.
        bool all_filled = true;
        for (float v : b.pixels) all_filled = all_filled && v == 0.25f;
        CHECK(all_filled);
    }
    {
        Plane small = Plane::unset(Window{0, 0, 256, 255});  // under 1 MiB: the C++ allocator's
    }
    CHECK(kept_plane_memory_bytes() == 4 * kMiB);
    release_plane_memory();
    CHECK(kept_plane_memory_bytes() == 0);
}

TEST_CASE("the plane memory kept stays within its limit, the longest unused freed first", "[plane_memory]") {
    PoolLimit limit(10 * kMiB);
    const float* addresses[3];
    {
        Plane planes[3];
        for (int i = 0; i < 3; ++i) {
            planes[i] = Plane::unset(Window{0, 0, 1024, 1024});
            addresses[i] = planes[i].pixels.data();
        }
        // Destroyed in reverse order: planes[2] is freed first, planes[0] last.
    }
    CHECK(kept_plane_memory_bytes() == 8 * kMiB);  // two of the three 4 MiB blocks
    Plane again = Plane::unset(Window{0, 0, 1024, 1024});
    CHECK(again.pixels.data() == addresses[0]);  // the most recently freed
    Plane next = Plane::unset(Window{0, 0, 1024, 1024});
    CHECK(next.pixels.data() == addresses[1]);
    CHECK(kept_plane_memory_bytes() == 0);
    // A block larger than the limit is never kept.
    { Plane huge = Plane::unset(Window{0, 0, 2048, 2048}); }  // 16 MiB
    CHECK(kept_plane_memory_bytes() == 0);
    // Lowering the limit frees what is kept beyond it.
    {
        Plane a = Plane::unset(Window{0, 0, 1024, 1024});
    }
    set_plane_memory_limit_bytes(2 * kMiB);
    CHECK(kept_plane_memory_bytes() == 0);
}

TEST_CASE("a process forked while another thread uses plane memory can still allocate planes", "[plane_memory]") {
    // Python's multiprocessing forks processes whose other threads may be developing: a child
    // must not inherit the pool's lock held.
    PoolLimit limit(64 * kMiB);
    std::atomic<bool> stop{false};
    std::thread churn([&] {
        while (!stop) Plane::unset(Window{0, 0, 512, 512});  // 1 MiB: taken and given back
    });
    int hung = 0;
    for (int i = 0; i < 40; ++i) {
        pid_t pid = fork();
        REQUIRE(pid >= 0);
        if (pid == 0) {
            Plane plane = Plane::unset(Window{0, 0, 512, 512});
            _exit(plane.pixels.empty() ? 1 : 0);
        }
        int status = 0;
        bool exited = false;
        for (int wait = 0; wait < 200 && !exited; ++wait) {  // up to 2 s
            exited = waitpid(pid, &status, WNOHANG) == pid;
            if (!exited) usleep(10000);
        }
        if (!exited) {
            ++hung;
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
        } else {
            CHECK((WIFEXITED(status) && WEXITSTATUS(status) == 0));
        }
    }
    stop = true;
    churn.join();
    CHECK(hung == 0);
}
