#include "fibra/export/envelope_separation.hpp"

#include <algorithm>
#include <set>
#include <utility>

#include "fibra/export/triangle_intersection.hpp"

namespace fibra {

namespace {

using LineSet = std::set<std::pair<int, int>>;  // (station, support line)

/// Marks the support lines through the contour vertices of triangle t (vertex j lies on lines j
/// and j + 1; the caps' centres move with their station).
void mark_lines(const TowEnvelope& env, Index t, LineSet& lines) {
  const int m = static_cast<int>(env.insets.front().size());
  const int contour_points = static_cast<int>(env.stations.size()) * m;
  for (int p : env.surface.triangles[t]) {
    if (p >= contour_points) continue;
    lines.insert({p / m, p % m});
    lines.insert({p / m, (p % m + 1) % m});
  }
}

/// Moves the marked lines inward by one step; false when none could move.
bool move_inward(TowEnvelope& env, const LineSet& lines, double step) {
  std::set<int> stations;
  bool moved = false;
  for (const auto& [k, j] : lines) {
    double& inset = env.insets[k][j];
    const double next = std::min(inset + step, env.largest_inset[k]);
    moved = moved || next > inset;
    inset = next;
    stations.insert(k);
  }
  for (int k : stations) update_contour(env, k);
  return moved;
}

}  // namespace

std::vector<EnvelopeClash> envelope_clashes(const std::vector<TowEnvelope>& envelopes) {
  std::vector<EnvelopeClash> clashes;
  for (size_t a = 0; a < envelopes.size(); ++a)
    for (size_t b = a + 1; b < envelopes.size(); ++b) {
      if (!mesh_bounds(envelopes[a].surface).intersects(mesh_bounds(envelopes[b].surface))) continue;
      const auto pairs = intersecting_triangles(envelopes[a].surface, envelopes[b].surface);
      if (!pairs.empty()) clashes.push_back({envelopes[a].tow, envelopes[b].tow, static_cast<Index>(pairs.size())});
    }
  return clashes;
}

Separation separate_envelopes(std::vector<TowEnvelope>& envelopes, double step, int max_rounds) {
  Separation s;
  const size_t n = envelopes.size();
  for (; s.rounds < max_rounds; ++s.rounds) {
    std::vector<LineSet> lines(n);
    bool any = false;
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b) {
        if (!mesh_bounds(envelopes[a].surface).intersects(mesh_bounds(envelopes[b].surface))) continue;
        for (const auto& [ta, tb] : intersecting_triangles(envelopes[a].surface, envelopes[b].surface)) {
          mark_lines(envelopes[a], ta, lines[a]);
          mark_lines(envelopes[b], tb, lines[b]);
          any = true;
        }
      }
    if (!any) break;
    bool moved = false;
    for (size_t a = 0; a < n; ++a) moved = move_inward(envelopes[a], lines[a], step) || moved;
    if (!moved) break;
  }
  for (const TowEnvelope& env : envelopes)
    for (const auto& station : env.insets)
      for (double inset : station) s.largest_inset = std::max(s.largest_inset, inset);
  s.remaining = envelope_clashes(envelopes);
  return s;
}

}  // namespace fibra
