#pragma once
/// The developers' trace switch: FIBRA_DEBUG_NEWTON set in the environment makes the solver
/// print every Newton iteration, normal update and cone freeze, and the contact checks say
/// which pair cut an increment. FIBRA_DEBUG_CHECKPOINT makes a run also save its state after
/// every increment (state/checkpoint_STEP_INCREMENT.bin), to study a long run's later
/// increments without running it again (copy one to state/STEP.bin of a run directory and go
/// on from it with [start]).
#include <cstdlib>

namespace fibra {

inline bool debug_newton() {
  static const bool on = std::getenv("FIBRA_DEBUG_NEWTON") != nullptr;
  return on;
}

inline bool debug_checkpoint() {
  static const bool on = std::getenv("FIBRA_DEBUG_CHECKPOINT") != nullptr;
  return on;
}

/// FIBRA_DEBUG_KILL=N: the run kills itself (SIGKILL) once the outputs of its N-th converged
/// increment are written, before its checkpoint: the tests of `fibra run --resume` stop runs
/// at chosen increments with it. 0 when unset.
inline int debug_kill_increment() {
  static const int n = std::getenv("FIBRA_DEBUG_KILL") ? std::atoi(std::getenv("FIBRA_DEBUG_KILL")) : 0;
  return n;
}

/// FIBRA_DEBUG_INTERRUPT=N: the run is interrupted (as by Ctrl-C) just before its N-th Newton
/// iteration (counted as summary.json's "iterations", a resumed run's included): the tests of
/// `fibra run --resume` interrupt runs within chosen increments with it. 0 when unset.
inline int debug_interrupt_iteration() {
  static const int n = std::getenv("FIBRA_DEBUG_INTERRUPT") ? std::atoi(std::getenv("FIBRA_DEBUG_INTERRUPT")) : 0;
  return n;
}

}  // namespace fibra
