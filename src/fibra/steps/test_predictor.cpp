#include "fibra/steps/test_predictor.hpp"

#include <algorithm>
#include <cmath>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <fmt/format.h>

#include "fibra/body/bodies.hpp"
#include "fibra/body/rotation.hpp"
#include "fibra/core/debug.hpp"
#include "fibra/model/fabric.hpp"

namespace fibra {

void predict_test_level(const Model& model, const BodySystem* bodies, const TestEdges* edges, const StepSpec& st,
                        const std::map<Index, std::pair<double, double>>& disp, const std::vector<char>& fixed,
                        const VecX& before, VecX& q) {
  if (!edges) return;
  // Each edge body's motion to lambda (zero along its free components) and its centre now.
  Vec3 centre[4], motion[4];
  const std::array<Index, 4>& first_dof = edges->first_dof;
  for (int e = 0; e < 4; ++e) {
    const Index d0 = first_dof[e];
    centre[e] = before.segment<3>(d0);
    motion[e] = q.segment<3>(d0) - before.segment<3>(d0);
  }
  const double lx = centre[1].x() - centre[0].x(), ly = centre[3].y() - centre[2].y();
  if (!(lx > 0.0 && ly > 0.0)) return;
  // A shear with its height free: the top edge's motion across is predicted from the length
  // of the line between the bottom and top edges' centres, kept (the wefts keep their length):
  // its offset along x since the step's start grows by the edges' motions.
  if (st.kind == StepSpec::Kind::Shear && st.free_height) {
    const auto start_x = [&](Index d) {
      const auto it = disp.find(d);
      return model.reference[d] + (it != disp.end() ? it->second.first : 0.0);
    };
    const double offset = (centre[3].x() - centre[2].x()) - (start_x(first_dof[3]) - start_x(first_dof[2]));
    const double moved = offset + motion[3].x() - motion[2].x();
    const double squared = offset * offset + ly * ly - moved * moved;
    if (squared > 0.0) motion[3].y() = std::sqrt(squared) - ly;
  }
  // The motion at a point: linear between the x- and x+ edges plus linear between the y- and
  // y+ edges (biaxial: each pair moves along its own axis; shear: only the y pair moves, along
  // x), constant beyond them; `gradient` its derivative.
  auto field = [&](const Vec3& p, Mat3* gradient) {
    const double tx = (p.x() - centre[0].x()) / lx, ty = (p.y() - centre[2].y()) / ly;
    const double sx = std::clamp(tx, 0.0, 1.0), sy = std::clamp(ty, 0.0, 1.0);
    if (gradient) {
      gradient->setZero();
      if (tx > 0.0 && tx < 1.0) gradient->col(0) = (motion[1] - motion[0]) / lx;
      if (ty > 0.0 && ty < 1.0) gradient->col(1) = (motion[3] - motion[2]) / ly;
    }
    return Vec3((1.0 - sx) * motion[0] + sx * motion[1] + (1.0 - sy) * motion[2] + sy * motion[3]);
  };
  Mat3 gradient;
  for (Index node = 0; node < model.num_nodes(); ++node) {
    const Index base = 9 * node;
    if (fixed[base] || fixed[base + 1] || fixed[base + 2]) continue;
    q.segment<3>(base) += field(q.segment<3>(base), &gradient);
    // The section vectors turn with the fiber: by the rotation that takes the section's normal
    // (the fiber's tangent) to the tangent moved by the field's gradient; no stretch.
    const Vec3 g1 = q.segment<3>(base + 3), g2 = q.segment<3>(base + 6);
    const Vec3 t = g1.cross(g2).normalized();
    const Vec3 moved = t + gradient * t;
    if (!(moved.norm() > 0.0) || !t.allFinite()) continue;
    const Mat3 turn = Eigen::Quaterniond::FromTwoVectors(t, moved).toRotationMatrix();
    q.segment<3>(base + 3) = turn * g1;
    q.segment<3>(base + 6) = turn * g2;
  }
  // The bodies follow their members so that their bindings hold as they did: a binding ties
  // the mean of its members to the body and their best-fit rotation to the body's frame
  // (body/bodies.hpp). A body free to turn (shear: the lateral edges and their tow ends, about
  // z) takes the rotation that best fits its members' motion (Procrustes: the exact angle
  // about a single free axis, Kabsch's rotation when more are free), and its centre keeps its
  // place relative to the members' mean. On the 2 x 2 sample sheared by 2 degrees the
  // bindings' largest violation after the prediction is 2.2e-7 m, against 3.5e-5 m with the
  // edges moved alone; what is left is the grips' (a simple shear stretches a gripped tow
  // end's width by gamma^2 / 2). Moving the centres alone, without the turn, left the 480-fiber
  // shear a residual of 2.7e5 N on an edge's turn. A body that cannot turn keeps the members'
  // mean translation. A body bound to bodies (an edge to its tow ends) must see its members
  // already moved: the passes repeat until one changes nothing (each body's update depends
  // only on its members, so one pass per level of the hierarchy, whatever the bodies' order).
  if (bodies) {
    const Index nubodies = static_cast<Index>(model.bodies.size());
    for (Index pass = 0; pass <= nubodies; ++pass) {
      bool changed = false;
      for (Index b = 0; b < nubodies; ++b) {
        const Index d0 = model.bodies[b].first_dof;
        bool moves = false;
        for (int k = 0; k < 6; ++k) moves = moves || !fixed[d0 + k];
        if (!moves) continue;
        const std::vector<Vec3> old_members = bodies->member_positions(b, before);
        const std::vector<Vec3> new_members = bodies->member_positions(b, q);
        if (old_members.empty()) continue;
        const double n = static_cast<double>(old_members.size());
        Vec3 mean = Vec3::Zero(), moved_mean = Vec3::Zero();
        for (size_t m = 0; m < old_members.size(); ++m) {
          mean += old_members[m] / n;
          moved_mean += new_members[m] / n;
        }
        Vec3 w = Vec3::Zero();
        int free_axes = 0, axis = 0;
        for (int k = 0; k < 3; ++k)
          if (!fixed[d0 + 3 + k]) ++free_axes, axis = k;
        if (free_axes == 1) {
          const Vec3 e = Vec3::Unit(axis);
          double sin_sum = 0.0, cos_sum = 0.0;
          for (size_t m = 0; m < old_members.size(); ++m) {
            const Vec3 a = old_members[m] - mean, c = new_members[m] - moved_mean;
            sin_sum += e.dot(a.cross(c));
            cos_sum += a.dot(c) - e.dot(a) * e.dot(c);
          }
          if (sin_sum != 0.0 || cos_sum != 0.0) w[axis] = std::atan2(sin_sum, cos_sum);
        } else if (free_axes > 1) {
          Mat3 h = Mat3::Zero();
          for (size_t m = 0; m < old_members.size(); ++m)
            h += (new_members[m] - moved_mean) * (old_members[m] - mean).transpose();
          const Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
          Mat3 sign = Mat3::Identity();
          sign(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
          w = rotation_log(svd.matrixU() * sign * svd.matrixV().transpose());
          for (int k = 0; k < 3; ++k)
            if (fixed[d0 + 3 + k]) w[k] = 0.0;
        }
        if (!w.allFinite()) w.setZero();
        const Vec3 centre_before = before.segment<3>(d0);
        const Vec3 moved_centre = moved_mean - rotation_exp(w) * (mean - centre_before);
        for (int k = 0; k < 3; ++k) {
          if (!fixed[d0 + k] && q[d0 + k] != moved_centre[k]) q[d0 + k] = moved_centre[k], changed = true;
          const double turned = before[d0 + 3 + k] + w[k];
          if (!fixed[d0 + 3 + k] && q[d0 + 3 + k] != turned) q[d0 + 3 + k] = turned, changed = true;
        }
      }
      if (!changed) break;
    }
  }
  if (debug_newton() && bodies) {
    VecX edges_only = before;
    for (Index i = 0; i < edges_only.size(); ++i)
      if (fixed[i]) edges_only[i] = q[i];
    double moved = 0.0;
    for (Index node = 0; node < model.num_nodes(); ++node)
      moved = std::max(moved, (q.segment<3>(9 * node) - before.segment<3>(9 * node)).norm());
    fmt::print(stderr,
               " level predictor: nodes moved up to {:.3e} m; bindings' largest violation {:.3e} m ({:.3e} m with the "
               "edges moved alone)\n",
               moved, bodies->violation(q), bodies->violation(edges_only));
  }
}

}  // namespace fibra
