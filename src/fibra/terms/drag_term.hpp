#pragma once
/// The proximal drag: c/2 |q - a|^2 (weighted) towards an anchor state a, which holds
/// mechanisms (loose fibers, free spins, tow ends) in the pseudo-time increments of weave,
/// relax and test steps (docs/theory/fabric.md). Its stiffness and anchor are set between
/// minimizations; it does no work once the state stops moving from its anchor.
#include <array>
#include <vector>

#include "fibra/assembly/energy_term.hpp"
#include "fibra/body/bodies.hpp"
#include "fibra/model/model.hpp"

namespace fibra {

/// The dofs a drag force is measured on: all of them; the nodes' positions and the bodies (the
/// forces a fabric's edges feel); the section vectors (the fibers' spin about their own axes
/// and the sections' deformation, which turn no edge force).
enum class DragPart { All, Positions, Sections };

/// What DragTerm::set takes: the drag whole, as a solver saves and puts it back.
struct DragSettings {
  double stiffness = 0;  ///< c, per node [N/m] (0: no drag)
  VecX anchor;           ///< the anchor state
  double director_weight = 1, axial_weight = 1, position_weight = 1;
};

/// Drag of every node (and body) towards an anchor state.
class DragTerm final : public EnergyTerm {
 public:
  /// For the nodes of `model` and the bodies of `bodies` (optional); both kept by reference.
  DragTerm(const Model& model, const BodySystem* bodies);
  std::string name() const override { return "drag"; }
  void pattern_changed(const BlockPattern& pattern) override;
  double assemble(const VecX& q, const AssemblyTarget& target) override;

  /// Energy c/2 sum over nodes of p (x0 - a)^T P (x0 - a) + w r^2 (|g1 - a1|^2 + |g2 - a2|^2)
  /// towards `anchor`, w = `director_weight`, p = `position_weight`, P = I - (1 -
  /// `axial_weight`) t t^T with t the fiber's unit tangent at the node in the anchor state;
  /// bodies p (c/2 |dR|^2 + c s^2/2 |dtheta|^2) (s the body's size); c = 0 removes it. With
  /// p = 0 only the section vectors are held: the drag exerts no force on the nodes' positions
  /// and the bodies, only moments that turn the sections.
  void set(double c, const VecX& anchor, double director_weight, double axial_weight, double position_weight = 1.0);
  /// The drag as set() took it (with set_stiffness()'s c): set(settings()) changes nothing.
  DragSettings settings() const { return {m_c, m_anchor, m_director, m_axial, m_position}; }
  void set(const DragSettings& s) { set(s.stiffness, s.anchor, s.director_weight, s.axial_weight, s.position_weight); }
  double stiffness() const { return m_c; }             ///< c, per node [N/m]
  /// Changes c only (the anchor, the weights and the tangents set() took from the anchor stay):
  /// the same drag taken off (0) and put back.
  void set_stiffness(double c) { m_c = c; }
  /// Norm of the drag's force at q over the dofs of `part`, each dof's component multiplied by
  /// `scale`; 0 without drag.
  double force_norm(const VecX& q, const VecX& scale, DragPart part = DragPart::All) const;
  /// P u for node `node`'s position (the drag's force per unit stiffness).
  Vec3 projected(Index node, const Vec3& u) const {
    if (m_axial == 1.0 || m_axis.empty()) return u;
    const Vec3& t = m_axis[node];
    return u - (1.0 - m_axial) * t.dot(u) * t;
  }

 private:
  double energy(const VecX& q, VecX* gradient, std::vector<double>* values, const std::vector<char>* fixed) const;
  const Model& m_model;
  const BodySystem* m_bodies = nullptr;
  double m_c = 0;
  double m_director = 1.0;
  double m_axial = 1.0;
  double m_position = 1.0;
  VecX m_anchor;
  std::vector<Vec3> m_axis;       // unit tangent per node in the anchor state
  std::vector<double> m_node_r2;  // squared section radius per node
  std::vector<Index> m_diagonal;  // value index of each diagonal entry
  std::vector<std::array<Index, 3>> m_position_offdiagonal;  // per node: value index of (x,y), (x,z), (y,z)
};

}  // namespace fibra
