#include "fibra/terms/binding_term.hpp"

#include <fmt/format.h>

#include "fibra/core/debug.hpp"

namespace fibra {

bool BindingTerm::update_lagged(const VecX& q, const LaggedTolerance& tolerance) {
  const double violation = m_bodies.violation(q), drift = m_bodies.anchor_drift(q);
  const bool satisfied = violation <= tolerance.length;
  // Anchored: no member moved more than the tolerance since its anchor, or the anchors' springs
  // (mu = 1e-10 k_ref) pull with less than a thousandth of the force the Newton solve leaves
  // (its tolerance times the reference force): either way they bias nothing. With the drift
  // alone, a settling increment of the 480-fiber twill's shear, the fabric still creeping under
  // the drag, restarted Newton after every solve (drift 1e-6 to 3e-5 m against 1e-7 m;
  // violation 6e-10 m) and failed after 30 updates, ~350 s; 12 of level 1's 19 updates were
  // drift alone (docs/performance.md, "Bindings: the anchors' drift").
  const double pull = m_bodies.proximal_stiffness() * drift;
  const bool anchored = drift <= tolerance.length || pull <= 1e-3 * tolerance.force;
  if (debug_newton() && !(satisfied && anchored))
    fmt::print(stderr, " bindings: violation {:.3e} m, anchors' drift {:.3e} m, tolerance {:.3e} m: updated\n",
               violation, drift, tolerance.length);
  if (!satisfied) m_bodies.update_multipliers(q);
  if (satisfied && anchored) return true;
  m_bodies.set_anchors(q);
  return false;
}

}  // namespace fibra
