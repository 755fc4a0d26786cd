#include "fibra/core/heap.hpp"

#include <malloc.h>

#include <cstdlib>
#include <initializer_list>

namespace fibra {

bool keep_freed_memory() {
  for (const char* tuned : {"GLIBC_TUNABLES", "MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_",
                            "MALLOC_MMAP_MAX_"})
    if (std::getenv(tuned)) return false;
  // No block of the main thread comes from a mapping of its own, whatever its size (mallopt's
  // mapping threshold, an int, stops at 2 GB, which the factors of the sheared 480-fiber samples
  // reach), and the heap never gives its top back (-1: no trimming; at a trim threshold of 2 GB,
  // freeing a factor left 2 GB free at the top, which went back to the system and was faulted
  // in again by the next factorization). Each call returns 1 on success.
  const bool mmap = mallopt(M_MMAP_MAX, 0) == 1;
  const bool trim = mallopt(M_TRIM_THRESHOLD, -1) == 1;
  const bool pad = mallopt(M_TOP_PAD, 256 << 20) == 1;
  return mmap && trim && pad;
}

}  // namespace fibra
