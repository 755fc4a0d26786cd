#pragma once
/// How the process's heap treats the large blocks the solver allocates and frees.

namespace fibra {

/// Keeps large freed blocks in the heap for the next request instead of returning them to the
/// system. Each factorization and each new contact pattern allocates and frees blocks of tens
/// of MB to 2 GB (CHOLMOD's factor and its permuted copy of the matrix, the Hessian's values);
/// glibc maps blocks above 128 kB to fresh pages and unmaps them on free, and gives the free
/// memory at its heap's top back to the system, so the kernel zeroes every such block page by
/// page again: 22 M page faults and 538 s of system time in a 40-minute 480-fiber weave and
/// relax (docs/performance.md, "Memory: freed blocks kept"). Every block of the main thread then
/// comes from the heap, which keeps its freed memory: the process holds its peak heap until it
/// ends. Call it first thing in main(), before any allocation that matters. Does nothing, and
/// returns false, when the user tunes malloc through the environment (GLIBC_TUNABLES or one of
/// the MALLOC_*_ variables); returns true once the settings are made. `fibra` and the
/// benchmarks call it, so the benchmarks measure the heap that `fibra` runs with.
bool keep_freed_memory();

}  // namespace fibra
