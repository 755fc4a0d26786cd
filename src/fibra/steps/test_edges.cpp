#include "fibra/steps/test_edges.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "fibra/model/fabric.hpp"

namespace fibra {

std::optional<TestEdges> find_test_edges(const Case& c, const Model& model) {
  TestEdges edges;
  for (int e = 0; e < 4; ++e) {
    edges.body[e] = model.body_index(kEdgeBodies[e]);
    if (edges.body[e] < 0) return std::nullopt;
    edges.first_dof[e] = model.bodies[edges.body[e]].first_dof;
  }
  for (int e : {0, 1})
    for (const BindingSpec& b : c.bindings) {
      if (b.body != kEdgeBodies[e]) continue;
      for (const std::string& child : b.bodies) {
        const int cb = model.body_index(child);
        if (cb >= 0) edges.bound[e].push_back(model.bodies[cb].first_dof);
      }
    }
  return edges;
}

void test_edge_conditions(const StepSpec& st, const TestEdges& edges, const VecX& force_end,
                          std::map<Index, std::pair<double, double>>& disp) {
  auto dof = [&](int e, int k) { return edges.first_dof[e] + k; };
  auto move = [&](int e, int k, double by) { disp.at(dof(e, k)).second += by; };
  if (st.kind == StepSpec::Kind::Biaxial) {
    // Warp edges pulled apart by strain x their distance, each by half of it, so that the
    // fabric's centre stays where it is; the weft ones likewise by ratio x that strain x
    // theirs, or the y+ edge free along the weft (ratio 0: uniaxial, the weft keeps its load).
    // Moving one edge of each pair by the whole elongation (the other held) carried the
    // fabric's middle along x by strain x lx / 2 while the edges across held their tow ends'
    // mean where it was: the tows across were bent in the plane and the held edges took a
    // tangential force that grew with the load (29 N, 6.5 % of the axial force, at 2 % on the
    // 480-fiber plain weave; docs/theory/fabric.md, "Mechanical tests").
    const double ex = 0.5 * st.strain * edges.lx;
    move(0, 0, -ex);
    move(1, 0, ex);
    if (st.ratio > 0.0) {
      const double ey = 0.5 * st.ratio * st.strain * edges.ly;
      move(2, 1, -ey);
      move(3, 1, ey);
    } else {
      disp.erase(dof(3, 1));
    }
    return;
  }
  if (st.kind != StepSpec::Kind::Shear) throw std::logic_error("test_edge_conditions: not a test step");
  // Shear: the y- and y+ edges (bottom and top) moved in opposite senses along x; the lateral
  // x- and x+ edges free to slide along them (y) and to turn about the fabric's normal, and so
  // are the tow ends bound to them; x- stays where it is along x and x+ keeps whatever holds
  // it there (by default free under the warp tension). The height held: each edge moves by
  // (ly / 2) tan(angle), and the line between the edges' centres turns by the angle as its
  // length grows by 1 / cos(angle). The height free: the top edge keeps the force it had
  // across (the weft tension) and each edge moves by (ly / 2) sin(angle), the angle the line
  // between them turns by if its length stays.
  const double gamma = st.angle * std::numbers::pi / 180.0;
  const double d = 0.5 * edges.ly * (st.free_height ? std::sin(gamma) : std::tan(gamma));
  move(2, 0, -d);
  move(3, 0, d);
  if (force_end[dof(1, 0)] != 0.0) disp.erase(dof(1, 0));
  if (st.free_height) {
    if (force_end[dof(3, 1)] == 0.0)
      throw std::logic_error("test_edge_conditions: a shear with its height free and no force across (resolve_case "
                             "checks it)");
    disp.erase(dof(3, 1));
  }
  for (int e : {0, 1}) {
    disp.erase(dof(e, 1));
    disp.erase(dof(e, 5));
    for (Index bound : edges.bound[e]) disp.erase(bound + 5);
  }
}

}  // namespace fibra
