#pragma once
/// The size limits the case harnesses read cases with: those of a machine of 1 GiB, so that a
/// case the reader accepts is one whose expansion (a fabric's fibers) fits in the memory that
/// scripts/fuzz.sh gives a run (-rss_limit_mb=2048). A case over them is refused with an
/// InputError, as on a machine of that size.
#include "fibra/model/model_size.hpp"

namespace fibra::fuzz {

inline SizeLimits size_limits() {
  SizeLimits limits;
  limits.memory = 1024.0 * 1024.0 * 1024.0;
  return limits;
}

}  // namespace fibra::fuzz
