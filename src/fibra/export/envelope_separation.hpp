#pragma once
/// Keeping the envelopes of different tows apart (docs/export.md, "Tow envelopes"). Where two
/// tows touch, their fibers nest into each other (a fiber of one lies in the hollow between
/// two fibers of the other) and overlap a little (contact is a penalty), so the convex
/// contours of the two tows overlap there. Each round finds the triangles of different
/// envelopes that intersect and moves the support lines through their vertices inward by one
/// step, on both envelopes, until no two envelopes intersect: the lines move only where the
/// envelopes meet, and only as far as needed (to a step).
#include <vector>

#include "fibra/export/tow_envelope.hpp"

namespace fibra {

/// Two tows whose envelopes intersect.
struct EnvelopeClash {
  int tow_a = 0, tow_b = 0;
  Index triangle_pairs = 0;  ///< pairs of their triangles that intersect
};

/// What the separation did.
struct Separation {
  int rounds = 0;
  double largest_inset = 0;              ///< the most a support line was moved inward [m]
  std::vector<EnvelopeClash> remaining;  ///< envelopes still intersecting (a line at its limit, or out of rounds)
};

/// The pairs of envelopes that intersect (boxes first, then triangle against triangle).
std::vector<EnvelopeClash> envelope_clashes(const std::vector<TowEnvelope>& envelopes);

/// Moves support lines inward by `step` [m] per round, at most `max_rounds` rounds.
Separation separate_envelopes(std::vector<TowEnvelope>& envelopes, double step, int max_rounds);

}  // namespace fibra
