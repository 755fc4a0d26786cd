#include "fibra/export/element_grid.hpp"

#include <algorithm>
#include <numeric>

namespace fibra {

Eigen::AlignedBox3d element_box(const Model& model, const VecX& q, Index e) {
  const BeamElement& el = model.elements[e];
  const Section& section = model.sections[el.section];
  const double* node = q.data() + el.first_dof;
  auto control = [&](int dof) -> std::array<Vec3, 3> {
    const Eigen::Map<const Vec3> v0(node + dof), v1(node + kNodeDofs + dof), v2(node + 2 * kNodeDofs + dof);
    return {Vec3(v0), Vec3(2.0 * v1 - 0.5 * (v0 + v2)), Vec3(v2)};
  };
  const auto x = control(0), g1 = control(3), g2 = control(6);
  double reach = 0;
  for (int k = 0; k < 3; ++k) reach = std::max(reach, section.a * g1[k].norm() + section.b * g2[k].norm());
  Eigen::AlignedBox3d box;
  for (const Vec3& p : x) box.extend(p);
  box.min().array() -= reach;
  box.max().array() += reach;
  return box;
}

std::vector<Index> ElementGrid::all_if_empty(const Model& model, std::vector<Index> elements) {
  if (elements.empty()) {
    elements.resize(model.elements.size());
    std::iota(elements.begin(), elements.end(), Index{0});
  }
  return elements;
}

ElementGrid::ElementGrid(const Model& model, const VecX& q, std::vector<Index> elements)
    : m_elements(all_if_empty(model, std::move(elements))), m_slot(model.elements.size(), -1), m_grid([&] {
        std::vector<Eigen::AlignedBox3d> boxes;
        for (Index e : m_elements) boxes.push_back(element_box(model, q, e));
        return boxes;
      }()) {
  for (size_t s = 0; s < m_elements.size(); ++s) m_slot[m_elements[s]] = static_cast<Index>(s);
}

void ElementGrid::find(const Eigen::AlignedBox3d& box, std::vector<Index>& out) const {
  m_grid.find(box, out);
  for (Index& n : out) n = m_elements[n];
  std::sort(out.begin(), out.end());
}

}  // namespace fibra
