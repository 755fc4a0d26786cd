#pragma once
/// The developers' trace switch: FIBRA_DEBUG_NEWTON set in the environment makes the solver
/// print every Newton iteration, normal update and cone freeze, and the contact checks say
/// which pair cut an increment.
#include <cstdlib>

namespace fibra {

inline bool debug_newton() {
  static const bool on = std::getenv("FIBRA_DEBUG_NEWTON") != nullptr;
  return on;
}

}  // namespace fibra
