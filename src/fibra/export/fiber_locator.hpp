#pragma once
/// Whether a point lies in a fiber, and the fiber's direction there (docs/export.md, "Voxel
/// model"). A point p is in element e when a section of e holds it: p = x(eta) + xi1 g1(eta)
/// + xi2 g2(eta) with eta in [-1, 1] and (xi1/a)^2 + (xi2/b)^2 <= 1, the placement of the
/// beam model itself (beam/beam_element.hpp); eta solves (p - x(eta)) . (g1 x g2)(eta) = 0 by
/// Newton's method from the point's projection on the element's chord.
#include <optional>
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/export/element_grid.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// A point found in a fiber.
struct FiberHit {
  int fiber = -1;
  Vec3 tangent = Vec3::UnitX();  ///< unit tangent of the centroid line at the section through the point
};

/// The hit of p in element e at state q, if the element's material holds p.
std::optional<FiberHit> element_hit(const Model& model, const VecX& q, Index e, const Vec3& p);

/// Points located among the elements of a model at a state. Each element is first bounded by
/// a capsule about its chord (the curve departs from its chord by at most |x_mid - (x_0 + x_2)
/// / 2|, its sections reach no farther than the element's box margin), which rejects most
/// points before any Newton iteration.
class FiberLocator {
 public:
  FiberLocator(const Model& model, const VecX& q);
  /// The elements whose boxes meet `box` (sorted, each once), for the points inside it.
  void candidates(const Eigen::AlignedBox3d& box, std::vector<Index>& out) const { m_grid.find(box, out); }
  /// The first of the candidate elements (in their order) whose material holds p.
  std::optional<FiberHit> find(const Vec3& p, const std::vector<Index>& candidates) const;

 private:
  /// A capsule holding an element's material: the segment a-b thickened by `radius`.
  struct Capsule {
    Vec3 a = Vec3::Zero(), b = Vec3::Zero();
    double radius = 0;
  };
  const Model& m_model;
  const VecX& m_q;
  ElementGrid m_grid;
  std::vector<Capsule> m_capsules;  ///< per element
};

}  // namespace fibra
