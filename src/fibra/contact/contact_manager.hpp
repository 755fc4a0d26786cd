#pragma once
/// Contact bookkeeping between the solver's loops (METHOD §3-4): builds contact elements from a
/// detection (laws, history carried over), updates normals, adapts the penalty per proximity
/// zone. The contact energy term commits the friction history (terms/contact_term.hpp).
#include <functional>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "fibra/contact/contact_element.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

struct Detection;
class ContactDetector;

/// Per-increment contact statistics (for history.csv).
struct ContactStats {
  int zones = 0;                     ///< proximity zones
  int elements = 0;                  ///< contact elements
  double max_penetration_ratio = 0;  ///< largest penetration / smaller radius of its pair
  double total_normal_force = 0;     ///< sum of normal forces [N]
  double detection_time = 0;         ///< time spent in detection during the increment [s]
  int detections = 0;                ///< detection loops of the increment
  int normal_updates = 0;            ///< normal-update loops of the increment
  int penalty_raises = 0;            ///< zones whose penalty was raised in the increment
  int penalty_softenings = 0;        ///< zones whose penalty was lowered at the end of the increment
};

/// Contact state across increments.
class ContactManager {
 public:
  /// Settings from the case's [contact] table; the model is kept by reference.
  ContactManager(const Model& model, const ContactSpec& spec);
  ~ContactManager();

  /// Detects at q and returns the new contact elements: normals from the detection, penalty of
  /// the matching previous element (or the initial one), friction history carried over from
  /// `previous` (matched by fiber pair and arc length), separations measured at `q_start`.
  std::vector<ContactElement> detect(const VecX& q, const VecX& q_start, const std::vector<ContactElement>& previous);
  /// Computes each normal as the unit vector between its section centres at q. Elements that
  /// carry no force at q with either normal (gap >= 0 with both) take theirs at once: their
  /// energy is zero before and after, the equilibrium does not see it. The others take theirs
  /// only if one of them turned by the normal tolerance or more, and then all at once. Returns
  /// the largest turn among the elements that carry force [rad] (what decides whether the
  /// normals settled); `idle_turn`, if given, gets the largest turn among the others; `slide`
  /// the largest distance across its old normal between the particles of an element that
  /// carries force, relative to the sum of its fibers' radii (detected, they face each other).
  double update_normals(std::vector<ContactElement>& contacts, const VecX& q, double* idle_turn = nullptr,
                        double* slide = nullptr) const;
  /// Weaving (METHOD §6): every element whose fibers `rule(fiber_a, fiber_b)` maps to +1 or -1
  /// gets the normal rule * `direction` (from A towards B), its border particles re-chosen to
  /// face that way, and is marked prescribed (update_normals leaves it); `offset` is added to
  /// its gap (penetration the law does not see yet: the tows separate progressively).
  /// Returns the largest penetration of the prescribed elements without the offset [m].
  double prescribe_normals(std::vector<ContactElement>& contacts, const VecX& q, const Vec3& direction,
                           const std::function<int(int, int)>& rule, double offset) const;
  /// Raises the penalty of every zone whose largest penetration exceeds the allowed one; returns
  /// the number of zones raised.
  int adapt_penalty(std::vector<ContactElement>& contacts, const std::vector<ContactResponse>& responses) const;
  /// The other way: a zone whose deepest penetration is below 35 % of the allowed one gets its
  /// penalty lowered towards 70 % of it (by at most 4 per call, never below `floor`). Returns
  /// the zones softened.
  int soften_penalty(std::vector<ContactElement>& contacts, const std::vector<ContactResponse>& responses,
                     double floor) const;
  /// True if a contact element without history penetrates deeper than a fiber can within one
  /// increment (a crossing missed between detections).
  /// `where`, when set, receives the element pair of the first such element.
  bool passed_through(const std::vector<ContactElement>& contacts, const std::vector<ContactResponse>& responses,
                      std::pair<Index, Index>* where = nullptr) const;
  /// True if the centroid lines of two elements crossed each other between q_start and q (a
  /// pass-through that detections at both states would miss). Candidate pairs come from a
  /// broad phase at the mid state with boxes grown by the largest nodal motion; each element is
  /// taken as its chord (moving linearly in time), and a crossing is a sign change, along the
  /// chords' common normal, of the vector between their closest points, with the chords closer
  /// than half the sum of the radii when it vanishes (through each other, not around an end nor
  /// side by side).
  /// `where`, when set, receives the element pair that crossed.
  bool crossed(const VecX& q_start, const VecX& q, std::pair<Index, Index>* where = nullptr) const;
  /// Largest penetration of `contacts` at q (gaps along their own normals), divided by the
  /// allowed penetration of each pair.
  double penetration_ratio(const std::vector<ContactElement>& contacts, const VecX& q) const;
  /// Fills the state statistics of `out` (zones, elements, largest penetration ratio, total
  /// normal force) from contacts at their responses; the loop counters are left as they are.
  void add_stats(const std::vector<ContactElement>& contacts, const std::vector<ContactResponse>& responses,
                 ContactStats& out) const;
  /// Friction parameters.
  FrictionParams friction() const { return m_friction; }
  const ContactSpec& spec() const { return m_spec; }  ///< settings
  int zones() const { return m_zones; }               ///< zones of the last detection
  /// The detector's memory of its last detection (ContactDetector::memory), and its restoring.
  std::vector<std::vector<std::uint64_t>> detection_memory() const;
  void set_detection_memory(const std::vector<std::vector<std::uint64_t>>& memory);
  double initial_stiffness() const { return m_initial_stiffness; }  ///< initial penalty [N/m]

 private:
  double pair_radius(const ContactElement& c) const;  // smaller section radius of the pair
  // Per zone, the largest penetration of its elements at `responses`, over the allowed one.
  std::map<int, double> zone_penetration(const std::vector<ContactElement>& contacts,
                                         const std::vector<ContactResponse>& responses) const;
  double arc_length(const Particle& p) const;         // reference arc length along its fiber

  const Model& m_model;
  ContactSpec m_spec;
  FrictionParams m_friction;
  std::unique_ptr<ContactDetector> m_detector;
  double m_initial_stiffness = 0;
  int m_zones = 0;
};

}  // namespace fibra
