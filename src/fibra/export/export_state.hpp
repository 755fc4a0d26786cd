#pragma once
/// What `fibra export` computes from a state, before anything is written: the tows'
/// envelopes, kept apart where tows touch (envelope_separation.hpp), and the voxel model
/// (docs/export.md).
#include <vector>

#include "fibra/export/envelope_separation.hpp"
#include "fibra/export/tow_envelope.hpp"
#include "fibra/export/tow_fibers.hpp"
#include "fibra/export/voxel_model.hpp"

namespace fibra {

/// Rounds of the envelopes' separation at most, and its step as a share of the smallest
/// semi-axis of the tows' fibers.
inline constexpr int kSeparationRounds = 200;
inline constexpr double kSeparationStep = 1.0 / 50.0;

/// The exported geometry of a state.
struct ExportedState {
  TowFibers tows;
  std::vector<TowEnvelope> envelopes;  ///< one per tow with fibers, in the case's order
  Separation separation;
  VoxelModel voxels;
};

/// The envelopes of the tows, separated.
std::vector<TowEnvelope> tow_envelopes(const Model& model, const VecX& q, const TowFibers& tows,
                                       const EnvelopeOptions& options, Separation* separation = nullptr);

/// Envelopes of the tows `tows` (those of the case the model was built from) at state q, and
/// the voxel model of `grid` with samples^3 points per voxel.
ExportedState export_state(const Model& model, const VecX& q, const std::vector<TowSpec>& tows, const VoxelGrid& grid,
                           int samples);

}  // namespace fibra
