#pragma once
/// Rigid bodies and averaged binding conditions (METHOD §5; theory in docs/theory/bodies.md).
///
/// A body has 6 dofs after the nodes' dofs: its centre R and an incremental rotation vector
/// theta, its frame being D = exp([theta]x) D_ref with D_ref the frame at the start of the
/// increment (theta is folded into D_ref and reset to 0 when an increment is accepted, so
/// any total rotation is reached without singularity).
///
/// A binding ties N members (fiber nodes by their centroid x0, or other bodies by their
/// centre and frame) to a body in average, by six conditions g = 0 expressed in the body
/// frame:
///   position: g_pos = (1/N) sum_m D^T (p_m - R) - c          (c: the same mean at the start)
///   rotation: g_rot = 1/(N s) [ sum_m a_m x D^T (p_m - R) + sum_c l_c^2 vee(P_c - P_c^T) ]
/// where a_m are the members' initial positions in the body frame relative to their mean,
/// s their rms distance to it, and P_c the rotation of a bound body relative to the binding
/// body since the start. g_rot = 0 says the best-fit (least-squares) rotation of the group
/// relative to the body is zero: every member keeps its freedom, only the mean motion is
/// tied. The conditions are enforced by an augmented Lagrangian: energy
/// lambda . g + k/2 |g|^2 per binding, exact gradient and Hessian, multipliers updated
/// (lambda += k g) until |g| is below the tolerance.
///
/// A grip (BindingSpec::grip) adds, per bound fiber node and per gripped body axis i, the
/// condition g_mi = D_i . (p_m - R) - c_mi = 0 (c_m: the node's initial position in the body
/// frame): each end is held by itself along those axes, like a clamp holds the fibers of a
/// tow, not only in average. Same augmented Lagrangian, one multiplier per condition.
///
/// A spin hold (BindingSpec::spin) adds, per bound fiber node, the condition that its section
/// does not turn about the fiber's axis relative to the body:
///   s_m = r/2 [ b2 . D^T g1 - b1 . D^T g2 ] - s0_m = 0
/// with b1, b2 the node's initial section directions in the body frame and r its radius (s is
/// the spin angle times r, a length like the grip's conditions; tilting the section or
/// stretching it leaves s unchanged to first order). Same augmented Lagrangian.
#include <string>
#include <utility>
#include <vector>

#include "fibra/model/case.hpp"
#include "fibra/model/model.hpp"
#include "fibra/assembly/assembler.hpp"
#include "fibra/assembly/block_pattern.hpp"

namespace fibra {

using Vec6 = Eigen::Matrix<double, 6, 1>;

/// What a body does at a state (for outputs and reactions).
struct BodyState {
  Vec3 center = Vec3::Zero();      ///< current centre [m]
  Mat3 frame = Mat3::Identity();   ///< current frame, columns D1, D2, D3
  Vec3 rotation = Vec3::Zero();    ///< accumulated rotation components [rad]
  Vec3 force = Vec3::Zero();       ///< force the body applies to its members [N]
  Vec3 moment = Vec3::Zero();      ///< moment it applies to them, about its centre [N m]
};

/// All rigid bodies and bindings of a model.
class BodySystem {
 public:
  /// Resolves the [[binding]] entries of `c` against `model` (whose bodies come from
  /// c.bodies) and checks that every body has members and every binding's members define a
  /// mean rotation; throws InputError naming the entry otherwise.
  BodySystem(const Case& c, const Model& model);

  Index num_bodies() const { return static_cast<Index>(m_bodies.size()); }  ///< bodies
  Index num_bindings() const { return static_cast<Index>(m_bindings.size()); }  ///< bindings
  /// One stencil per binding: the members' groups, then the body's group.
  const StencilSet& stencils() const { return m_stencils; }
  /// Characteristic length of body b (rms radius of its members) [m], for rotation scaling.
  double size(Index b) const { return m_bodies[b].size; }

  /// Energy of all bindings at q; adds the gradient and Hessian (sequential, fixed order).
  double evaluate(const VecX& q, const AssemblyTarget& target, bool want_gradient, bool want_hessian);
  /// Whether evaluate() adds each binding's local Hessian projected onto the positive
  /// semi-definite matrices where it is not (its negative eigenvalues set to zero). Off by
  /// default: the exact Hessian, which the derivative checks compare with finite differences.
  /// The solver projects when the exact tangent is not positive definite (docs/theory/solver.md,
  /// "Indefinite tangents").
  void set_projected(bool on) { m_projected = on; }
  /// Local Hessians evaluate() found indefinite and projected since the last call (the count
  /// is reset).
  Index take_projections() { return std::exchange(m_projections, 0); }
  /// The six conditions of binding k at q, in the body frame (position then rotation) [m].
  Vec6 conditions(Index k, const VecX& q) const;
  /// Largest |g| over all conditions of all bindings [m].
  double violation(const VecX& q) const;
  /// Augmented Lagrangian update lambda += k g of every binding.
  void update_multipliers(const VecX& q);
  /// Proximal stabilization: each bound fiber node is tied to an anchor (its values when the
  /// anchors were last set) by a spring of stiffness mu (mu r^2 on the section vectors). The
  /// averaged conditions leave a member's own rigid motions to contact and the fibers; where
  /// nothing holds them yet (a loose strand, a core inside a rope before it is pressed) the
  /// tangent is singular. The spring removes that singularity; the anchors follow the
  /// solution (set_anchors after every solve), so the spring's force vanishes at convergence:
  /// the loop ends when no member moved more than the tolerance since its anchor.
  void set_anchors(const VecX& q);
  /// Largest distance of a bound node from its anchor (section vectors scaled by r) [m].
  double anchor_drift(const VecX& q) const;
  /// Stiffness of the proximal spring [N/m].
  double proximal_stiffness() const { return m_mu; }
  /// Multipliers of all bindings (6 per binding, body frame), then per bound node of the
  /// bindings with grips or spin holds those of its grip (3, zero on axes not gripped) and of
  /// its spin hold (1), to save and restore.
  std::vector<double> multipliers() const;
  void set_multipliers(const std::vector<double>& values);  ///< restores multipliers()
  /// The state that outlives an increment: per body the committed frame (9 values, column
  /// major) and accumulated rotation (3), then multipliers().
  std::vector<double> snapshot() const;
  /// Restores snapshot(); throws std::invalid_argument if its size does not match.
  void restore(const std::vector<double>& values);
  /// Penalty of binding k [N/m].
  double stiffness(Index k) const { return m_bindings[k].k; }
  /// Number of single-node conditions (grips: nodes x gripped axes; spin holds: nodes) of all
  /// bindings.
  Index num_grip_conditions() const;

  /// Local Hessian of binding k at q (its stencil's dofs; for developers' diagnostics).
  Eigen::MatrixXd local_hessian(Index k, const VecX& q) const;

  /// Current frame of body b at q.
  Mat3 frame(Index b, const VecX& q) const;
  /// Accumulated rotation components of body b at q (committed increments + theta).
  Vec3 rotation(Index b, const VecX& q) const;
  /// Rotation components accumulated by the accepted increments.
  Vec3 committed_rotation(Index b) const { return m_bodies[b].rotation; }
  /// Force and moment body b applies to its members at q, and its position and frame.
  BodyState state(Index b, const VecX& q) const;
  /// Current positions of the members bound to body b (fiber nodes' x0, bodies' centres).
  std::vector<Vec3> member_positions(Index b, const VecX& q) const;
  /// Accepts the increment: every frame takes its rotation theta, theta is set to 0 in q.
  void commit(VecX& q);

 private:
  struct Member {
    Index group = 0;     ///< matrix group (node or body)
    Index dof = 0;       ///< first global dof (x0 or R)
    int body = -1;       ///< body index when the member is a body
    int offset = 0;      ///< first local dof in the binding's stencil vector
    Vec3 a = Vec3::Zero();  ///< initial position in the body frame, relative to the mean
    double l2 = 0;       ///< bound body: squared rotational length (its own size)
    double r2 = 0;       ///< fiber node: squared section radius (scales its section vectors)
    Eigen::Matrix<double, 9, 1> anchor = Eigen::Matrix<double, 9, 1>::Zero();  ///< proximal anchor (nodes)
    Vec3 grip_lambda = Vec3::Zero();  ///< grip multipliers along the body axes (nodes) [N]
    Vec3 b1 = Vec3::Zero(), b2 = Vec3::Zero();  ///< initial section directions, body frame (nodes)
    double s0 = 0;                    ///< initial spin measure (nodes) [m]
    double spin_lambda = 0;           ///< spin-hold multiplier (nodes) [N]
  };
  struct Binding {
    int body = 0;
    std::vector<Member> members;
    int parent_offset = 0;  ///< local offset of the body's R
    int local_size = 0;
    Vec3 mean = Vec3::Zero();  ///< initial mean position of the members in the body frame
    double s = 0;              ///< rms radius of the members (with bound bodies' sizes)
    double k = 0;              ///< penalty [N/m]
    Vec6 lambda = Vec6::Zero();  ///< multipliers, body frame [N]
    std::vector<int> grip;       ///< gripped body axes (0-based)
    double kg = 0;               ///< penalty of each grip condition [N/m]
    bool spin = false;           ///< each bound node held against spinning about its axis
  };
  struct BodyData {
    Mat3 frame_ref = Mat3::Identity();  ///< D_ref: frame at the start of the increment
    Vec3 rotation = Vec3::Zero();       ///< accumulated rotation components
    double size = 0;
  };
  /// A body's incremental turn e(theta) = exp(-[theta]x) (D^T v = D_ref^T e v) and, when
  /// asked, its first derivatives de_j and second derivatives d2e_jl (index 3 j + l).
  struct Turn {
    Mat3 e;
    Mat3 de[3];
    Mat3 d2e[9];
  };
  Turn turn(const Binding& b, const VecX& q, bool first, bool second) const;
  /// Energy of binding k with its grips (local gradient and Hessian when given, sized local_size).
  double binding_energy(const Binding& b, const VecX& q, VecX* g, Eigen::MatrixXd* h) const;
  /// The averaged conditions' part of binding_energy (sets g and h; the grips add to them).
  double averaged_energy(const Binding& b, const VecX& q, const Turn& turned, VecX* g, Eigen::MatrixXd* h) const;
  /// Conditions of binding b in the spatial frame of the start of the increment (D_ref g).
  Vec6 spatial_conditions(const Binding& b, const VecX& q) const;
  /// Offset of node member m of binding b from its initial place in the body frame,
  /// D^T (x0 - R) - (mean + a), given e = exp(-[theta]x) and the centre R of the body at q: its
  /// components along the gripped axes are the grip conditions [m].
  Vec3 grip_offset(const Binding& b, const Member& m, const VecX& q, const Mat3& e, const Vec3& r) const;
  /// Adds the grips' energy of binding b (and their local gradient and Hessian when given).
  double grip_energy(const Binding& b, const VecX& q, const Turn& t, VecX* g, Eigen::MatrixXd* h) const;
  /// Spin condition s_m of node member m of binding b, given e = exp(-[theta]x) [m].
  double spin_offset(const Binding& b, const Member& m, const VecX& q, const Mat3& e) const;
  /// Calls f(member, grip offset, spin condition) for each fiber node of binding b (a Binding or
  /// a const Binding) held by grips or a spin hold; the offset is zero without grips and the
  /// spin condition zero without a spin hold. One walk for the violation and the multipliers.
  template <class B, class F>
  void for_each_node_condition(B& b, const VecX& q, F&& f) const;
  /// Adds the spin holds' energy of binding b (and their local gradient and Hessian when given).
  double spin_energy(const Binding& b, const VecX& q, const Turn& t, VecX* g, Eigen::MatrixXd* h) const;

  const Model& m_model;
  std::vector<BodyData> m_bodies;
  std::vector<Binding> m_bindings;
  StencilSet m_stencils;
  double m_mu = 0;          // proximal stiffness
  bool m_projected = false;  // evaluate() projects indefinite local Hessians (set_projected)
  Index m_projections = 0;   // local Hessians projected since take_projections()
  VecX m_g;                 // local buffers (sized to the largest binding)
  Eigen::MatrixXd m_h;
};

}  // namespace fibra
