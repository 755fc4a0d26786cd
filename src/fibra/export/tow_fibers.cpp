#include "fibra/export/tow_fibers.hpp"

#include <cmath>

namespace fibra {

namespace {

/// v turned so that its largest component (in magnitude) is positive.
Vec3 with_positive_largest_component(const Vec3& v) {
  Eigen::Index k = 0;
  v.cwiseAbs().maxCoeff(&k);
  return v[k] < 0 ? Vec3(-v) : v;
}

}  // namespace

Vec3 fiber_chord(const Model& model, const VecX& q, const Fiber& fiber) {
  const Vec3 first = q.segment<3>(kNodeDofs * fiber.first_node);
  const Vec3 last = q.segment<3>(kNodeDofs * (fiber.first_node + fiber.num_nodes - 1));
  return last - first;
}

TowFibers tow_fibers(const Model& model, const VecX& q, const std::vector<TowSpec>& tows) {
  TowFibers t;
  t.tow_of_fiber.assign(model.fibers.size(), -1);
  t.sign.assign(model.fibers.size(), 1.0);
  for (size_t k = 0; k < tows.size(); ++k) {
    std::vector<int> members;
    Vec3 sum = Vec3::Zero(), first = Vec3::Zero();
    for (const std::string& name : tows[k].fibers) {
      const int f = model.fiber_index(name);
      if (f < 0) continue;  // the reader checked the names; a model built otherwise may lack some
      members.push_back(f);
      t.tow_of_fiber[f] = static_cast<int>(k);
      const Vec3 chord = fiber_chord(model, q, model.fibers[f]);
      if (members.size() == 1) first = chord;
      sum += chord.dot(first) < 0 ? Vec3(-chord) : chord;
    }
    const Vec3 direction = sum.norm() > 0 ? with_positive_largest_component(sum.normalized()) : Vec3::UnitX();
    for (int f : members) t.sign[f] = fiber_chord(model, q, model.fibers[f]).dot(direction) < 0 ? -1.0 : 1.0;
    t.fibers.push_back(std::move(members));
    t.direction.push_back(direction);
  }
  for (size_t f = 0; f < model.fibers.size(); ++f) {
    if (t.tow_of_fiber[f] >= 0) continue;
    const Vec3 chord = fiber_chord(model, q, model.fibers[f]);
    t.sign[f] = chord.dot(with_positive_largest_component(chord)) < 0 ? -1.0 : 1.0;
  }
  return t;
}

}  // namespace fibra
