#pragma once
/// A run's final state read back from its output directory: the model rebuilt from the
/// expanded case.toml the run wrote, the node values from its nodes.csv (the path of
/// `fibra slice`).
#include <string>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// The case, its model and the final state of a run.
struct ResultState {
  Case c;
  Model model;
  VecX q;  ///< 9 values per node, then the bodies' (their reference values)
};

/// Reads RESULT_DIR/case.toml and RESULT_DIR/nodes.csv. Throws InputError naming the
/// directory or the file when it is missing or does not read; `command` ("fibra export")
/// is named in the message.
ResultState read_result_state(const std::string& dir, const std::string& command);

}  // namespace fibra
