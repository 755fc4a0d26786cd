#pragma once
/// The tows of a case as fiber indices of its model, with one orientation per tow so that the
/// fiber directions the export writes agree in sign: a tow's direction is the mean of its
/// fibers' end-to-end chords (each counted along the first fiber's), turned so that its
/// largest component is positive; a fiber runs along its tow's direction or against it.
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// Tow membership and orientation of the fibers of a model at a state.
struct TowFibers {
  std::vector<std::vector<int>> fibers;  ///< per tow: its fibers (indices into Model::fibers)
  std::vector<Vec3> direction;           ///< per tow: unit mean chord, largest component > 0
  std::vector<int> tow_of_fiber;         ///< per fiber: its tow, -1 for none
  /// Per fiber: +1 when its nodes run along its reference direction (its tow's, or for a
  /// fiber in no tow its own chord turned like a tow's), -1 against it.
  std::vector<double> sign;
};

/// Membership and orientation; `tows` are those of the case the model was built from (their
/// fiber names were checked by the reader).
TowFibers tow_fibers(const Model& model, const VecX& q, const std::vector<TowSpec>& tows);

/// End-to-end chord of a fiber at state q: last centroid minus first [m].
Vec3 fiber_chord(const Model& model, const VecX& q, const Fiber& fiber);

}  // namespace fibra
