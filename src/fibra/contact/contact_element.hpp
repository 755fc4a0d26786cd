#pragma once
/// A contact element: a pair of material particles on the borders of two fiber sections,
/// predicted to touch (METHOD §2), with its normal, penalty law and friction history.
///
/// Particle P on beam element e sits at parametric eta and section coordinates (xi1, xi2):
/// x = sum_a N_a(eta) (x0_a + xi1 g1_a + xi2 g2_a), linear in the element's 27 dofs. With
/// the normal N fixed during Newton iterations, gap = N . (x_B - x_A) is linear in the 54
/// dofs of the two elements, so the normal energy phi(-gap) has an exact rank-one Hessian.
#include <Eigen/Core>

#include "fibra/contact/contact_law.hpp"
#include "fibra/core/types.hpp"

namespace fibra {

/// Dofs of a contact element: the 27 of element A then the 27 of element B.
inline constexpr int kContactDofs = 2 * kElementDofs;
using ContactVec = Eigen::Matrix<double, kContactDofs, 1>;
using ContactMat = Eigen::Matrix<double, kContactDofs, kContactDofs>;

/// A material particle on a beam element.
struct Particle {
  Index element = 0;  ///< global beam element index
  double eta = 0;     ///< parametric coordinate in [-1, 1]
  double xi1 = 0;     ///< section coordinate along g1 [m]
  double xi2 = 0;     ///< section coordinate along g2 [m]
};

/// One contact element and its state.
struct ContactElement {
  Particle a;                      ///< particle on fiber i
  Particle b;                      ///< particle on fiber j
  Vec3 normal = Vec3::UnitZ();     ///< unit normal, from A's section centre towards B's
  PenaltyLaw law;                  ///< normal law (stiffness adapted per proximity zone)
  int zone = 0;                    ///< proximity zone index
  bool fresh = true;               ///< appeared at the last detection (no history carried over)
  bool prescribed = false;         ///< normal set by the weave pattern (not updated from the centres)
  double offset = 0;               ///< added to the gap: penetration hidden from the law [m] (weaving)
  /// Normal force that sets the friction cone and the stick stiffness [N]; negative: the
  /// current normal force. The solver freezes it per normal-update loop (docs/theory/contact.md,
  /// "Frozen friction limit"), which makes the friction potential of a Newton solve a convex
  /// function of the slip with an exactly symmetric Hessian.
  double friction_normal = -1;
  // Friction history (at the last converged increment).
  Vec3 friction_previous = Vec3::Zero();  ///< tangential force on B at the last converged state [N]
  Vec3 separation_previous = Vec3::Zero();  ///< x_B - x_A at the last converged state [m]
};

/// Evaluated quantities of a contact element (for output and the adaptive penalty).
struct ContactResponse {
  double gap = 0;            ///< N . (x_B - x_A) [m]; negative = penetration
  double normal_force = 0;   ///< >= 0 [N]
  Vec3 friction = Vec3::Zero();  ///< tangential force on B [N]
  bool slip = false;         ///< friction on the Coulomb cone
};

/// Friction parameters.
struct FrictionParams {
  double mu = 0;            ///< Coulomb coefficient
  double elastic_slip = 0;  ///< delta [m]: tangential stiffness mu f_n / delta
};

/// Position of particle p from the element dofs q_e (27 values).
Vec3 particle_position(const Particle& p, const double* q_e);

/// The Hessian of a contact element.
enum class ContactTangent {
  /// The normal law's exact second derivative; for friction, k_t and the cone held fixed: the
  /// exact Hessian of the friction energy when the cone is frozen (on the cone, curvature only
  /// across the trial force's direction).
  Exact,
  /// A quadratic model above the element's energy for every step (docs/theory/contact.md, "A
  /// tangent above the contact energy"): the normal law's largest curvature k whatever the
  /// penetration (open elements too), and for friction as Exact in stick, and on the cone the
  /// across-curvature k_t mu f_n / |T| in every tangential direction, along the trial force
  /// too. What the solver factorizes for the elements whose exact model failed.
  Majorizing,
  /// The exact, non-symmetric derivative of the friction force (k_t and the cone following the
  /// normal force when they are not frozen).
  Consistent,
};

/// Energy (normal potential plus the friction spring's, see docs/theory/contact.md), gradient
/// and Hessian with respect to [q_A; q_B]; q_a, q_b are the current element dofs. Friction
/// force is computed by return mapping from the element's history. The Hessian is exact for
/// the normal part; for friction it is the `tangent` asked for. With `accumulate`,
/// grad and hess are added to, and only the upper 3x3 blocks of hess (block row <= block
/// column) are written: what the assembler scatters (the fast path of Problem).
double contact_element_energy(const ContactElement& c, const double* q_a, const double* q_b,
                              const FrictionParams& friction, ContactVec* grad, ContactMat* hess,
                              ContactResponse* response, ContactTangent tangent = ContactTangent::Exact,
                              bool accumulate = false);

/// An element's energy along a step of its dofs, against a tangent's quadratic model, split
/// into the normal law's part and the friction spring's.
struct StepModel {
  double normal_change = 0, normal_model = 0;      ///< the normal law's change and its model [J]
  double friction_change = 0, friction_model = 0;  ///< the friction spring's [J]
  double slope = 0;                                ///< the gradient's work along the step [J]
  ContactResponse start, end;                      ///< the element before and after the step
  double change() const { return normal_change + friction_change; }
  /// The change less the model: positive where the model falls below the energy (with the
  /// Exact tangent: a slip the step turns back, an open element the step pushes into
  /// penetration, a penetration deepened along the quadratic start).
  double excess() const { return change() - (normal_model + friction_model); }
};
/// The element's energy change along the step from (q_a, q_b) to (t_a, t_b) against the
/// quadratic model of `tangent` at the start: the same model as contact_element_energy's
/// gradient and Hessian give, without forming them.
StepModel contact_step_model(const ContactElement& c, const double* q_a, const double* q_b, const double* t_a,
                             const double* t_b, const FrictionParams& friction,
                             ContactTangent tangent = ContactTangent::Exact);

}  // namespace fibra
