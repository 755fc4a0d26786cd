#pragma once
/// The discrete problem at one load level: total potential Pi(q) = W_beams(q) - loads, its
/// gradient (f_int - f_ext) and Hessian, with eliminated (fixed or prescribed) dofs.
#include <array>
#include <string>
#include <vector>

#include "fibra/body/bodies.hpp"
#include "fibra/contact/contact_element.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/assembler.hpp"
#include "fibra/solver/block_pattern.hpp"

namespace fibra {

/// A moment on a node's section vectors (see nodal_load.hpp).
struct NodalMoment {
  Index node = 0;
  Vec3 moment = Vec3::Zero();  ///< [N m]
};

/// Accumulated wall times of the assembly [s].
struct AssemblyTimes {
  double assembly = 0;  ///< element and load evaluation + scatter
  int evaluations = 0;  ///< calls to evaluate()
};

/// Energy terms of the model, assembled.
class Problem {
 public:
  /// Builds stencils, colouring and the sparsity pattern of `model` (kept by reference) and
  /// of the bindings of `bodies` (optional, kept by reference).
  explicit Problem(const Model& model, BodySystem* bodies = nullptr);

  const Model& model() const { return m_model; }                 ///< the model
  const BlockPattern& pattern() const { return m_pattern; }      ///< matrix sparsity
  std::vector<char>& fixed() { return m_fixed; }                 ///< per dof: 1 = eliminated
  const std::vector<char>& fixed() const { return m_fixed; }     ///< per dof: 1 = eliminated
  VecX& forces() { return m_forces; }                            ///< dead nodal forces (per dof) [N]
  std::vector<NodalMoment>& moments() { return m_moments; }      ///< nodal moments
  const AssemblyTimes& times() const { return m_times; }         ///< accumulated timings
  BodySystem* bodies() const { return m_bodies; }                ///< rigid bodies and bindings (or null)

  /// Replaces the contact elements (each is oriented so that a.element < b.element) and the
  /// friction parameters; returns true when the matrix pattern changed (new element pairs),
  /// after which the linear solver's analysis must be redone.
  bool set_contacts(std::vector<ContactElement> contacts, const FrictionParams& friction);
  const std::vector<ContactElement>& contacts() const { return m_contacts; }  ///< current contact elements
  std::vector<ContactElement>& contacts() { return m_contacts; }              ///< (normals, laws, history)
  /// Evaluated state of every contact element at q (same order as contacts()).
  std::vector<ContactResponse> contact_responses(const VecX& q) const;

  /// Drag (weave and relax steps): energy c/2 sum over nodes of (x0 - a)^T P (x0 - a) + w r^2
  /// (|g1 - a1|^2 + |g2 - a2|^2) towards the anchor state `anchor` (the increment's start),
  /// w = `director_weight` (1: the section boundary's motion), P = I - (1 - `axial_weight`) t t^T
  /// with t the fiber's unit tangent at the node in the anchor state (1: isotropic; less: a
  /// fiber slides along itself more freely, so a tow can draw in as it crimps); c = 0 removes it.
  void set_drag(double c, const VecX& anchor, double director_weight = 1.0, double axial_weight = 1.0);
  /// Norm of the drag's force at q, each dof's component multiplied by `scale` (e.g. 1/r on
  /// section vectors, making their generalized forces forces); 0 without drag.
  double drag_force_norm(const VecX& q, const VecX& scale) const;
  const VecX& drag_anchor() const { return m_drag_anchor; }  ///< anchor of the drag
  double drag() const { return m_drag; }                      ///< drag stiffness per node [N/m]
  /// P u for node `node`'s position (the drag's force per unit stiffness, see set_drag).
  Vec3 drag_projected(Index node, const Vec3& u) const {
    if (m_drag_axial == 1.0 || m_drag_axis.empty()) return u;
    const Vec3& t = m_drag_axis[node];
    return u - (1.0 - m_drag_axial) * t.dot(u) * t;
  }
  /// Sets the state from which moment work is measured in evaluate()'s energy (moment
  /// potentials are only defined up to whole turns, so energies are compared near this state).
  void set_energy_base(const VecX& q) { m_energy_base = q; }
  /// Developers' diagnostic of an indefinite tangent: the local Hessians of the beam elements,
  /// the contact pairs and the bindings at q whose smallest eigenvalue is negative (beyond
  /// rounding), the worst of each kind with its groups. A sum of positive semi-definite local
  /// matrices is positive semi-definite: the terms listed are where negative curvature comes from.
  std::string local_spectra(const VecX& q) const;
  /// Total potential energy at q; fills the gradient of Pi on every dof (f_int - f_ext) and
  /// the Hessian values (free-free block; eliminated dofs get a unit-scaled diagonal).
  double evaluate(const VecX& q, VecX* gradient, std::vector<double>* hessian);

 private:
  void build_pattern();
  /// The drag's energy at q (set_drag), adding its gradient and Hessian values when asked.
  double drag_energy(const VecX& q, VecX* gradient, std::vector<double>* hessian) const;
  const Model& m_model;
  BodySystem* m_bodies = nullptr;
  StencilSet m_beams;
  StencilSet m_contact_pairs;            // one stencil per element pair in contact (6 nodes)
  std::vector<Index> m_pair_begin;       // contacts of pair s: [m_pair_begin[s], m_pair_begin[s+1])
  std::vector<ContactElement> m_contacts;
  FrictionParams m_friction;
  BlockPattern m_pattern;
  std::vector<char> m_fixed;
  std::vector<char> m_group_fixed;  // per group (node or body): some dof fixed (scatter fast path otherwise)
  VecX m_forces;
  std::vector<NodalMoment> m_moments;
  std::vector<double> m_energy_buffer;
  std::vector<double> m_contact_energy_buffer;
  VecX m_energy_base;
  double m_drag_director = 1.0;
  double m_drag_axial = 1.0;
  std::vector<Vec3> m_drag_axis;  // unit tangent per node in the drag's anchor state
  double m_drag = 0;
  VecX m_drag_anchor;
  std::vector<double> m_node_r2;  // squared section radius per node
  std::vector<Index> m_diagonal;  // value index of each diagonal entry
  std::vector<std::array<Index, 3>> m_position_offdiagonal;  // per node: value index of (x,y), (x,z), (y,z)
  AssemblyTimes m_times;
};

}  // namespace fibra
