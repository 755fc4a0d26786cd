#include "fibra/body/bodies.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "fibra/assembly/psd_projection.hpp"
#include "fibra/body/rotation.hpp"
#include "fibra/core/error.hpp"

namespace fibra {
namespace {

/// Gram–Schmidt on the columns (removes round-off drift of products of rotations).
Mat3 orthonormalized(const Mat3& d) {
  Mat3 r;
  r.col(0) = d.col(0).normalized();
  r.col(1) = (d.col(1) - d.col(1).dot(r.col(0)) * r.col(0)).normalized();
  r.col(2) = r.col(0).cross(r.col(1));
  return r;
}

}  // namespace

BodySystem::BodySystem(const Case& c, const Model& model) : m_model(model) {
  const Index nb = static_cast<Index>(model.bodies.size());
  m_bodies.resize(nb);
  for (Index b = 0; b < nb; ++b) m_bodies[b].frame_ref = model.bodies[b].axes;

  // Stiffness scale of the model: the axial stiffness of the stiffest fiber's node spacing.
  double k_ref = 0.0;
  for (const Fiber& f : model.fibers) {
    const double ea = model.materials[f.material].young * model.sections[f.section].area;
    k_ref = std::max(k_ref, ea * 2.0 * static_cast<double>(f.num_elements) / f.length);
  }
  if (k_ref <= 0.0) k_ref = 1.0;
  // Proximal spring: small enough to leave the solution unbiased (its force at convergence is
  // below mu * tolerance) and the convergence of genuine modes untouched, large enough that a
  // member's undetermined rigid motion has pivots far above round-off.
  m_mu = 1e-10 * k_ref;

  // Resolve members.
  std::vector<std::vector<int>> parent_of(nb);  // bindings whose body is b
  for (size_t i = 0; i < c.bindings.size(); ++i) {
    const BindingSpec& spec = c.bindings[i];
    const std::string key = fmt::format("binding[{}]", i);
    Binding bd;
    bd.body = model.body_index(spec.body);
    if (bd.body < 0) throw InputError(c.file, key + ".body", fmt::format("no body named \"{}\"", spec.body));
    for (size_t j = 0; j < spec.ends.size(); ++j) {
      const Index node = model.node_index(spec.ends[j], c.file, fmt::format("{}.ends[{}]", key, j));
      Member m;
      m.group = node;
      m.dof = kNodeDofs * node;
      if (const int f = model.fiber_of_node(node); f >= 0) {
        const Section& section = model.sections[model.fibers[f].section];
        m.r2 = section.a * section.b;
      }
      m.anchor = model.reference.segment<9>(m.dof);
      bd.members.push_back(m);
    }
    for (size_t j = 0; j < spec.bodies.size(); ++j) {
      const int cb = model.body_index(spec.bodies[j]);
      if (cb < 0)
        throw InputError(c.file, fmt::format("{}.bodies[{}]", key, j), fmt::format("no body named \"{}\"", spec.bodies[j]));
      if (cb == bd.body)
        throw InputError(c.file, fmt::format("{}.bodies[{}]", key, j),
                         fmt::format("body \"{}\" cannot be bound to itself", spec.bodies[j]));
      Member m;
      m.group = model.body_group(cb);
      m.dof = model.bodies[cb].first_dof;
      m.body = cb;
      bd.members.push_back(m);
    }
    if (bd.members.empty())
      throw InputError(c.file, key, "a binding needs members: give `ends` and/or `bodies`");
    for (int axis : spec.grip) {
      if (axis < 1 || axis > 3 || spec.grip.size() > 2)
        throw InputError(c.file, key + ".grip", "expected at most two of the body's axes 1, 2, 3");
      bd.grip.push_back(axis - 1);
    }
    if (!bd.grip.empty() && spec.ends.empty())
      throw InputError(c.file, key + ".grip", "a grip holds bound fiber ends, and this binding has none");
    bd.spin = spec.spin;
    if (bd.spin && spec.ends.empty())
      throw InputError(c.file, key + ".spin", "a spin hold holds bound fiber ends, and this binding has none");
    if (bd.spin) {
      const Mat3& axes = model.bodies[bd.body].axes;
      for (Member& m : bd.members) {
        if (m.body >= 0) continue;
        const Vec3 g1 = axes.transpose() * model.reference.segment<3>(m.dof + 3);
        const Vec3 g2 = axes.transpose() * model.reference.segment<3>(m.dof + 6);
        if (!(g1.norm() > 0.0) || !(g2.norm() > 0.0) || g1.cross(g2).norm() < 1e-6 * g1.norm() * g2.norm())
          throw InputError(c.file, key + ".spin", "a bound node's section vectors are degenerate: its spin is undefined");
        m.b1 = g1.normalized();
        m.b2 = g2.normalized();
        m.s0 = 0.5 * std::sqrt(m.r2) * (m.b2.dot(g1) - m.b1.dot(g2));
      }
    }
    parent_of[bd.body].push_back(static_cast<int>(i));
    m_bindings.push_back(std::move(bd));
  }
  for (Index b = 0; b < nb; ++b)
    if (parent_of[b].empty())
      throw InputError(c.file, fmt::format("body[{}]", b),
                       fmt::format("body \"{}\" has no members: bind fiber nodes or bodies to it with a [[binding]] "
                                   "whose body = \"{}\" (a body alone has nothing to move)",
                                   model.bodies[b].name, model.bodies[b].name));

  // Sizes and node counts, children first (depth-first; a cycle is an input error).
  std::vector<int> visit(nb, 0);
  std::vector<double> node_count(nb, 0.0);
  std::function<void(Index)> size_of = [&](Index b) {
    if (visit[b] == 2) return;
    if (visit[b] == 1)
      throw InputError(c.file, "binding", fmt::format("body \"{}\" is bound (through other bodies) to itself", model.bodies[b].name));
    visit[b] = 1;
    for (int i : parent_of[b]) {
      Binding& bd = m_bindings[i];
      const Body& body = model.bodies[b];
      double count = 0.0;
      for (Member& m : bd.members) {
        if (m.body >= 0) {
          size_of(m.body);
          m.l2 = m_bodies[m.body].size * m_bodies[m.body].size;
          count += node_count[m.body];
        } else {
          count += 1.0;
        }
        m.a = body.axes.transpose() * (model.reference.segment<3>(m.dof) - body.center);
      }
      const double n = static_cast<double>(bd.members.size());
      bd.mean.setZero();
      for (const Member& m : bd.members) bd.mean += m.a / n;
      Mat3 inertia = Mat3::Zero();
      double sum2 = 0.0;
      bool has_body = false;
      for (Member& m : bd.members) {
        m.a -= bd.mean;
        inertia += m.a.squaredNorm() * Mat3::Identity() - m.a * m.a.transpose() + 2.0 * m.l2 * Mat3::Identity();
        sum2 += m.a.squaredNorm() + m.l2;
        has_body = has_body || m.body >= 0;
      }
      const Eigen::SelfAdjointEigenSolver<Mat3> eig(inertia);
      const double lmax = eig.eigenvalues().maxCoeff();
      if (!(lmax > 0.0) || eig.eigenvalues().minCoeff() < 1e-6 * lmax) {
        const std::string why = (bd.members.size() < 3 && !has_body) ? fmt::format("are only {}", bd.members.size())
                                                                      : std::string("lie on one line");
        throw InputError(c.file, fmt::format("binding[{}]", i),
                         fmt::format("the members bound to body \"{}\" {}: they cannot define a mean rotation; bind at "
                                     "least 3 fiber nodes that are not on one line (or bodies)",
                                     body.name, why));
      }
      bd.s = std::sqrt(sum2 / n);
      bd.k = c.solver.method.binding_stiffness > 0.0 ? c.solver.method.binding_stiffness : 100.0 * k_ref * count;
      // A grip condition holds one node: the stiffness the averaged position gives its mean.
      bd.kg = c.solver.method.binding_stiffness > 0.0 ? c.solver.method.binding_stiffness : 100.0 * k_ref;
      m_bodies[b].size = std::max(m_bodies[b].size, bd.s);
      node_count[b] += count;
    }
    visit[b] = 2;
  };
  for (Index b = 0; b < nb; ++b) size_of(b);

  // Stencils and local layout.
  int largest = 0;
  for (Binding& bd : m_bindings) {
    std::vector<Index> groups;
    int off = 0;
    for (Member& m : bd.members) {
      m.offset = off;
      off += m.body >= 0 ? 6 : kNodeDofs;
      groups.push_back(m.group);
    }
    bd.parent_offset = off;
    bd.local_size = off + 6;
    groups.push_back(model.body_group(bd.body));
    m_stencils.add(groups);
    largest = std::max(largest, bd.local_size);
  }
  m_stencils.colorize(model.num_groups());
  m_g.setZero(largest);
  m_h.setZero(largest, largest);
}

Vec6 BodySystem::spatial_conditions(const Binding& b, const VecX& q) const {
  const Body& body = m_model.bodies[b.body];
  const Mat3& dref = m_bodies[b.body].frame_ref;
  const Vec3 r = q.segment<3>(body.first_dof);
  const Mat3 e = rotation_exp(-q.segment<3>(body.first_dof + 3).eval());
  const double n = static_cast<double>(b.members.size());
  const double w = 1.0 / (n * b.s);
  Vec3 pbar = Vec3::Zero(), grot = Vec3::Zero();
  for (const Member& m : b.members) {
    const Vec3 p = q.segment<3>(m.dof);
    pbar += p / n;
    grot += (dref * m.a).cross(e * (p - r));
    if (m.body >= 0) {
      const Body& child = m_model.bodies[m.body];
      const Mat3 kc = m_bodies[m.body].frame_ref * child.axes.transpose() * body.axes * dref.transpose();
      grot += m.l2 * vee_antisymmetric(e * rotation_exp(q.segment<3>(m.dof + 3).eval()) * kc);
    }
  }
  Vec6 g;
  g.head<3>() = e * (pbar - r) - dref * b.mean;
  g.tail<3>() = w * grot;
  return g;
}

Vec6 BodySystem::conditions(Index k, const VecX& q) const {
  const Binding& b = m_bindings[k];
  const Mat3& dref = m_bodies[b.body].frame_ref;
  const Vec6 gs = spatial_conditions(b, q);
  Vec6 g;
  g.head<3>() = dref.transpose() * gs.head<3>();
  g.tail<3>() = dref.transpose() * gs.tail<3>();
  return g;
}

template <class B, class F>
void BodySystem::for_each_node_condition(B& b, const VecX& q, F&& f) const {
  if (b.grip.empty() && !b.spin) return;
  const Index pd = m_model.bodies[b.body].first_dof;
  const Mat3 e = rotation_exp(-q.segment<3>(pd + 3).eval());
  for (auto& m : b.members) {
    if (m.body >= 0) continue;
    const Vec3 off = b.grip.empty() ? Vec3::Zero().eval() : grip_offset(b, m, q, e, q.segment<3>(pd));
    f(m, off, b.spin ? spin_offset(b, m, q, e) : 0.0);
  }
}

double BodySystem::violation(const VecX& q) const {
  double v = 0.0;
  for (const Binding& b : m_bindings) {
    const Vec6 g = spatial_conditions(b, q);
    v = std::max({v, g.head<3>().norm(), g.tail<3>().norm()});
    for_each_node_condition(b, q, [&](const Member&, const Vec3& off, double spin) {
      for (int i : b.grip) v = std::max(v, std::abs(off[i]));
      v = std::max(v, std::abs(spin));
    });
  }
  return v;
}

Index BodySystem::num_grip_conditions() const {
  Index n = 0;
  for (const Binding& b : m_bindings)
    for (const Member& m : b.members)
      if (m.body < 0) n += static_cast<Index>(b.grip.size()) + (b.spin ? 1 : 0);
  return n;
}

void BodySystem::update_multipliers(const VecX& q) {
  for (Binding& b : m_bindings) {
    const Mat3& dref = m_bodies[b.body].frame_ref;
    const Vec6 g = spatial_conditions(b, q);
    b.lambda.head<3>() += b.k * (dref.transpose() * g.head<3>());
    b.lambda.tail<3>() += b.k * (dref.transpose() * g.tail<3>());
    for_each_node_condition(b, q, [&](Member& m, const Vec3& off, double spin) {
      for (int i : b.grip) m.grip_lambda[i] += b.kg * off[i];
      m.spin_lambda += b.kg * spin;
    });
  }
}

void BodySystem::set_anchors(const VecX& q) {
  for (Binding& b : m_bindings)
    for (Member& m : b.members)
      if (m.body < 0) m.anchor = q.segment<9>(m.dof);
}

double BodySystem::anchor_drift(const VecX& q) const {
  double drift = 0.0;
  for (const Binding& b : m_bindings)
    for (const Member& m : b.members) {
      if (m.body >= 0) continue;
      const double r = std::sqrt(m.r2);
      drift = std::max(drift, (q.segment<3>(m.dof) - m.anchor.head<3>()).cwiseAbs().maxCoeff());
      drift = std::max(drift, r * (q.segment<6>(m.dof + 3) - m.anchor.tail<6>()).cwiseAbs().maxCoeff());
    }
  return drift;
}

std::vector<double> BodySystem::multipliers() const {
  std::vector<double> out;
  out.reserve(6 * m_bindings.size());
  for (const Binding& b : m_bindings) out.insert(out.end(), b.lambda.data(), b.lambda.data() + 6);
  for (const Binding& b : m_bindings)
    for (const Member& m : b.members) {
      if (m.body >= 0) continue;
      if (!b.grip.empty()) out.insert(out.end(), m.grip_lambda.data(), m.grip_lambda.data() + 3);
      if (b.spin) out.push_back(m.spin_lambda);
    }
  return out;
}

void BodySystem::set_multipliers(const std::vector<double>& values) {
  for (size_t k = 0; k < m_bindings.size(); ++k)
    for (int i = 0; i < 6; ++i) m_bindings[k].lambda[i] = values.at(6 * k + i);
  size_t at = 6 * m_bindings.size();
  for (Binding& b : m_bindings)
    for (Member& m : b.members) {
      if (m.body >= 0) continue;
      if (!b.grip.empty())
        for (int i = 0; i < 3; ++i) m.grip_lambda[i] = values.at(at++);
      if (b.spin) m.spin_lambda = values.at(at++);
    }
}

std::vector<double> BodySystem::snapshot() const {
  std::vector<double> out;
  out.reserve(12 * m_bodies.size() + 6 * m_bindings.size());
  for (const BodyData& b : m_bodies) {
    out.insert(out.end(), b.frame_ref.data(), b.frame_ref.data() + 9);
    out.insert(out.end(), b.rotation.data(), b.rotation.data() + 3);
  }
  const std::vector<double> lambda = multipliers();
  out.insert(out.end(), lambda.begin(), lambda.end());
  return out;
}

void BodySystem::restore(const std::vector<double>& values) {
  const size_t expected = 12 * m_bodies.size() + multipliers().size();
  if (values.size() != expected) {
    const size_t averaged = 12 * m_bodies.size() + 6 * m_bindings.size();
    throw std::invalid_argument(
        values.size() == averaged   ? "the state was saved without the grips or spin holds this case's bindings have"
        : expected == averaged      ? "the state was saved with grips or spin holds this case's bindings do not have"
                                    : fmt::format("body state of {} values, {} expected", values.size(), expected));
  }
  const double* v = values.data();
  for (BodyData& b : m_bodies) {
    b.frame_ref = Eigen::Map<const Mat3>(v);
    b.rotation = Eigen::Map<const Vec3>(v + 9);
    v += 12;
  }
  set_multipliers(std::vector<double>(v, values.data() + values.size()));
}

double BodySystem::binding_energy(const Binding& b, const VecX& q, VecX* grad, Eigen::MatrixXd* hess) const {
  const Turn t = turn(b, q, grad || hess, hess != nullptr);
  const double energy = averaged_energy(b, q, t, grad, hess);
  return energy + (b.grip.empty() ? 0.0 : grip_energy(b, q, t, grad, hess)) +
         (b.spin ? spin_energy(b, q, t, grad, hess) : 0.0);
}

BodySystem::Turn BodySystem::turn(const Binding& b, const VecX& q, bool first, bool second) const {
  Turn t;
  Mat3 dR[3];
  // e(theta) = R(-theta): its first derivatives change sign, its second ones keep it.
  t.e = rotation_exp(-q.segment<3>(m_model.bodies[b.body].first_dof + 3).eval(), first ? dR : nullptr,
                     second ? t.d2e : nullptr);
  if (first)
    for (int j = 0; j < 3; ++j) t.de[j] = -dR[j];
  return t;
}

double BodySystem::spin_offset(const Binding& b, const Member& m, const VecX& q, const Mat3& e) const {
  const Mat3& dref = m_bodies[b.body].frame_ref;
  const Vec3 g1 = dref.transpose() * (e * q.segment<3>(m.dof + 3));
  const Vec3 g2 = dref.transpose() * (e * q.segment<3>(m.dof + 6));
  return 0.5 * std::sqrt(m.r2) * (m.b2.dot(g1) - m.b1.dot(g2)) - m.s0;
}

double BodySystem::spin_energy(const Binding& b, const VecX& q, const Turn& t, VecX* grad,
                               Eigen::MatrixXd* hess) const {
  // s = r/2 [u2 . e(theta) g1 - u1 . e(theta) g2] - s0 with u_k = D_ref b_k and
  // e(theta) = exp(-[theta]x): ds/dg1 = r/2 e^T u2, ds/dg2 = -r/2 e^T u1,
  // ds/dtheta_j = r/2 [u2 . de_j g1 - u1 . de_j g2]; second derivatives d2s/dg1 dtheta_j =
  // r/2 de_j^T u2, d2s/dg2 dtheta_j = -r/2 de_j^T u1, d2s/dtheta_j dtheta_l =
  // r/2 [u2 . d2e_jl g1 - u1 . d2e_jl g2]. Energy lambda s + k/2 s^2 per node.
  const Mat3& dref = m_bodies[b.body].frame_ref;
  const bool derivatives = grad || hess;
  const int po = b.parent_offset;
  double energy = 0.0;
  for (const Member& m : b.members) {
    if (m.body >= 0) continue;
    const double s = spin_offset(b, m, q, t.e);
    energy += m.spin_lambda * s + 0.5 * b.kg * s * s;
    if (!derivatives) continue;
    const double half_r = 0.5 * std::sqrt(m.r2);
    const Vec3 u1 = dref * m.b1, u2 = dref * m.b2;
    const Vec3 g1 = q.segment<3>(m.dof + 3), g2 = q.segment<3>(m.dof + 6);
    const double mu = m.spin_lambda + b.kg * s;
    // Local gradient of s over (g1, g2, theta).
    Eigen::Matrix<double, 9, 1> js;
    js.head<3>() = half_r * (t.e.transpose() * u2);
    js.segment<3>(3) = -half_r * (t.e.transpose() * u1);
    for (int j = 0; j < 3; ++j) js[6 + j] = half_r * (u2.dot(t.de[j] * g1) - u1.dot(t.de[j] * g2));
    const int at[3] = {m.offset + 3, m.offset + 6, po + 3};
    if (grad)
      for (int blk = 0; blk < 3; ++blk) grad->segment<3>(at[blk]) += mu * js.segment<3>(3 * blk);
    if (!hess) continue;
    auto& h = *hess;
    for (int bi = 0; bi < 3; ++bi)
      for (int bj = 0; bj < 3; ++bj)
        h.block<3, 3>(at[bi], at[bj]).noalias() += b.kg * js.segment<3>(3 * bi) * js.segment<3>(3 * bj).transpose();
    Mat3 c1, c2;  // d2s/dg1 dtheta, d2s/dg2 dtheta (rows g, columns theta)
    for (int j = 0; j < 3; ++j) {
      c1.col(j) = half_r * (t.de[j].transpose() * u2);
      c2.col(j) = -half_r * (t.de[j].transpose() * u1);
    }
    h.block<3, 3>(m.offset + 3, po + 3) += mu * c1;
    h.block<3, 3>(po + 3, m.offset + 3) += mu * c1.transpose();
    h.block<3, 3>(m.offset + 6, po + 3) += mu * c2;
    h.block<3, 3>(po + 3, m.offset + 6) += mu * c2.transpose();
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < 3; ++l)
        h(po + 3 + j, po + 3 + l) += mu * half_r * (u2.dot(t.d2e[3 * j + l] * g1) - u1.dot(t.d2e[3 * j + l] * g2));
  }
  return energy;
}

Vec3 BodySystem::grip_offset(const Binding& b, const Member& m, const VecX& q, const Mat3& e, const Vec3& r) const {
  return m_bodies[b.body].frame_ref.transpose() * (e * (q.segment<3>(m.dof) - r)) - (b.mean + m.a);
}

double BodySystem::grip_energy(const Binding& b, const VecX& q, const Turn& t, VecX* grad,
                               Eigen::MatrixXd* hess) const {
  // g = d_i . e(theta) (p - R) - c_i with d_i the body's axis i at the increment start and
  // e(theta) = exp(-[theta]x): dg/dp = e^T d_i = -dg/dR, dg/dtheta_j = d_i . de_j (p - R);
  // second derivatives d2g/dp dtheta_j = de_j^T d_i = -d2g/dR dtheta_j and
  // d2g/dtheta_j dtheta_l = d_i . d2e_jl (p - R). Energy lambda g + k/2 g^2 per condition.
  const Mat3& dref = m_bodies[b.body].frame_ref;
  const Vec3 r = q.segment<3>(m_model.bodies[b.body].first_dof);
  const bool derivatives = grad || hess;
  const int po = b.parent_offset;
  double energy = 0.0;
  for (const Member& m : b.members) {
    if (m.body >= 0) continue;
    const Vec3 v = q.segment<3>(m.dof) - r;
    const Vec3 off = grip_offset(b, m, q, t.e, r);
    for (int i : b.grip) {
      const Vec3 d = dref.col(i);
      const double g = off[i];
      const double lambda = m.grip_lambda[i];
      energy += lambda * g + 0.5 * b.kg * g * g;
      if (!derivatives) continue;
      const double mu = lambda + b.kg * g;
      // Local gradient of g over (p, R, theta).
      Eigen::Matrix<double, 9, 1> jg;
      jg.head<3>() = t.e.transpose() * d;
      jg.segment<3>(3) = -jg.head<3>();
      for (int j = 0; j < 3; ++j) jg[6 + j] = d.dot(t.de[j] * v);
      const int at[3] = {m.offset, po, po + 3};
      if (grad)
        for (int blk = 0; blk < 3; ++blk) grad->segment<3>(at[blk]) += mu * jg.segment<3>(3 * blk);
      if (!hess) continue;
      auto& h = *hess;
      for (int bi = 0; bi < 3; ++bi)
        for (int bj = 0; bj < 3; ++bj)
          h.block<3, 3>(at[bi], at[bj]).noalias() +=
              b.kg * jg.segment<3>(3 * bi) * jg.segment<3>(3 * bj).transpose();
      Mat3 cross;  // d2g/dp dtheta (rows p, columns theta)
      for (int j = 0; j < 3; ++j) cross.col(j) = t.de[j].transpose() * d;
      h.block<3, 3>(m.offset, po + 3) += mu * cross;
      h.block<3, 3>(po + 3, m.offset) += mu * cross.transpose();
      h.block<3, 3>(po, po + 3) -= mu * cross;
      h.block<3, 3>(po + 3, po) -= mu * cross.transpose();
      for (int j = 0; j < 3; ++j)
        for (int l = 0; l < 3; ++l) h(po + 3 + j, po + 3 + l) += mu * d.dot(t.d2e[3 * j + l] * v);
    }
  }
  return energy;
}

double BodySystem::averaged_energy(const Binding& b, const VecX& q, const Turn& turned, VecX* grad,
                                   Eigen::MatrixXd* hess) const {
  const Body& body = m_model.bodies[b.body];
  const Mat3& dref = m_bodies[b.body].frame_ref;
  const Index pd = body.first_dof;
  const Vec3 r = q.segment<3>(pd);
  const bool derivatives = grad || hess;
  const Mat3& e = turned.e;
  const Mat3* de = turned.de;
  const Mat3* d2R = turned.d2e;
  const double n = static_cast<double>(b.members.size());
  const double w = 1.0 / (n * b.s);

  // Conditions (spatial frame of the increment start), and what their derivatives reuse.
  const Vec6 g = spatial_conditions(b, q);
  Vec3 pbar = Vec3::Zero(), qsum = Vec3::Zero();
  for (const Member& m : b.members) {
    pbar += q.segment<3>(m.dof) / n;
    qsum += dref * m.a;
  }
  const Vec3 u = pbar - r;
  Vec6 lam;
  lam.head<3>() = dref * b.lambda.head<3>();
  lam.tail<3>() = dref * b.lambda.tail<3>();
  double energy = lam.dot(g) + 0.5 * b.k * g.squaredNorm();
  // Proximal springs of the bound nodes (their Hessian is diagonal, added below).
  for (const Member& m : b.members) {
    if (m.body >= 0) continue;
    for (int d = 0; d < 9; ++d) {
      const double spring = d < 3 ? m_mu : m_mu * m.r2;
      energy += 0.5 * spring * (q[m.dof + d] - m.anchor[d]) * (q[m.dof + d] - m.anchor[d]);
    }
  }
  if (!derivatives) return energy;

  const Vec6 mu = lam + b.k * g;
  const Vec3 mu_p = mu.head<3>(), mu_r = mu.tail<3>();
  const int ns = b.local_size;
  const int po = b.parent_offset;
  Eigen::Matrix<double, 6, Eigen::Dynamic> jac = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, ns);
  // Members' positions.
  for (const Member& m : b.members) {
    jac.block<3, 3>(0, m.offset) = e / n;
    jac.block<3, 3>(3, m.offset) = w * skew(dref * m.a) * e;
  }
  // Body centre.
  jac.block<3, 3>(0, po) = -e;
  jac.block<3, 3>(3, po) = -w * skew(qsum) * e;
  // Body rotation, and bound bodies' rotations.
  struct ChildTerms {
    Mat3 rc, drc[3], d2rc[9], kc;
  };
  std::vector<ChildTerms> child(b.members.size());
  for (size_t i = 0; i < b.members.size(); ++i) {
    const Member& m = b.members[i];
    if (m.body < 0) continue;
    const Body& cb = m_model.bodies[m.body];
    ChildTerms& t = child[i];
    t.kc = m_bodies[m.body].frame_ref * cb.axes.transpose() * body.axes * dref.transpose();
    t.rc = rotation_exp(q.segment<3>(m.dof + 3).eval(), t.drc, hess ? t.d2rc : nullptr);
    for (int l = 0; l < 3; ++l)
      jac.block<3, 1>(3, m.offset + 3 + l) = w * m.l2 * vee_antisymmetric(e * t.drc[l] * t.kc);
  }
  for (int j = 0; j < 3; ++j) {
    Vec3 rot = Vec3::Zero();
    for (size_t i = 0; i < b.members.size(); ++i) {
      const Member& m = b.members[i];
      rot += (dref * m.a).cross(de[j] * (q.segment<3>(m.dof) - r));
      if (m.body >= 0) rot += m.l2 * vee_antisymmetric(de[j] * child[i].rc * child[i].kc);
    }
    jac.block<3, 1>(0, po + 3 + j) = de[j] * u;
    jac.block<3, 1>(3, po + 3 + j) = w * rot;
  }
  if (grad) {
    grad->head(ns) = jac.transpose() * mu;
    for (const Member& m : b.members)
      if (m.body < 0)
        for (int d = 0; d < 9; ++d) (*grad)[m.offset + d] += (d < 3 ? m_mu : m_mu * m.r2) * (q[m.dof + d] - m.anchor[d]);
  }
  if (!hess) return energy;

  auto h = hess->topLeftCorner(ns, ns);
  // k J^T J as six rank-one updates: plain loops (Eigen would thread a product this size
  // over the OpenMP threads, which is slower here and not wanted inside a sequential loop).
  h.setZero();
  for (int row = 0; row < 6; ++row)
    for (int col = 0; col < ns; ++col) {
      const double v = b.k * jac(row, col);
      if (v == 0.0) continue;
      h.col(col).noalias() += v * jac.row(row).transpose();
    }
  for (const Member& m : b.members)
    if (m.body < 0)
      for (int d = 0; d < 9; ++d) h(m.offset + d, m.offset + d) += d < 3 ? m_mu : m_mu * m.r2;
  auto add_sym = [&](int row, int col, double v) {
    h(row, col) += v;
    if (row != col) h(col, row) += v;
  };
  // Second derivatives of mu . g.
  for (int j = 0; j < 3; ++j) {
    const int tj = po + 3 + j;
    for (size_t i = 0; i < b.members.size(); ++i) {
      const Member& m = b.members[i];
      const Vec3 col = de[j].transpose() * (mu_p / n + w * mu_r.cross(dref * m.a));
      for (int a = 0; a < 3; ++a) add_sym(m.offset + a, tj, col[a]);
      if (m.body >= 0) {
        const ChildTerms& t = child[i];
        for (int l = 0; l < 3; ++l)
          add_sym(tj, m.offset + 3 + l, w * m.l2 * mu_r.dot(vee_antisymmetric(de[j] * t.drc[l] * t.kc)));
      }
    }
    const Vec3 colr = -de[j].transpose() * (mu_p + w * mu_r.cross(qsum));
    for (int a = 0; a < 3; ++a) add_sym(po + a, tj, colr[a]);
    for (int l = j; l < 3; ++l) {
      const Mat3& d2 = d2R[3 * j + l];
      double v = mu_p.dot(d2 * u);
      for (size_t i = 0; i < b.members.size(); ++i) {
        const Member& m = b.members[i];
        v += w * mu_r.cross(dref * m.a).dot(d2 * (q.segment<3>(m.dof) - r));
        if (m.body >= 0) v += w * m.l2 * mu_r.dot(vee_antisymmetric(d2 * child[i].rc * child[i].kc));
      }
      add_sym(tj, po + 3 + l, v);
    }
  }
  for (size_t i = 0; i < b.members.size(); ++i) {
    const Member& m = b.members[i];
    if (m.body < 0) continue;
    const ChildTerms& t = child[i];
    for (int j = 0; j < 3; ++j)
      for (int l = j; l < 3; ++l)
        add_sym(m.offset + 3 + j, m.offset + 3 + l, w * m.l2 * mu_r.dot(vee_antisymmetric(e * t.d2rc[3 * j + l] * t.kc)));
  }
  return energy;
}

double BodySystem::evaluate(const VecX& q, const AssemblyTarget& target, bool want_gradient, bool want_hessian) {
  double energy = 0.0;
  for (Index k = 0; k < num_bindings(); ++k) {
    const Binding& b = m_bindings[k];
    const int ns = b.local_size;
    energy += binding_energy(b, q, want_gradient ? &m_g : nullptr, want_hessian ? &m_h : nullptr);
    if (want_hessian && m_projected && project_psd(m_h.topLeftCorner(ns, ns))) ++m_projections;
    const auto gv = m_g.head(ns);
    const auto hv = m_h.topLeftCorner(ns, ns);
    scatter_local(target, m_stencils.stencil(k), want_gradient ? &gv : nullptr, want_hessian ? &hv : nullptr);
  }
  return energy;
}

Eigen::MatrixXd BodySystem::local_hessian(Index k, const VecX& q) const {
  const Binding& b = m_bindings[k];
  VecX g = VecX::Zero(b.local_size);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(b.local_size, b.local_size);
  binding_energy(b, q, &g, &h);
  return h;
}

Mat3 BodySystem::frame(Index b, const VecX& q) const {
  return rotation_exp(q.segment<3>(m_model.bodies[b].first_dof + 3).eval()) * m_bodies[b].frame_ref;
}

Vec3 BodySystem::rotation(Index b, const VecX& q) const {
  return m_bodies[b].rotation + q.segment<3>(m_model.bodies[b].first_dof + 3);
}

BodyState BodySystem::state(Index b, const VecX& q) const {
  BodyState s;
  const Body& body = m_model.bodies[b];
  s.center = q.segment<3>(body.first_dof);
  s.frame = frame(b, q);
  s.rotation = rotation(b, q);
  VecX g;
  Vec3 dtheta = Vec3::Zero();
  for (const Binding& bd : m_bindings) {
    if (bd.body != b) continue;
    g.setZero(bd.local_size);
    binding_energy(bd, q, &g, nullptr);
    s.force += g.segment<3>(bd.parent_offset);
    dtheta += g.segment<3>(bd.parent_offset + 3);
  }
  // dW/dtheta = T^T m.
  s.moment = rotation_tangent(q.segment<3>(body.first_dof + 3).eval()).transpose().lu().solve(dtheta);
  return s;
}

std::vector<Vec3> BodySystem::member_positions(Index b, const VecX& q) const {
  std::vector<Vec3> out;
  for (const Binding& bd : m_bindings)
    if (bd.body == b)
      for (const Member& m : bd.members) out.push_back(q.segment<3>(m.dof));
  return out;
}

void BodySystem::commit(VecX& q) {
  for (Index b = 0; b < num_bodies(); ++b) {
    const Index d = m_model.bodies[b].first_dof + 3;
    const Vec3 theta = q.segment<3>(d);
    m_bodies[b].frame_ref = orthonormalized(rotation_exp(theta) * m_bodies[b].frame_ref);
    m_bodies[b].rotation += theta;
    q.segment<3>(d).setZero();
  }
}

}  // namespace fibra
