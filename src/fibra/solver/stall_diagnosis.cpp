#include "fibra/solver/stall_diagnosis.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <vector>

namespace fibra {
namespace {

// A unit direction written with two decimals, its largest component positive (a mode's sign
// is arbitrary).
std::string direction_text(Vec3 v) {
  Index largest = 0;
  v.cwiseAbs().maxCoeff(&largest);
  if (v[largest] < 0) v = -v;
  v /= v.norm();
  for (int k = 0; k < 3; ++k)
    if (std::abs(v[k]) < 0.005) v[k] = 0.0;  // no "-0.00"
  return fmt::format("({:.2f}, {:.2f}, {:.2f})", v.x(), v.y(), v.z());
}

}  // namespace

std::string describe_motion(const Model& model, const VecX& motion, const VecX& length_scale) {
  const Index groups = model.num_groups();
  const Index nodes = model.num_nodes();
  auto group_begin = [&](Index g) { return g < nodes ? kNodeDofs * g : model.bodies[g - nodes].first_dof; };
  auto group_size = [&](Index g) { return g < nodes ? Index{kNodeDofs} : Index{6}; };
  std::vector<double> norm(groups, 0.0);
  for (Index g = 0; g < groups; ++g) {
    double s = 0.0;
    for (Index k = 0; k < group_size(g); ++k) {
      const Index d = group_begin(g) + k;
      s += std::pow(motion[d] * length_scale[d], 2);
    }
    norm[g] = std::sqrt(s);
  }
  const auto top = std::max_element(norm.begin(), norm.end());
  if (top == norm.end() || !(*top > 0.0)) return {};
  const Index g = top - norm.begin();
  const double cut = 0.5 * *top;  // a group moving at least half as much as the most is "where it moves"
  if (g >= nodes) {
    const Body& b = model.bodies[g - nodes];
    const Index d = b.first_dof;
    const Vec3 centre = motion.segment<3>(d).cwiseProduct(length_scale.segment<3>(d));
    const Vec3 turn = motion.segment<3>(d + 3).cwiseProduct(length_scale.segment<3>(d + 3));
    return centre.norm() >= turn.norm()
               ? fmt::format("body \"{}\": its centre, along {}", b.name, direction_text(centre))
               : fmt::format("body \"{}\": its rotation, about {}", b.name, direction_text(turn));
  }
  // The fiber of the node that moves most, the range of its nodes that move at least half as
  // much, and the other fibers that have such nodes too.
  const int fiber = std::max(0, model.fiber_of_node(g));
  const Fiber& f = model.fibers[fiber];
  Index lo = g, hi = g;
  for (Index n = f.first_node; n < f.first_node + f.num_nodes; ++n)
    if (norm[n] >= cut) {
      lo = std::min(lo, n);
      hi = std::max(hi, n);
    }
  int others = 0;
  for (size_t o = 0; o < model.fibers.size(); ++o) {
    if (static_cast<int>(o) == fiber) continue;
    const Fiber& of = model.fibers[o];
    for (Index n = of.first_node; n < of.first_node + of.num_nodes; ++n)
      if (norm[n] >= cut) {
        ++others;
        break;
      }
  }
  for (Index b = 0; b < static_cast<Index>(model.bodies.size()); ++b)
    if (norm[nodes + b] >= cut) ++others;
  // Centre line or sections: the weighed sizes summed over the range.
  double centre = 0.0, sections = 0.0;
  for (Index n = lo; n <= hi; ++n) {
    for (int k = 0; k < 3; ++k) centre += std::pow(motion[kNodeDofs * n + k] * length_scale[kNodeDofs * n + k], 2);
    for (int k = 3; k < kNodeDofs; ++k) sections += std::pow(motion[kNodeDofs * n + k] * length_scale[kNodeDofs * n + k], 2);
  }
  // Node numbers as a case file's `node` counts them: from 0 at the fiber's first node.
  const Index first = lo - f.first_node, last = hi - f.first_node, end = f.num_nodes - 1;
  std::string where = first == last ? fmt::format("fiber \"{}\", node {} (of 0-{})", f.name, first, end)
                                    : fmt::format("fiber \"{}\", nodes {}-{} (of 0-{})", f.name, first, last, end);
  if (others > 0) where += fmt::format(" (and {} other fiber{} or bod{})", others, others > 1 ? "s" : "", others > 1 ? "ies" : "y");
  if (centre >= sections) {
    const Vec3 dir = motion.segment<3>(kNodeDofs * g);
    return fmt::format("{}: the centre line, along {}", where, direction_text(dir));
  }
  return fmt::format("{}: the section vectors (the sections turn or deform)", where);
}

std::string StallDiagnosis::tangent_name() const {
  switch (tangent) {
    case Tangent::Indefinite: return "indefinite";
    case Tangent::Singular: return "singular";
    case Tangent::Definite: return "definite";
    case Tangent::Unknown: break;
  }
  return "unknown";
}

std::string StallDiagnosis::text() const {
  std::string s;
  if (!made) return s;
  if (!refusal.empty()) s = fmt::format("the contact loop refused the last attempt: {}. Besides, ", refusal);
  const std::string mode = softest_mode.empty() ? std::string("(not found)") : softest_mode;
  switch (tangent) {
    case Tangent::Indefinite:
      s += fmt::format(
          "the last equilibrium is unstable (its tangent is indefinite; softest mode {:.3g} N/m, where the softest "
          "fiber bent as a cantilever has {:.3g} N/m): {}. Past a buckling load, a snap-through or a limit load no equilibrium near the "
          "last one follows the load. What can be changed: drive that place by a prescribed displacement instead of a "
          "force or moment, or hold the mode's components with a [[fix]] if the symmetric path is the one wanted.",
          softest_stiffness, bending_stiffness, mode);
      break;
    case Tangent::Singular:
      s += fmt::format(
          "nothing resists a motion of the model (its tangent is singular; softest mode {:.3g} N/m, where the softest "
          "fiber bent as a cantilever has {:.3g} N/m): {}. A fiber held only by what does not hold it yet (contact not reached, a free "
          "spin, a body without support) moves without limit. What can be changed: hold it with a [[fix]] or a "
          "binding, or start it in contact with what should hold it.",
          softest_stiffness, bending_stiffness, mode);
      break;
    case Tangent::Definite:
      s += fmt::format(
          "the last equilibrium is stable (its tangent is positive definite; softest mode {:.3g} N/m, {}), so the "
          "increment's own changes (contact elements appearing, stick and slip switching, large rotations) are too "
          "large for Newton's method. What can be changed: more increments in that step.",
          softest_stiffness, mode);
      break;
    case Tangent::Unknown:
      s += "the tangent at the last equilibrium could not be factorized.";
      break;
  }
  if (!largest_motion.empty()) s += fmt::format(" The failed attempt moved most at {}.", largest_motion);
  return s;
}

}  // namespace fibra
