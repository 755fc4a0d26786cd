#include "fibra/core/heap.hpp"

#include <malloc.h>

#include <climits>
#include <cstdlib>
#include <initializer_list>

namespace fibra {

bool keep_freed_memory() {
  for (const char* tuned : {"GLIBC_TUNABLES", "MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_",
                            "MALLOC_MMAP_MAX_"})
    if (std::getenv(tuned)) return false;
  // mallopt takes an int: blocks of up to 2 GB come from the heap; each call returns 1 on success.
  const bool mmap = mallopt(M_MMAP_THRESHOLD, INT_MAX) == 1;
  const bool trim = mallopt(M_TRIM_THRESHOLD, INT_MAX) == 1;
  const bool pad = mallopt(M_TOP_PAD, 256 << 20) == 1;
  return mmap && trim && pad;
}

}  // namespace fibra
