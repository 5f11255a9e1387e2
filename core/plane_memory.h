// Memory for large planes, recycled between the planes of a run and between runs.
//
// A 4K frame developed stage after stage (core/develop.cpp: the high and reference tiers,
// the texture output) allocates and frees about fifteen planes of 35 MB. glibc maps blocks
// that large afresh from the kernel and unmaps them when freed, so each new plane faulted
// its zeroed pages in again: a 4K fast-tier frame took 430 ms instead of 280 ms (2 threads)
// in every process that had not changed malloc's thresholds (the Python module, OFX hosts).
// Blocks of kPooledBytes or more therefore come from here: a freed block is kept and handed
// to the next request of its size class. At most the limit is kept (2 GiB; none under
// AddressSanitizer, which then catches a plane used after it is freed), the longest-unused
// blocks freed first; release_plane_memory() frees all that is kept.
#pragma once

#include <cstddef>

namespace darkroom {

// Requests from this size up are pooled; smaller ones go to the C++ allocator.
constexpr size_t kPooledBytes = size_t(1) << 20;

// A block of at least `bytes`, 64-byte aligned; throws std::bad_alloc.
void* take_plane_memory(size_t bytes);
// Gives back a block from take_plane_memory, with the same `bytes` it was asked for.
void give_plane_memory(void* block, size_t bytes) noexcept;

// Frees every block kept for reuse (an OFX host's purge-caches action calls it); returns
// the bytes freed.
size_t release_plane_memory() noexcept;
// The bytes kept for reuse now, and the most that is kept (the oldest go first beyond it).
size_t kept_plane_memory_bytes() noexcept;
size_t plane_memory_limit_bytes() noexcept;
void set_plane_memory_limit_bytes(size_t bytes) noexcept;

}  // namespace darkroom
