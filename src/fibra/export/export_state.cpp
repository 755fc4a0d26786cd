#include "fibra/export/export_state.hpp"

#include <algorithm>
#include <limits>

namespace fibra {

namespace {

double smallest_semi_axis(const Model& model, const TowFibers& tows) {
  double smallest = std::numeric_limits<double>::infinity();
  for (const auto& fibers : tows.fibers)
    for (int f : fibers) {
      const Section& s = model.sections[model.fibers[f].section];
      smallest = std::min({smallest, s.a, s.b});
    }
  return smallest;
}

}  // namespace

std::vector<TowEnvelope> tow_envelopes(const Model& model, const VecX& q, const TowFibers& tows,
                                       const EnvelopeOptions& options, Separation* separation) {
  std::vector<TowEnvelope> envelopes;
  for (int t = 0; t < static_cast<int>(tows.fibers.size()); ++t)
    if (!tows.fibers[t].empty()) envelopes.push_back(tow_envelope(model, q, tows, t, options));
  const Separation s =
      separate_envelopes(envelopes, kSeparationStep * smallest_semi_axis(model, tows), kSeparationRounds);
  if (separation) *separation = s;
  return envelopes;
}

ExportedState export_state(const Model& model, const VecX& q, const std::vector<TowSpec>& tows, const VoxelGrid& grid,
                           int samples) {
  ExportedState s;
  s.tows = tow_fibers(model, q, tows);
  s.envelopes = tow_envelopes(model, q, s.tows, EnvelopeOptions{}, &s.separation);
  s.voxels = voxel_model(model, q, s.tows, s.envelopes, grid, samples);
  return s;
}

}  // namespace fibra
