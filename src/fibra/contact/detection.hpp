#pragma once
/// Contact detection (METHOD §2): broad phase, proximity zones, intermediate geometry and
/// contact elements (pairs of border particles facing each other). What is computed, with
/// every choice and default: docs/theory/contact.md, "Detection".
#include <cstdint>
#include <memory>
#include <vector>

#include "fibra/contact/broad_phase.hpp"
#include "fibra/contact/contact_element.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// Centre and section vectors at eta of an element (its 27 dofs q_e).
void section_at(const double* q_e, double eta, Vec3& x0, Vec3& g1, Vec3& g2);
/// Section coordinates (xi1, xi2) of the border point of the ellipse (semi-axes a along g1, b
/// along g2) in the direction of `toward` projected on the section plane.
void border_point(const Vec3& g1, const Vec3& g2, const Vec3& toward, double a, double b, double& xi1, double& xi2);

/// Detection settings; a zero selects the default, which depends on the pair's radii.
struct DetectionParams {
  /// Extra distance beyond r_i + r_j for proximity [m]; 0 -> half the smaller radius of the pair.
  double margin = 0;
  /// Spacing of contact elements along the intermediate geometry [m]; 0 -> the smaller radius of the pair.
  double spacing = 0;
  /// Same-fiber arc-length exclusion [m]; 0 -> 4 (r_i + r_j) = 8 r.
  double self_exclusion = 0;
};

/// A proximity zone: a part of fiber i close to a part of fiber j (i <= j; i == j: self-contact).
struct ProximityZone {
  int fiber_i = 0;        ///< sampled fiber: the lower index, or the thinner one when over 3 times thinner
  int fiber_j = 0;        ///< other fiber
  double s_begin = 0;     ///< start of the zone on fiber i, reference arc length [m]
  double s_end = 0;       ///< end of the zone on fiber i, reference arc length [m]
  int first_element = 0;  ///< index of its first contact element in Detection::elements
  int num_elements = 0;   ///< number of its contact elements (>= 1)
};

/// Result of one detection: zones sorted by (fiber_i, fiber_j, s_begin), their contact
/// elements contiguous and in the same order (along the intermediate geometry).
struct Detection {
  std::vector<ProximityZone> zones;      ///< proximity zones
  std::vector<ContactElement> elements;  ///< contact elements (law and friction left default)
  double time = 0;                       ///< wall time of the detection [s]
};

/// Detects proximity zones and builds contact elements at given dofs; keeps its buffers
/// between calls. The model must outlive the detector.
class ContactDetector {
 public:
  /// Prepares the detector for `model`.
  explicit ContactDetector(const Model& model, DetectionParams params = {});
  ~ContactDetector();                                           ///< out of line (private workspace type)
  ContactDetector(const ContactDetector&) = delete;             ///< not copyable
  ContactDetector& operator=(const ContactDetector&) = delete;  ///< not copyable

  /// Detection at dofs q (size model.num_dofs()).
  Detection detect(const VecX& q);
  /// Detection at dofs q into `out`, reusing its capacity.
  void detect(const VecX& q, Detection& out);

  const BroadPhase& broad_phase() const { return m_broad; }   ///< the broad phase (last boxes and pairs)
  /// What a detection remembers of the last one, per fiber: the zone ends given their own
  /// element (an end keeps its element while the fibers stay pressed there). Saved in
  /// checkpoints, so that a resumed run detects as the run that wrote them.
  std::vector<std::vector<std::uint64_t>> memory() const;
  /// Restores memory(); throws std::invalid_argument when it is not one list per fiber.
  void set_memory(const std::vector<std::vector<std::uint64_t>>& memory);
  const DetectionParams& params() const { return m_params; }  ///< settings

 private:
  struct Workspace;  // per-thread scratch buffers (defined in detection.cpp)
  struct FiberOutput {
    std::vector<ProximityZone> zones;
    std::vector<ContactElement> elements;
    // Ends of a zone given their own element (fiber j << 1 | the zone's side along fiber i), this detection's and
    // the last one's: an end keeps its element while the fibers stay pressed there.
    std::vector<std::uint64_t> end_keys, last_end_keys;
  };
  const Model& m_model;
  DetectionParams m_params;
  BroadPhase m_broad;
  std::vector<Index> m_fiber_pair_begin;  // per fiber: first candidate pair whose sampled element is on it
  bool m_mixed_radii = false;             // some fibers are over 3 times thinner than others
  std::vector<ElementPair> m_sampled_pairs;  // with mixed radii: the pairs, the thinner fiber's element first
  std::vector<FiberOutput> m_fiber_out;
  std::vector<std::unique_ptr<Workspace>> m_work;

  void detect_fiber(int fiber, const VecX& q, Workspace& work, FiberOutput& out) const;
};

}  // namespace fibra
