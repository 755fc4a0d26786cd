#pragma once
/// Broad phase of contact detection (METHOD §2.1): axis-aligned boxes of the beam elements'
/// centroid curves, inflated by the section radius plus a margin, and the element pairs whose
/// boxes overlap, found with a uniform grid (cells the mean box size along each axis) stored
/// as a spatial hash: cost linear in the number of elements for boxes of similar sizes. Choices:
/// docs/theory/contact.md, "Detection".
#include <vector>

#include "fibra/core/types.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// Axis-aligned box [m].
struct Box {
  Vec3 lo = Vec3::Zero();  ///< minimum corner [m]
  Vec3 hi = Vec3::Zero();  ///< maximum corner [m]
  /// True when the closed boxes intersect.
  bool overlaps(const Box& o) const {
    return lo.x() <= o.hi.x() && o.lo.x() <= hi.x() && lo.y() <= o.hi.y() && o.lo.y() <= hi.y() && lo.z() <= o.hi.z() &&
           o.lo.z() <= hi.z();
  }
};

/// The quadratic centroid curve of an element in power form: x0(eta) = c + b eta + a eta^2.
struct CentroidCurve {
  Vec3 a;                                                           ///< (x0_0 - 2 x0_1 + x0_2) / 2 [m]
  Vec3 b;                                                           ///< (x0_2 - x0_0) / 2 [m]
  Vec3 c;                                                           ///< x0_1 [m]
  Vec3 value(double eta) const { return c + eta * (b + eta * a); }  ///< x0(eta) [m]
  Vec3 derivative(double eta) const { return b + 2.0 * eta * a; }   ///< dx0/deta [m]
};

/// Centroid curve of an element from its 27 dofs.
CentroidCurve centroid_curve(const double* q_e);

/// Tight box of an element's centroid curve (exact extrema of the quadratic), inflated by
/// `inflation` [m] on every side.
Box element_box(const CentroidCurve& curve, double inflation);

/// A candidate pair of beam elements (global indices, first < second).
struct ElementPair {
  Index first = 0;   ///< lower element index
  Index second = 0;  ///< higher element index
  bool operator==(const ElementPair& o) const { return first == o.first && second == o.second; }  ///< equality
};

/// Broad-phase settings.
struct BroadPhaseParams {
  double margin = 0;          ///< box inflation beyond the section radius [m]; 0 -> half the element's radius
  double self_exclusion = 0;  ///< same-fiber arc-length exclusion [m]; 0 -> 8 r (= 4 (r_i + r_j))
};

/// Per-element data of the contact search (reference quantities).
struct ContactBeamInfo {
  int fiber = 0;         ///< owning fiber
  Index local = 0;       ///< index of the element within its fiber
  double radius = 0;     ///< section radius max(a, b) [m]
  double inflation = 0;  ///< box inflation: radius + margin [m]
  double length = 0;     ///< reference arc length of the element [m]
};

/// Boxes and candidate pairs, with buffers reused across calls (no allocation once they
/// have reached their working size). The model must outlive the object.
class BroadPhase {
 public:
  /// Prepares the per-element data of `model`.
  explicit BroadPhase(const Model& model, BroadPhaseParams params = {});

  /// Updates curves and boxes at dofs q and returns the candidate pairs, sorted by (first,
  /// second), deterministic for any thread count: pairs whose boxes overlap, without pairs of
  /// the same fiber closer than the self-exclusion length.
  const std::vector<ElementPair>& find_pairs(const VecX& q);

  const std::vector<ElementPair>& pairs() const { return m_pairs; }           ///< last candidate pairs
  const std::vector<Box>& boxes() const { return m_boxes; }                   ///< last element boxes
  const std::vector<CentroidCurve>& curves() const { return m_curves; }       ///< last centroid curves
  const ContactBeamInfo& info(Index e) const { return m_info[e]; }            ///< data of element e
  double self_exclusion(int fiber) const { return m_self_exclusion[fiber]; }  ///< exclusion length of a fiber [m]
  const Vec3& cell_size() const { return m_cell; }                            ///< last grid cell sizes [m]
  /// True when elements a and b are on the same fiber with reference arc-length separation
  /// (between the nearest ends of their intervals) below the fiber's self-exclusion length.
  bool excluded(Index a, Index b) const;

 private:
  struct Entry {
    Index element;
    int cell[3];
  };
  const Model& m_model;
  std::vector<ContactBeamInfo> m_info;
  std::vector<double> m_self_exclusion;
  std::vector<CentroidCurve> m_curves;
  std::vector<Box> m_boxes;
  std::vector<int> m_cell_range;     // 6 per element: lo xyz, hi xyz
  std::vector<Index> m_entry_begin;  // per element: first entry slot (prefix of cell counts)
  std::vector<Index> m_bucket_begin;
  std::vector<Entry> m_entries;
  std::vector<std::vector<ElementPair>> m_thread_pairs;
  std::vector<ElementPair> m_pairs;
  Vec3 m_cell = Vec3::Ones();
  Vec3 m_origin = Vec3::Zero();
  std::uint64_t m_bucket_mask = 0;
};

}  // namespace fibra
