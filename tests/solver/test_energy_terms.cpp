// Every energy term of the total potential (assembly/energy_term.hpp) through the one
// finite-difference harness (support/finite_difference.hpp: central differences, step
// cbrt(eps) times the state's scale), at random states and at degenerate ones: a straight,
// unstrained fiber; contact at zero gap, in the quadratic start and beyond it, open; friction
// in stick, in slip and on the stick/slip boundary; a fiber end at its body's centre; a drag
// along and across the fibers; moments about an axis along a reference section vector.
//
// For each: the gradient (every dof) against differences of the energy, the Hessian (free-free
// upper values, through the term's own stencils in a pattern of its own) against differences
// of the gradient, and the sum of the term's local Hessians against the assembled one (the
// local Hessians are what diagnostics read). The checks ask for 1e-6 relative, where the
// differences are good to ~1e-8, so a wrong term of relative size 1e-6 fails. On the
// stick/slip boundary the friction energy is only C1, and at zero gap the Hessian has a kink:
// there the gradient is checked, and the Hessian against the one-sided differences of the side
// the kernel takes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "fibra/assembly/psd_projection.hpp"
#include "fibra/body/bodies.hpp"
#include "fibra/contact/contact_manager.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/model/model.hpp"
#include "fibra/solver/problem.hpp"
#include "fibra/terms/beam_term.hpp"
#include "fibra/terms/binding_term.hpp"
#include "fibra/terms/contact_term.hpp"
#include "fibra/terms/drag_term.hpp"
#include "fibra/terms/load_term.hpp"
#include "support/assembled.hpp"
#include "support/finite_difference.hpp"

namespace fibra {
namespace {

using test::dense;
using test::fd_gradient;
using test::fd_jacobian;
using test::fd_step;
using test::random_unit;
using test::rel_error;

/// A term assembled on its own: its energy, gradient and dense Hessian at q.
struct Assembled {
  double energy = 0;
  VecX gradient;
  Eigen::MatrixXd hessian;
};

class TermHarness {
 public:
  TermHarness(EnergyTerm& term, const Model& model) : m_term(term), m_model(model) { rebuild(); }
  /// After the term's stencils changed.
  void rebuild() {
    std::vector<const StencilSet*> sets;
    if (const StencilSet* s = m_term.stencils()) sets.push_back(s);
    m_pattern = std::make_unique<BlockPattern>(m_model.group_sizes(), sets);
    m_term.pattern_changed(*m_pattern);
  }
  std::vector<char> fixed = {};
  double energy(const VecX& q) { return assemble(q, false, false).energy; }
  VecX gradient(const VecX& q) { return assemble(q, true, false).gradient; }
  Assembled assemble(const VecX& q, bool want_gradient, bool want_hessian) {
    if (fixed.empty()) fixed.assign(q.size(), 0);
    std::vector<char> group_fixed(m_model.num_groups(), 0);
    for (Index d = 0; d < q.size(); ++d)
      if (fixed[d]) group_fixed[m_pattern->group_of_dof(d)] = 1;
    Assembled a;
    a.gradient = VecX::Zero(q.size());
    std::vector<double> values(m_pattern->nonzeros(), 0.0);
    const AssemblyTarget t{m_pattern.get(), &fixed, &group_fixed, want_gradient ? &a.gradient : nullptr,
                           want_hessian ? &values : nullptr};
    a.energy = m_term.assemble(q, t);
    if (want_hessian) a.hessian = dense(*m_pattern, values);
    return a;
  }
  /// The free-free block of a dense matrix (fixed rows and columns zeroed).
  Eigen::MatrixXd free_part(Eigen::MatrixXd m) const {
    for (Index d = 0; d < m.rows(); ++d)
      if (!fixed.empty() && fixed[d]) m.row(d).setZero(), m.col(d).setZero();
    return m;
  }
  /// The term's local Hessians summed into a dense matrix (upper blocks mirrored as assembled).
  Eigen::MatrixXd local_sum(const VecX& q) const {
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(q.size(), q.size());
    for (Index k = 0; k < m_term.num_local(); ++k) {
      const Eigen::MatrixXd h = m_term.local_hessian(k, q);
      std::vector<Index> dofs;
      for (Index g : m_term.local_groups(k))
        for (int i = 0; i < m_pattern->group_size(g); ++i) dofs.push_back(m_pattern->group_dof(g) + i);
      EXPECT_EQ(static_cast<Index>(dofs.size()), h.rows()) << m_term.name();
      for (size_t i = 0; i < dofs.size(); ++i)
        for (size_t j = 0; j < dofs.size(); ++j) m(dofs[i], dofs[j]) += h(i, j);
    }
    return m;
  }

 private:
  EnergyTerm& m_term;
  const Model& m_model;
  std::unique_ptr<BlockPattern> m_pattern;
};

/// The harness's checks at q: gradient, Hessian, local Hessians (when the term has them).
/// `scale`: the state's length scale for the difference step; `stiffness`: the term's own
/// stiffness scale [N/m], the floor of the relative errors where the Hessian (or, times 1e-3
/// scale, the gradient) is zero (an unstrained fiber, a contact at zero gap). `kink`: the
/// Hessian jumps or has a kink at q (friction on its cone, contact at zero gap): the gradient
/// is checked to the first-order error of differences across it, and each column of the Hessian
/// against the one-sided differences of the side the kernel takes.
void expect_derivatives(EnergyTerm& term, const Model& model, const VecX& q, double scale, double stiffness,
                        const std::string& label, const std::vector<char>& fixed = {}, bool kink = false) {
  TermHarness h(term, model);
  h.fixed = fixed;
  const Assembled a = h.assemble(q, true, true);
  const double step = fd_step(scale);
  const VecX gfd = fd_gradient([&](const VecX& x) { return h.energy(x); }, q, step);
  EXPECT_LT(rel_error(a.gradient, gfd, 1e-3 * stiffness * scale), kink ? 1e-4 : 1e-6) << term.name() << ", " << label;
  const Eigen::MatrixXd hess = h.free_part(a.hessian);
  if (!kink) {
    const Eigen::MatrixXd hfd = h.free_part(fd_jacobian([&](const VecX& x) { return h.gradient(x); }, q, step));
    EXPECT_LT(rel_error(hess, hfd, stiffness), 1e-6) << term.name() << ", " << label;
  } else {
    // Forward and backward differences: the kernel's Hessian is one of the two sides.
    Eigen::MatrixXd fwd(q.size(), q.size()), bwd(q.size(), q.size());
    const VecX g0 = h.gradient(q);
    VecX x = q;
    for (Index i = 0; i < q.size(); ++i) {
      x[i] = q[i] + step;
      fwd.col(i) = (h.gradient(x) - g0) / step;
      x[i] = q[i] - step;
      bwd.col(i) = (g0 - h.gradient(x)) / step;
      x[i] = q[i];
    }
    // Column by column: a dof's side of the kink depends on its direction. One-sided
    // differences are first-order: good to ~step / scale = 6e-6 of the stiffness.
    const Eigen::MatrixXd f = h.free_part(fwd), b = h.free_part(bwd);
    for (Index i = 0; i < q.size(); ++i) {
      const double e = std::min((hess.col(i) - f.col(i)).norm(), (hess.col(i) - b.col(i)).norm());
      EXPECT_LT(e, 1e-4 * std::max(hess.norm(), stiffness)) << term.name() << ", " << label << ", column " << i;
    }
  }
  if (term.num_local() > 0) {
    EXPECT_LT(rel_error(h.free_part(h.local_sum(q)), hess, stiffness), 1e-12) << term.name() << ", " << label;
  }
}

// A large-deformation state: rotations growing along the model (up to ~1 rad), 10 % stretches,
// distortions.
VecX random_state(const Model& model, std::mt19937& rng, double size) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 axis = random_unit(rng);
  VecX q = model.reference;
  const Index n = model.num_nodes();
  for (Index k = 0; k < n; ++k) {
    const Mat3 rot = Eigen::AngleAxisd(static_cast<double>(k) / static_cast<double>(n) + 0.2 * u(rng), axis).toRotationMatrix();
    q.segment<3>(9 * k) = 1.1 * (rot * model.reference.segment<3>(9 * k));
    for (int a = 0; a < 2; ++a)
      q.segment<3>(9 * k + 3 + 3 * a) = (1.0 + 0.1 * u(rng)) * (rot * model.reference.segment<3>(9 * k + 3 + 3 * a));
  }
  for (Index d = 0; d < model.node_dofs; ++d) q[d] += 0.05 * u(rng) * (d % 9 < 3 ? size : 1.0);
  return q;
}

const char* kHelix = R"(
[[material]]
name = "carbon"
model = "transverse"
young = 230e9
poisson = 0.2
young_transverse = 15e9
shear_axial = 24e9
poisson_transverse = 0.45
[[fiber]]
name = "coil"
material = "carbon"
semi_axes = [0.05, 0.03]
helix = { center = [0, 0, 0], axis = [0.2, 0.1, 1], radius = 0.4, pitch = 0.3, turns = 0.5 }
elements = 3
[[step]]
name = "s"
)";

// E A / L of the helix's elements (230e9 Pa, 4.7e-3 m^2, ~0.4 m): the beam term's stiffness scale.
constexpr double kBeamStiffness = 2.7e9;

TEST(EnergyTerms, BeamElasticity) {
  const Case c = parse_case_toml(kHelix, "helix.toml");
  const Model model = build_model(c);
  BeamTerm term(model);
  std::mt19937 rng(11);
  // The reference (unstrained, zero gradient): the Hessian alone.
  expect_derivatives(term, model, model.reference, 0.4, kBeamStiffness, "reference");
  for (int trial = 0; trial < 3; ++trial)
    expect_derivatives(term, model, random_state(model, rng, 0.4), 0.4, kBeamStiffness, "random " + std::to_string(trial));
}

TEST(EnergyTerms, ExternalWork) {
  const Case c = parse_case_toml(kHelix, "helix.toml");
  const Model model = build_model(c);
  LoadTerm term(model);
  std::mt19937 rng(5);
  for (Index k : {2, 5, 6})
    for (int d = 0; d < 3; ++d) term.forces()[9 * k + d] = 100.0 * random_unit(rng)[d];
  term.moments().push_back({6, 30.0 * random_unit(rng)});
  // About the reference g1 of node 3: that vector's weight is zero (no stiffness on it).
  term.moments().push_back({3, 20.0 * model.reference.segment<3>(9 * 3 + 3).normalized()});
  // About the reference tangent of node 4: both section vectors weigh 1/2.
  term.moments().push_back({4, 10.0 * model.reference.segment<3>(9 * 4 + 3).cross(model.reference.segment<3>(9 * 4 + 6))});
  for (int trial = 0; trial < 3; ++trial) {
    const VecX q = random_state(model, rng, 0.4);
    term.set_energy_base(trial == 0 ? model.reference : q);
    std::vector<char> fixed(model.num_dofs(), 0);
    if (trial == 2)
      for (Index d : {9 * 3 + 4, 9 * 6 + 7}) fixed[d] = 1;
    expect_derivatives(term, model, q, 0.4, 1e3, "random " + std::to_string(trial), fixed);
  }
}

// Two fibers of one element each crossing at 60 degrees, element 0 below element 1; contact
// elements between them with the gap, normal force and slip each test asks for.
const char* kCrossing = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "low"
material = "m"
radius = 0.001
points = [[-0.01, 0, 0], [0.01, 0, 0]]
elements = 1
[[fiber]]
name = "high"
material = "m"
radius = 0.001
points = [[-0.005, -0.00866, 0.002], [0.005, 0.00866, 0.002]]
elements = 1
[[step]]
name = "s"
)";

struct Crossing {
  Case c = parse_case_toml(kCrossing, "crossing.toml");
  Model model = build_model(c);
  VecX q;
  std::vector<ContactElement> elements;
  FrictionParams friction{0.3, 1e-6};

  Crossing(std::mt19937& rng, int count) {
    std::uniform_real_distribution<double> u(-1, 1);
    q = random_state(model, rng, 0.002);
    for (int k = 0; k < count; ++k) {
      ContactElement e;
      e.a = {0, 0.3 * u(rng), 0.0, 1e-3};
      e.b = {1, 0.3 * u(rng), 0.0, -1e-3};
      e.normal = random_unit(rng);
      e.law = {1e6, 1e-6};
      e.friction_normal = 0.5 + 0.5 * std::abs(u(rng));
      elements.push_back(e);
    }
  }
  double gap(const ContactElement& e) const {
    return (particle_position(e.b, q.data() + 27) - particle_position(e.a, q.data())).dot(e.normal);
  }
  /// Moves fiber "high" along element k's normal to the given gap.
  void set_gap(int k, double g) {
    const double shift = g - gap(elements[k]);
    for (int n = 3; n < 6; ++n) q.segment<3>(9 * n) += shift * elements[k].normal;
  }
  /// Element k's friction history such that its trial tangential force is `ratio` times the
  /// cone's radius (below 1: stick; above: slip).
  void set_slip(int k, double ratio, std::mt19937& rng) {
    ContactElement& e = elements[k];
    const Vec3 sep = particle_position(e.b, q.data() + 27) - particle_position(e.a, q.data());
    Vec3 t = random_unit(rng);
    t = (t - t.dot(e.normal) * e.normal).normalized();
    e.friction_previous = Vec3::Zero();
    // k_t = mu f_n / delta: a tangential slip of ratio * delta puts the trial force at ratio * mu f_n.
    e.separation_previous = sep - ratio * friction.elastic_slip * t;
  }
};

// The contact terms' length scale for the difference step: the normal law's regularization
// depth p_r and the elastic slip (1e-6 m), the lengths over which their stiffness changes.
constexpr double kContactScale = 1e-6;

TEST(EnergyTerms, ContactNormalLaw) {
  std::mt19937 rng(3);
  // One element at each point of the normal law: open, zero gap, in the quadratic start (p_r = 1e-6),
  // at its end, beyond it.
  for (double gap : {2e-6, 0.0, -0.3e-6, -1e-6 + 1e-9, -5e-6}) {
    Crossing x(rng, 1);
    x.friction.mu = 0.0;
    x.set_gap(0, gap);
    ContactTerm term(x.model);
    term.set_contacts(x.elements, x.friction);
    // At zero gap the force and the stiffness are continuous, but the stiffness has a kink
    // (0 before, k p / p_r after): central differences of the gradient are first order there.
    expect_derivatives(term, x.model, x.q, kContactScale, 1e6, "gap " + std::to_string(gap), {}, gap == 0.0);
  }
}

TEST(EnergyTerms, ContactWithFriction) {
  std::mt19937 rng(8);
  for (double ratio : {0.4, 3.0}) {
    Crossing x(rng, 3);
    for (int k = 0; k < 3; ++k) x.set_slip(k, ratio, rng);
    x.set_gap(0, -2e-6);
    ContactTerm term(x.model);
    term.set_contacts(x.elements, x.friction);
    std::vector<ContactResponse> r = term.responses(x.q);
    ASSERT_EQ(r[0].slip, ratio > 1.0);
    expect_derivatives(term, x.model, x.q, kContactScale, 1e6, ratio > 1.0 ? "slip" : "stick");
  }
  // The tangent above the energy (ContactTangent::Majorizing, tests/contact): its friction part
  // (what it adds beyond what it adds to the same elements without friction, the normal law's
  // curvature k) is nothing in stick, positive semi-definite in slip; the local Hessians sum to
  // it.
  for (double ratio : {0.4, 3.0}) {
    Crossing x(rng, 3);
    x.set_gap(0, -2e-6);
    for (int k = 0; k < 3; ++k) x.set_slip(k, ratio, rng);
    ContactTerm term(x.model);
    term.set_contacts(x.elements, x.friction);
    TermHarness h(term, x.model);
    const Eigen::MatrixXd exact = h.assemble(x.q, false, true).hessian;
    term.set_tangent(ContactTangent::Majorizing);
    const Eigen::MatrixXd above = h.assemble(x.q, false, true).hessian;
    EXPECT_LT(rel_error(h.local_sum(x.q), above, 1e6), 1e-12) << ratio;
    for (const ContactResponse& r : term.responses(x.q)) EXPECT_EQ(r.slip, ratio > 1.0);
    FrictionParams frictionless = x.friction;
    frictionless.mu = 0.0;
    ContactTerm normal(x.model);
    normal.set_contacts(x.elements, frictionless);
    TermHarness hn(normal, x.model);
    const Eigen::MatrixXd normal_exact = hn.assemble(x.q, false, true).hessian;
    normal.set_tangent(ContactTangent::Majorizing);
    const Eigen::MatrixXd normal_added = hn.assemble(x.q, false, true).hessian - normal_exact;
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(normal_added).eigenvalues().minCoeff(),
              -1e-9 * exact.norm());
    if (ratio < 1.0) {
      EXPECT_LT((above - exact - normal_added).norm(), 1e-12 * exact.norm());
    } else {
      const Eigen::MatrixXd added = above - exact - normal_added;
      EXPECT_GT(added.norm(), 1e-3 * exact.norm());
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(added).eigenvalues().minCoeff(), -1e-9 * exact.norm());
    }
  }
  // On the cone: the friction energy is C1 there.
  Crossing x(rng, 1);
  x.set_gap(0, -2e-6);
  x.set_slip(0, 1.0, rng);
  ContactTerm term(x.model);
  term.set_contacts(x.elements, x.friction);
  expect_derivatives(term, x.model, x.q, kContactScale, 1e6, "stick/slip boundary", {}, true);
}

// Fiber ends bound to a tow body, tows to an edge body; one fiber end at its body's centre
// (its radial direction is 0/0: docs/theory/bodies.md).
const char* kBodies = R"(
[[material]]
name = "m"
young = 1e9
poisson = 0.3
[[fiber]]
name = "a"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0, 0], [1, 0.03, 0.02]]
[[fiber]]
name = "b"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.05, 0.01], [1.1, 0.05, 0.01]]
[[fiber]]
name = "c"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.01, 0.06], [0.9, 0.01, 0.06]]
[[fiber]]
name = "d"
material = "m"
radius = 0.01
elements = 1
points = [[0, 0.3, 0], [1, 0.3, 0]]
[[body]]
name = "tow1"
center = [1.0, 0.03, 0.02]
[[body]]
name = "edge"
center = [1.05, 0.2, 0.0]
[[binding]]
body = "tow1"
ends = [{ fiber = "a", node = "last" }, { fiber = "b", node = "last" }, { fiber = "c", node = "last" }]
grip = [1, 3]
spin = true
[[binding]]
body = "edge"
bodies = ["tow1"]
ends = [{ fiber = "d", node = "first" }, { fiber = "d", node = "last" }]
[[step]]
name = "s"
)";

// The model of kBodies and its bodies.
struct BoundFibers {
  Case c = parse_case_toml(kBodies, "bodies.toml");
  Model model = build_model(c);
  BodySystem bodies{c, model};
};

TEST(EnergyTerms, Bindings) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    BoundFibers fx;
    const Model& model = fx.model;
    BodySystem& bodies = fx.bodies;
    BindingTerm term(bodies);
    VecX q = model.reference;
    if (trial > 0) {
      // A committed increment first (frames differ from the initial ones), multipliers, then a
      // random state.
      for (const Body& b : model.bodies)
        for (int k = 0; k < 3; ++k) q[b.first_dof + 3 + k] = 0.5 * normal(rng);
      bodies.commit(q);
      for (Index d = 0; d < model.node_dofs; ++d) q[d] += 0.05 * normal(rng);
      for (const Body& b : model.bodies)
        for (int k = 0; k < 6; ++k) q[b.first_dof + k] += 0.3 * normal(rng);
      std::vector<double> lambda = bodies.multipliers();
      for (double& l : lambda) l = 1e6 * normal(rng);
      bodies.set_multipliers(lambda);
    }
    expect_derivatives(term, model, q, 1.0, 1e6, trial == 0 ? "reference (an end at its body's centre)" : "random " + std::to_string(trial));
  }
}

// A random state of the nodes, the bodies moved a little from `anchor` (their rotations stay
// small, where the drag's rotation terms are meant).
VecX dragged_state(const Model& model, const VecX& anchor, std::mt19937& rng) {
  VecX q = random_state(model, rng, 1.0);
  for (const Body& b : model.bodies)
    for (int k = 0; k < 6; ++k) q[b.first_dof + k] = anchor[b.first_dof + k] + 0.1 * random_unit(rng)[k % 3];
  return q;
}

TEST(EnergyTerms, Drag) {
  BoundFibers fx;
  const Model& model = fx.model;
  BodySystem& bodies = fx.bodies;
  DragTerm term(model, &bodies);
  std::mt19937 rng(2);
  const VecX anchor = random_state(model, rng, 1.0);
  // Isotropic, weak along the fibers, and with the positions and bodies released (the end of
  // a relax step or a settled test level: only the section vectors held).
  for (const auto& [axial, position] : {std::pair{1.0, 1.0}, std::pair{0.01, 1.0}, std::pair{0.01, 0.0}}) {
    term.set(1e3, anchor, 100.0, axial, position);
    const VecX q = dragged_state(model, anchor, rng);
    std::vector<char> fixed(model.num_dofs(), 0);
    fixed[9 * 1 + 2] = 1;
    expect_derivatives(term, model, q, 1.0, 1e3,
                       "axial weight " + std::to_string(axial) + ", position weight " + std::to_string(position), fixed);
  }
}

// The drag's force by parts: the positions and bodies, the section vectors, and all of them (their
// squares add up); with the positions released the drag pulls on the section vectors only, as
// it did with them held.
TEST(EnergyTerms, DragForceByParts) {
  BoundFibers fx;
  const Model& model = fx.model;
  BodySystem& bodies = fx.bodies;
  DragTerm term(model, &bodies);
  std::mt19937 rng(5);
  const VecX anchor = random_state(model, rng, 1.0);
  const VecX q = dragged_state(model, anchor, rng);
  VecX scale = VecX::Ones(q.size());
  for (Index d = 0; d < model.node_dofs; ++d)
    if (d % kNodeDofs >= 3) scale[d] = 7.0;
  term.set(1e3, anchor, 100.0, 0.5);
  const double all = term.force_norm(q, scale), positions = term.force_norm(q, scale, DragPart::Positions),
               sections = term.force_norm(q, scale, DragPart::Sections);
  EXPECT_GT(positions, 0.0);
  EXPECT_GT(sections, 0.0);
  EXPECT_NEAR(all * all, positions * positions + sections * sections, 1e-12 * all * all);
  // Its gradient by hand: positions P (x - a) c, bodies c (and c s^2 on rotations), sections c w r^2.
  VecX g = VecX::Zero(q.size());
  AssemblyTarget t;
  t.gradient = &g;
  term.assemble(q, t);
  double pos2 = 0.0;
  for (Index n = 0; n < model.num_nodes(); ++n) pos2 += scale.segment<3>(kNodeDofs * n).cwiseProduct(g.segment<3>(kNodeDofs * n)).squaredNorm();
  pos2 += g.tail(q.size() - model.node_dofs).squaredNorm();
  EXPECT_NEAR(positions, std::sqrt(pos2), 1e-12 * positions);

  term.set(1e3, anchor, 100.0, 0.5, 0.0);
  EXPECT_EQ(term.force_norm(q, scale, DragPart::Positions), 0.0);
  EXPECT_NEAR(term.force_norm(q, scale, DragPart::Sections), sections, 1e-12 * sections);
  EXPECT_NEAR(term.force_norm(q, scale), sections, 1e-12 * sections);
  EXPECT_EQ(term.settings().position_weight, 0.0);
}

// The projection of a local Hessian (assembly/psd_projection.hpp): negative eigenvalues set to
// zero, eigenvectors kept, written through an expression (a block of a larger matrix); positive
// semi-definite matrices, singular ones included, left exactly as they are.
TEST(EnergyTerms, ProjectionOntoPositiveSemiDefiniteMatrices) {
  std::mt19937 rng(8);
  const Mat3 rot = Eigen::AngleAxisd(0.7, random_unit(rng)).toRotationMatrix();
  Eigen::Matrix<double, 5, 5> m = Eigen::Matrix<double, 5, 5>::Constant(7.0);
  const Mat3 indefinite = rot * Vec3(4.0, -1.0, 0.5).asDiagonal() * rot.transpose();
  m.block<3, 3>(1, 1) = indefinite;
  EXPECT_TRUE(project_psd(m.block<3, 3>(1, 1)));
  const Mat3 expected = rot * Vec3(4.0, 0.0, 0.5).asDiagonal() * rot.transpose();
  EXPECT_LT((m.block<3, 3>(1, 1) - expected).norm(), 1e-14 * expected.norm());
  EXPECT_EQ(m(0, 0), 7.0);
  EXPECT_EQ(m(4, 1), 7.0);
  // Singular along a rigid motion, and negative within round-off: kept bit for bit.
  Mat3 singular = rot * Vec3(4.0, 0.0, -1e-12).asDiagonal() * rot.transpose();
  const Mat3 before = singular;
  EXPECT_FALSE(project_psd(singular));
  EXPECT_EQ(singular, before);
  Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(4, 4);
  EXPECT_FALSE(project_psd(zero));
}

// Projected Newton's local Hessians (EnergyTerm::set_projected): with the projection on, a
// term assembles each local Hessian that is indefinite beyond round-off projected, and counts
// it. The projection adds exactly the negative parts: the added matrix is positive
// semi-definite and its trace is the sum of the negative eigenvalues' magnitudes; the projected
// tangent is positive semi-definite. Where no local Hessian is indefinite (an unstrained fiber,
// singular along its rigid motions) nothing changes. Beams at large-deformation states (a
// compressed or sharply bent element) and moments on turned sections.
void expect_projection(EnergyTerm& term, const Model& model, const VecX& q, bool indefinite_expected,
                       const std::string& label) {
  TermHarness h(term, model);
  int indefinite = 0;
  double negative = 0.0;
  for (Index k = 0; k < term.num_local(); ++k) {
    const Eigen::MatrixXd local = term.local_hessian(k, q);
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(local).eigenvalues();
    if (ev.minCoeff() >= -1e-10 * local.diagonal().cwiseAbs().maxCoeff()) continue;
    ++indefinite;
    for (Index i = 0; i < ev.size(); ++i) negative += std::max(0.0, -ev[i]);
  }
  EXPECT_EQ(indefinite > 0, indefinite_expected) << term.name() << ", " << label;
  const Eigen::MatrixXd exact = h.assemble(q, false, true).hessian;
  ASSERT_TRUE(term.set_projected(true)) << term.name();
  const Eigen::MatrixXd projected = h.assemble(q, false, true).hessian;
  term.set_projected(false);
  EXPECT_EQ(term.take_projections(), indefinite) << term.name() << ", " << label;
  EXPECT_EQ(term.take_projections(), 0);
  // Off again: the exact Hessian.
  EXPECT_EQ(h.assemble(q, false, true).hessian, exact) << term.name() << ", " << label;
  const double scale = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(exact).eigenvalues().cwiseAbs().maxCoeff();
  if (indefinite == 0) {
    EXPECT_EQ(projected, exact) << term.name() << ", " << label;
    return;
  }
  const Eigen::MatrixXd added = projected - exact;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(added).eigenvalues().minCoeff(), -1e-12 * scale)
      << term.name() << ", " << label;
  EXPECT_NEAR(added.trace(), negative, 1e-9 * scale) << term.name() << ", " << label;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(projected).eigenvalues().minCoeff(), -1e-12 * scale)
      << term.name() << ", " << label;
  EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(exact).eigenvalues().minCoeff(), -1e-9 * scale)
      << term.name() << ", " << label;
}

TEST(EnergyTerms, ProjectedNewtonLocalHessians) {
  const Case c = parse_case_toml(kHelix, "helix.toml");
  const Model model = build_model(c);
  std::mt19937 rng(11);
  BeamTerm beams(model);
  expect_projection(beams, model, model.reference, false, "reference");
  // The helix compressed along its axis to 60 % of its height with its sections turned about
  // it: compressed, sharply bent elements.
  for (int trial = 0; trial < 2; ++trial) {
    VecX q = random_state(model, rng, 0.4);
    for (Index k = 0; k < model.num_nodes(); ++k) q.segment<3>(9 * k) *= 0.6;
    expect_projection(beams, model, q, true, "compressed " + std::to_string(trial));
  }
  LoadTerm loads(model);
  EXPECT_FALSE(loads.set_projected(true)) << "no moments: nothing to project";
  loads.set_projected(false);
  for (Index k : {2, 4, 6}) loads.moments().push_back({k, 30.0 * random_unit(rng)});
  expect_projection(loads, model, model.reference, true, "reference");
  expect_projection(loads, model, random_state(model, rng, 0.4), true, "random");
}

// The problem sums exactly its terms.
TEST(EnergyTerms, ProblemIsTheSumOfItsTerms) {
  BoundFibers fx;
  const Model& model = fx.model;
  BodySystem& bodies = fx.bodies;
  Problem p(model, &bodies);
  std::vector<std::string> names;
  for (const EnergyTerm* t : p.terms()) names.push_back(t->name());
  EXPECT_EQ(names, (std::vector<std::string>{"beam elements", "contact pairs", "bindings", "drag", "external work"}));
  std::mt19937 rng(4);
  const VecX q = random_state(model, rng, 1.0);
  p.set_drag(10.0, model.reference, 1.0, 0.5);
  p.forces()[3] = 2.0;
  const double total = p.evaluate(q, nullptr, nullptr);
  double sum = 0.0;
  for (EnergyTerm* t : p.terms()) {
    TermHarness h(*t, model);  // (repoints the drag's value positions: energies only after this)
    sum += h.energy(q);
  }
  EXPECT_NEAR(total, sum, 1e-12 * std::abs(total));
}

// The hooks by which the solver handles a term's lagged state (assembly/energy_term.hpp).
TEST(EnergyTerms, ContactStateIsSavedRestoredAndCommitted) {
  std::mt19937 rng(11);
  Crossing x(rng, 3);
  for (int k = 0; k < 3; ++k) x.set_slip(k, k == 2 ? 3.0 : 0.4, rng);
  x.set_gap(0, -2e-6);
  for (ContactElement& e : x.elements) e.fresh = true;
  Problem p(x.model);
  const ContactTerm& term = dynamic_cast<const ContactTerm&>(*p.terms()[1]);
  ASSERT_TRUE(p.set_contacts(x.elements, x.friction));
  const Index nonzeros = p.pattern().nonzeros();
  // No solution recorded: nothing to commit from.
  VecX q = x.q;
  p.set_contact_solution({});
  EXPECT_THROW(p.commit(q), std::logic_error);
  const std::vector<ContactResponse> solution = p.contact_responses(x.q);
  p.set_contact_solution(solution);
  const LaggedStates saved = p.save_lagged();
  const double energy = p.evaluate(x.q, nullptr, nullptr);  // with the saved friction history
  p.commit(q);
  EXPECT_EQ(q, x.q);  // the contact term's dofs are positions: nothing rewritten
  const std::vector<ContactResponse> after = p.contact_responses(x.q);
  for (size_t k = 0; k < 3; ++k) {
    const ContactElement& c = term.contacts()[k];
    EXPECT_FALSE(c.fresh);
    EXPECT_EQ(c.friction_previous, solution[k].friction);
    EXPECT_EQ(c.separation_previous, particle_position(c.b, x.q.data() + 27) - particle_position(c.a, x.q.data()));
    // Committed at q, the friction force at q is the one committed, in stick and in slip, to
    // round-off: the force is the stick stiffness times a slip found as the difference of
    // separations of ~1e-3 m (eps x 1e-3 m against a slip of ~1e-7 m: 1e-12 relative; the
    // sanitizers' build, without fused multiply-adds, measured 1.1e-12).
    EXPECT_LT((after[k].friction - solution[k].friction).norm(), 1e-9 * solution[k].friction.norm()) << k;
  }
  // Other elements (another pattern), then the saved ones back: pattern and energy as before.
  EXPECT_TRUE(p.set_contacts({}, x.friction));
  EXPECT_LT(p.pattern().nonzeros(), nonzeros);
  EXPECT_TRUE(p.restore_lagged(saved));
  EXPECT_EQ(p.pattern().nonzeros(), nonzeros);
  ASSERT_EQ(term.contacts().size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_TRUE(term.contacts()[k].fresh);
    EXPECT_EQ(term.contacts()[k].friction_previous, x.elements[k].friction_previous);
  }
  EXPECT_EQ(term.solution().size(), 3u);
  EXPECT_EQ(p.evaluate(x.q, nullptr, nullptr), energy);
  // Restored with the same element pairs: the pattern stays.
  EXPECT_FALSE(p.restore_lagged(saved));
}

// The fixed-point hooks (EnergyTerm::begin_fixed_point, update_fixed_point): the contact term's
// cones take the normal force at the state they are given, its normals the contact manager's
// update, and the change they report is how far both moved.
TEST(EnergyTerms, ContactFixedPointIsItsNormalsAndCones) {
  std::mt19937 rng(13);
  Crossing x(rng, 1);
  x.set_gap(0, -2e-6);
  Problem p(x.model);
  const ContactTerm& term = dynamic_cast<const ContactTerm&>(*p.terms()[1]);
  ASSERT_TRUE(p.set_contacts(x.elements, x.friction));
  // Without friction the cones stay as they are; without a normal rule, the normals.
  FrictionParams frictionless = x.friction;
  frictionless.mu = 0.0;
  p.set_contacts(x.elements, frictionless);
  p.begin_fixed_point(x.q);
  EXPECT_EQ(term.contacts()[0].friction_normal, x.elements[0].friction_normal);
  VecX moved = x.q;
  moved.segment<3>(27) += 1e-4 * random_unit(rng);  // fiber "high"'s first node
  FixedPointChange none = p.update_fixed_point(moved);
  EXPECT_EQ(none.turn, 0.0);
  EXPECT_EQ(none.relative, 0.0);
  EXPECT_EQ(term.contacts()[0].normal, x.elements[0].normal);
  // With friction: the cone takes the normal force at the state; pressed further, the change
  // is the cone's over its new force.
  p.set_contacts(x.elements, x.friction);
  p.begin_fixed_point(x.q);
  const double fn = p.contact_responses(x.q)[0].normal_force;
  ASSERT_GT(fn, 0.0);
  EXPECT_EQ(term.contacts()[0].friction_normal, fn);
  moved = x.q;
  for (int n = 3; n < 6; ++n) moved.segment<3>(9 * n) -= 1e-6 * x.elements[0].normal;  // fiber "high", deeper
  const FixedPointChange pressed = p.update_fixed_point(moved);
  const double fn_pressed = p.contact_responses(moved)[0].normal_force;
  ASSERT_GT(fn_pressed, fn);
  EXPECT_EQ(pressed.turn, 0.0);
  EXPECT_EQ(term.contacts()[0].friction_normal, fn_pressed);
  EXPECT_NEAR(pressed.relative, (fn_pressed - fn) / fn_pressed, 1e-15);
  // With the manager's rule: the normals as ContactManager::update_normals turns them (from the
  // fixture's random normal to the one between section centres), then the cones at the new
  // normals.
  ContactSpec spec = x.c.contact;
  spec.enabled = true;
  ContactManager manager(x.model, spec);
  p.set_normal_rule(&manager);
  std::vector<ContactElement> expected = term.contacts();
  double idle = -1.0;
  const double turn = manager.update_normals(expected, moved, &idle);
  ASSERT_GT(std::max(turn, idle), spec.normal_tolerance);
  const FixedPointChange change = p.update_fixed_point(moved);
  EXPECT_EQ(change.turn, turn);
  EXPECT_EQ(change.idle_turn, idle);
  EXPECT_EQ(term.contacts()[0].normal, expected[0].normal);
  EXPECT_NE(term.contacts()[0].normal, x.elements[0].normal);
  EXPECT_EQ(term.contacts()[0].friction_normal, p.contact_responses(moved)[0].normal_force);
  // At the fixed point nothing moves.
  const FixedPointChange settled = p.update_fixed_point(moved);
  EXPECT_LT(std::max(settled.turn, settled.idle_turn), 1e-7);  // (acos near 1)
  EXPECT_EQ(settled.relative, 0.0);
}

// The solver's adaptive contact tangent (ContactTerm::mark_overshoots): a step that turns one
// slipping element's slip back marks that element alone (its energy rose above its exact
// model); a step that slides it further marks nothing; nor does a step that opens an open
// element, while one that presses it in marks it. A marked element assembles the tangent
// above its energy; the marks are saved and restored with the term's lagged state and dropped
// with new elements.
TEST(EnergyTerms, ContactMarksTheElementsWhoseSlipAStepTurnsBack) {
  std::mt19937 rng(17);
  Crossing x(rng, 2);
  x.set_gap(0, -2e-6);
  x.set_gap(1, -2e-6);
  x.set_slip(0, 3.0, rng);  // slipping
  x.set_slip(1, 0.4, rng);  // sticking
  Problem p(x.model);
  ContactTerm& term = dynamic_cast<ContactTerm&>(*p.terms()[1]);
  p.set_contacts(x.elements, x.friction);
  const std::vector<ContactResponse> r = p.contact_responses(x.q);
  ASSERT_TRUE(r[0].slip);
  ASSERT_FALSE(r[1].slip);
  // Fiber "high" (nodes 3-5) moved as a whole, along element 0's friction force (its slip,
  // continued) or against it by five elastic slips (turned back through the stick disc).
  auto moved = [&](const Vec3& v) {
    VecX dq = VecX::Zero(x.q.size());
    for (int n = 3; n < 6; ++n) dq.segment<3>(9 * n) = v;
    return dq;
  };
  const Vec3 along = r[0].friction.normalized();
  const VecX further = moved(1e-6 * along), back = moved(-5.0 * x.friction.elastic_slip * along);
  EXPECT_EQ(p.mark_overshoots(x.q, further), 0);
  EXPECT_EQ(term.marked(), std::vector<char>({0, 0}));
  TermHarness h(term, x.model);
  const Eigen::MatrixXd exact = h.assemble(x.q, false, true).hessian;
  const LaggedStates unmarked = p.save_lagged();
  EXPECT_EQ(p.mark_overshoots(x.q, back), 1);
  EXPECT_EQ(term.marked(), std::vector<char>({1, 0}));
  const Eigen::MatrixXd marked = h.assemble(x.q, false, true).hessian;
  EXPECT_GT((marked - exact).norm(), 1e-3 * exact.norm());
  EXPECT_LT(rel_error(h.local_sum(x.q), marked, 1e6), 1e-12);
  // Marking again adds nothing.
  EXPECT_EQ(p.mark_overshoots(x.q, back), 0);
  // Only element 0's tangent changed: the same as that of every element marked.
  term.set_tangent(ContactTangent::Majorizing);
  EXPECT_EQ(h.assemble(x.q, false, true).hessian, marked);
  term.set_tangent(ContactTangent::Exact);
  // Saved and restored with the lagged state; new elements start unmarked.
  const LaggedStates saved = p.save_lagged();
  p.restore_lagged(unmarked);
  EXPECT_EQ(term.marked(), std::vector<char>({0, 0}));
  p.restore_lagged(saved);
  EXPECT_EQ(term.marked(), std::vector<char>({1, 0}));
  p.set_contacts(x.elements, x.friction);
  EXPECT_EQ(term.marked(), std::vector<char>({0, 0}));
  // Without friction: an open element that a step presses in is marked (its model has no
  // curvature, its energy rises), one that it opens is not.
  Crossing y(rng, 1);
  y.set_gap(0, 1e-7);
  FrictionParams frictionless = y.friction;
  frictionless.mu = 0.0;
  Problem pn(y.model);
  const ContactTerm& open = dynamic_cast<const ContactTerm&>(*pn.terms()[1]);
  pn.set_contacts(y.elements, frictionless);
  auto normal_step = [&](double size) {
    VecX dq = VecX::Zero(y.q.size());
    for (int n = 3; n < 6; ++n) dq.segment<3>(9 * n) = size * y.elements[0].normal;
    return dq;
  };
  EXPECT_EQ(pn.mark_overshoots(y.q, normal_step(1e-6)), 0);
  EXPECT_EQ(pn.mark_overshoots(y.q, normal_step(-2e-6)), 1);
  EXPECT_EQ(open.marked(), std::vector<char>({1}));
}

TEST(EnergyTerms, ContactBoundsTheNewtonStep) {
  std::mt19937 rng(12);
  Crossing x(rng, 1);
  Problem p(x.model);
  const Index n = x.model.num_dofs();
  VecX dq = VecX::Zero(n);
  dq[4] = -4e-3;  // a section vector's component: moves its tip by 4e-3 * its length scale
  EXPECT_EQ(p.step_bound(x.q, dq), 1.0);  // no limit set
  VecX scale = VecX::Ones(n);
  scale[4] = 0.5;
  p.set_step_limit(1e-3, scale);
  EXPECT_DOUBLE_EQ(p.step_bound(x.q, dq), 0.5);  // 1e-3 / (4e-3 * 0.5)
  dq[4] = 1e-4;
  EXPECT_EQ(p.step_bound(x.q, dq), 1.0);
}

TEST(EnergyTerms, BindingStateIsSavedRestoredAndCommitted) {
  BoundFibers fx;
  const Model& model = fx.model;
  BodySystem& bodies = fx.bodies;
  Problem p(model, &bodies);
  std::mt19937 rng(13);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> lambda = bodies.multipliers();
  for (double& l : lambda) l = normal(rng);
  bodies.set_multipliers(lambda);
  const LaggedStates saved = p.save_lagged();
  // An increment's rotation committed: the bodies' rotation dofs start the next one at zero.
  VecX q = model.reference;
  std::vector<Vec3> theta;
  for (const Body& b : model.bodies) {
    theta.push_back(Vec3(normal(rng), normal(rng), normal(rng)) * 0.2);
    q.segment<3>(b.first_dof + 3) = theta.back();
  }
  p.commit(q);
  for (Index b = 0; b < static_cast<Index>(model.bodies.size()); ++b) {
    EXPECT_TRUE(q.segment<3>(model.bodies[b].first_dof + 3).isZero(0.0));
    EXPECT_EQ(bodies.committed_rotation(b), theta[b]);
  }
  std::vector<double> other = lambda;
  for (double& l : other) l += 1.0;
  bodies.set_multipliers(other);
  EXPECT_FALSE(p.restore_lagged(saved));
  EXPECT_EQ(bodies.multipliers(), lambda);
  for (Index b = 0; b < static_cast<Index>(model.bodies.size()); ++b)
    EXPECT_TRUE(bodies.committed_rotation(b).isZero(0.0));
}

TEST(EnergyTerms, BindingUpdatesItsLaggedStateWhenUnsettled) {
  BoundFibers fx;
  const Model& model = fx.model;
  BodySystem& bodies = fx.bodies;
  Problem p(model, &bodies);
  VecX q = model.reference;
  p.begin_lagged(q);
  EXPECT_EQ(bodies.anchor_drift(q), 0.0);
  // Fiber a's last node (bound to tow1) moved across: its binding violated, its anchor drifted.
  const Index node = model.fibers[0].first_node + model.fibers[0].num_nodes - 1;
  q[9 * node + 1] += 1e-3;
  const double violation = bodies.violation(q), drift = bodies.anchor_drift(q);
  ASSERT_GT(violation, 1e-6);
  ASSERT_GT(drift, 1e-6);
  const std::vector<double> lambda = bodies.multipliers();
  // Within the tolerance: settled, nothing changes.
  EXPECT_TRUE(p.update_lagged(q, {2.0 * std::max(violation, drift), 0.0}));
  EXPECT_EQ(bodies.multipliers(), lambda);
  EXPECT_EQ(bodies.anchor_drift(q), drift);
  // Drifted, the violation within the tolerance, but the anchors' springs pull with less than a
  // thousandth of the force left: settled.
  const double pull = bodies.proximal_stiffness() * drift;
  EXPECT_TRUE(p.update_lagged(q, {violation, 1001.0 * pull}));
  // ... and with more: the anchors follow, the multipliers stay.
  EXPECT_FALSE(p.update_lagged(q, {violation, 999.0 * pull}));
  EXPECT_EQ(bodies.multipliers(), lambda);
  EXPECT_EQ(bodies.anchor_drift(q), 0.0);
  // Violated: the multipliers are updated (and the anchors follow).
  q[9 * node + 1] += 1e-3;
  EXPECT_FALSE(p.update_lagged(q, {0.5 * bodies.violation(q), 0.0}));
  EXPECT_NE(bodies.multipliers(), lambda);
  EXPECT_EQ(bodies.anchor_drift(q), 0.0);
}

}  // namespace
}  // namespace fibra
