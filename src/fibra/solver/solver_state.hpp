#pragma once
/// The solver's state at the end of a step, saved as `state.bin` in a result directory so that
/// a later run can go on from it (`[start] from = DIR`): weave a fabric once, test it many
/// times. Everything the next step needs: nodal and body values, the bodies' committed frames
/// and binding multipliers, the contact elements with their history, and the loads and
/// prescribed values in force (docs/outputs.md, "state.bin").
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "fibra/contact/contact_element.hpp"
#include "fibra/core/types.hpp"

namespace fibra {

struct Model;

/// Identifies the model a state belongs to: its sizes (the reference configuration is stored
/// alongside and compared within round-off).
struct ModelFingerprint {
  std::int64_t dofs = 0, elements = 0, bodies = 0, bindings = 0;
  bool operator==(const ModelFingerprint&) const = default;
};

/// Fingerprint of `model` with `bindings` averaged bindings.
ModelFingerprint fingerprint(const Model& model, Index bindings);

struct SolverState {
  ModelFingerprint model;
  VecX reference;          ///< the model's reference configuration (checked on restore)
  std::string step;        ///< name of the step whose end this is
  int steps_done = 0;      ///< steps of its run completed
  VecX q;                  ///< nodal and body dofs
  std::vector<double> bodies;  ///< BodySystem::snapshot()
  std::vector<ContactElement> contacts;
  VecX force_end;                                     ///< loads in force, per dof
  std::map<Index, std::pair<Vec3, Vec3>> moments;     ///< nodal moments in force (start, end)
  std::map<Index, std::pair<double, double>> disp;    ///< prescribed dofs (start, end) of q - reference
  /// The drag stiffness [N/m] that applied the last load level of a test step (biaxial, shear)
  /// in the run that wrote the state (0 before any): a run going on from the state loads its
  /// first test level with at least that drag. Not in version-1 files (read as 0).
  double test_drag = 0.0;
};

/// Writes `state` to `path` (write_file_atomic: through a temporary file renamed into place;
/// throws RunError).
void write_state_file(const std::string& path, const SolverState& state);
/// Reads a state file; throws InputError naming `path` if it is missing, truncated or not a
/// state file of this version.
SolverState read_state_file(const std::string& path);
/// Checks that `state` (read from `path`) belongs to `model` with `bindings` bindings: its
/// fingerprint, its reference configuration, its prescribed dofs and moments; throws
/// InputError naming `path` and what differs.
void check_state_fits(const SolverState& state, const Model& model, Index bindings, const std::string& path);

}  // namespace fibra
