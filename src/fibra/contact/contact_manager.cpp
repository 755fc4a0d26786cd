#include "fibra/contact/contact_manager.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include <fmt/core.h>

#include "fibra/beam/beam_element.hpp"
#include "fibra/core/debug.hpp"
#include "fibra/contact/broad_phase.hpp"
#include "fibra/contact/detection.hpp"

namespace fibra {
namespace {

// Centre of the section of particle p (x0 at its eta) and the unit tangent of the centroid
// line there.
void section_centre(const Model& model, const Particle& p, const VecX& q, Vec3& centre, Vec3& tangent) {
  const double* q_e = q.data() + model.elements[p.element].first_dof;
  double n[3], dn[3];
  beam_shape(p.eta, n, dn);
  centre.setZero();
  tangent.setZero();
  for (int a = 0; a < 3; ++a) {
    const Eigen::Map<const Vec3> x(q_e + kNodeDofs * a);
    centre += n[a] * x;
    tangent += dn[a] * x;
  }
  const double len = tangent.norm();
  if (len > 0.0) tangent /= len;
}

// The normal of a contact element at q: the unit vector between its two section centres, in
// the plane normal to the bisector of the two centroid lines' tangents (the plane that cut the
// two lines at detection, detection.cpp). Two fibers that slide along each other move their
// particles' section centres apart along the fibers; the vector between them then tilts by
// slide / (r_a + r_b) although the fibers' surfaces still face each other the same way (a
// slide of 7.7 um turned the normals of the 480-fiber sample under shear by 0.19 rad). In the
// cutting plane that tilt is gone for fibers along each other, and halved at a right-angle
// crossing. Of the two bisectors (the tangents' orientations), the one whose plane keeps the
// normal closer to the element's current one: at a right-angle crossing the sign of ta . tb
// flips with round-off, and a choice by that sign flipped such normals by up to 0.15 rad at
// every update. Returns false (normal left) when the centres coincide in the cutting plane.
bool cut_plane_normal(const Model& model, const ContactElement& c, const VecX& q, Vec3& normal) {
  Vec3 ca, ta, cb, tb;
  section_centre(model, c.a, q, ca, ta);
  section_centre(model, c.b, q, cb, tb);
  const Vec3 d = cb - ca;
  bool found = false;
  double best = -2.0;
  for (const double sign : {1.0, -1.0}) {
    const Vec3 bisector = ta + sign * tb;
    const double bn = bisector.norm();
    Vec3 in_plane = d;
    if (bn > 1e-8) in_plane -= d.dot(bisector / bn) * (bisector / bn);
    const double len = in_plane.norm();
    if (!(len > 0.0)) continue;
    const Vec3 candidate = in_plane / len;
    if (candidate.dot(c.normal) > best) {
      best = candidate.dot(c.normal);
      normal = candidate;
      found = true;
    }
  }
  return found;
}

}  // namespace

ContactManager::ContactManager(const Model& model, const ContactSpec& spec) : m_model(model), m_spec(spec) {
  DetectionParams params;
  params.margin = spec.margin;
  params.spacing = spec.spacing;
  params.self_exclusion = spec.self_exclusion;
  m_detector = std::make_unique<ContactDetector>(model, params);
  double r_min = 1e300, e_t = 1e300;
  for (const Fiber& f : model.fibers) {
    const Section& s = model.sections[f.section];
    r_min = std::min(r_min, std::min(s.a, s.b));
    const MaterialSpec& m = model.materials[f.material];
    e_t = std::min(e_t, m.model == MaterialSpec::Model::Transverse ? m.young_transverse : m.young);
  }
  if (model.fibers.empty()) r_min = e_t = 1.0;
  m_initial_stiffness = spec.stiffness > 0 ? spec.stiffness : 0.1 * e_t * r_min;
  m_friction.mu = spec.friction;
  m_friction.elastic_slip = spec.elastic_slip > 0 ? spec.elastic_slip : 1e-3 * r_min;
}

ContactManager::~ContactManager() = default;

double ContactManager::pair_radius(const ContactElement& c) const {
  const Section& sa = m_model.sections[m_model.fibers[m_model.elements[c.a.element].fiber].section];
  const Section& sb = m_model.sections[m_model.fibers[m_model.elements[c.b.element].fiber].section];
  return std::min({sa.a, sa.b, sb.a, sb.b});
}

double ContactManager::arc_length(const Particle& p) const {
  const BeamElement& e = m_model.elements[p.element];
  const Fiber& f = m_model.fibers[e.fiber];
  const double h = f.length / static_cast<double>(f.num_elements);
  return h * (static_cast<double>(p.element - f.first_element) + 0.5 * (p.eta + 1.0));
}

std::vector<std::vector<std::uint64_t>> ContactManager::detection_memory() const { return m_detector->memory(); }

void ContactManager::set_detection_memory(const std::vector<std::vector<std::uint64_t>>& memory) {
  m_detector->set_memory(memory);
}

std::vector<ContactElement> ContactManager::detect(const VecX& q, const VecX& q_start,
                                                   const std::vector<ContactElement>& previous) {
  Detection det = m_detector->detect(q);
  m_zones = static_cast<int>(det.zones.size());
  // Previous elements by fiber pair, sorted by arc length on fiber a.
  std::map<std::pair<int, int>, std::vector<std::pair<double, const ContactElement*>>> old;
  for (const ContactElement& c : previous) {
    const int fa = m_model.elements[c.a.element].fiber, fb = m_model.elements[c.b.element].fiber;
    old[{fa, fb}].push_back({arc_length(c.a), &c});
    if (fa != fb) old[{fb, fa}].push_back({arc_length(c.b), &c});
  }
  for (auto& [key, list] : old) std::sort(list.begin(), list.end(), [](auto& x, auto& y) { return x.first < y.first; });

  // Zone stiffness: the largest matched previous stiffness in the zone, else the initial one.
  std::vector<double> zone_k(det.zones.size(), 0.0);
  std::vector<const ContactElement*> match(det.elements.size(), nullptr);
  std::vector<bool> flipped(det.elements.size(), false);
  for (size_t k = 0; k < det.elements.size(); ++k) {
    ContactElement& c = det.elements[k];
    const int fa = m_model.elements[c.a.element].fiber, fb = m_model.elements[c.b.element].fiber;
    auto it = old.find({fa, fb});
    if (it == old.end()) continue;
    const double s = arc_length(c.a);
    const double tol = 0.75 * (m_spec.spacing > 0 ? m_spec.spacing : pair_radius(c));
    const auto& list = it->second;
    auto pos = std::lower_bound(list.begin(), list.end(), s, [](auto& x, double v) { return x.first < v; });
    double best = tol;
    for (auto cand = (pos == list.begin() ? pos : pos - 1); cand != list.end() && cand <= pos; ++cand) {
      if (std::abs(cand->first - s) <= best) {
        best = std::abs(cand->first - s);
        match[k] = cand->second;
      }
    }
    if (match[k]) {
      flipped[k] = m_model.elements[match[k]->a.element].fiber != fa;
      zone_k[c.zone] = std::max(zone_k[c.zone], match[k]->law.stiffness);
    }
  }
  for (size_t k = 0; k < det.elements.size(); ++k) {
    ContactElement& c = det.elements[k];
    const double allowed = m_spec.max_penetration * pair_radius(c);
    c.law.stiffness = zone_k[c.zone] > 0 ? zone_k[c.zone] : m_initial_stiffness;
    c.law.regularization = m_spec.regularization * allowed;
    c.separation_previous = particle_position(c.b, q_start.data() + m_model.elements[c.b.element].first_dof) -
                            particle_position(c.a, q_start.data() + m_model.elements[c.a.element].first_dof);
    c.fresh = match[k] == nullptr;
    if (match[k]) {
      const Vec3 f = flipped[k] ? Vec3(-match[k]->friction_previous) : match[k]->friction_previous;
      c.friction_previous = f - f.dot(c.normal) * c.normal;
    } else {
      c.friction_previous.setZero();
    }
  }
  return std::move(det.elements);
}

double ContactManager::update_normals(std::vector<ContactElement>& contacts, const VecX& q, double* idle_turn,
                                      double* slide) const {
  // New normals between section centres. An element with no force at q under its old normal
  // nor under its new one (gap >= 0 with both: the penalty law and the friction cone, frozen at
  // the normal force, are zero) takes its new normal at once; the others only if one of them
  // turned by the tolerance or more: below it the converged state stays consistent with the
  // normals it was solved with (forces and reactions balance exactly). Measuring the turn on
  // every element let a pair of sliding fibers with no force between them (their section
  // centres drifting apart along the fibers) keep a relax from settling.
  double turn = 0.0, idle = 0.0, worst_slide = 0.0, largest_slide = 0.0;
  size_t worst = contacts.size();
  std::vector<Vec3> fresh(contacts.size());
  std::vector<char> loaded(contacts.size(), 0);
  for (size_t k = 0; k < contacts.size(); ++k) {
    ContactElement& c = contacts[k];
    if (c.prescribed) {
      fresh[k] = c.normal;
      continue;
    }
    if (!cut_plane_normal(m_model, c, q, fresh[k])) fresh[k] = c.normal;
    const double angle = std::acos(std::clamp(fresh[k].dot(c.normal), -1.0, 1.0));
    const Vec3 gap_vector = particle_position(c.b, q.data() + m_model.elements[c.b.element].first_dof) -
                            particle_position(c.a, q.data() + m_model.elements[c.a.element].first_dof);
    if (gap_vector.dot(c.normal) + c.offset < 0.0 || gap_vector.dot(fresh[k]) + c.offset < 0.0) {
      loaded[k] = 1;
      const Section& sa = m_model.sections[m_model.elements[c.a.element].section];
      const Section& sb = m_model.sections[m_model.elements[c.b.element].section];
      const double across = (gap_vector - gap_vector.dot(c.normal) * c.normal).norm();
      largest_slide = std::max(largest_slide, across / (std::min(sa.a, sa.b) + std::min(sb.a, sb.b)));
      if (angle > turn) {
        worst = k;
        worst_slide = across;
      }
      turn = std::max(turn, angle);
    } else {
      idle = std::max(idle, angle);
      c.normal = fresh[k];
    }
  }
  if (turn >= m_spec.normal_tolerance)
    for (size_t k = 0; k < contacts.size(); ++k)
      if (loaded[k]) contacts[k].normal = fresh[k];
  if (idle_turn) *idle_turn = idle;
  if (slide) *slide = largest_slide;
  if (debug_newton() && worst < contacts.size())
    fmt::print(stderr, " largest turn with force: element {} (zone {}), its particles slid {:.3e} m apart along the old normal's plane\n",
               worst, contacts[worst].zone, worst_slide);
  return turn;
}

double ContactManager::prescribe_normals(std::vector<ContactElement>& contacts, const VecX& q, const Vec3& direction,
                                        const std::function<int(int, int)>& rule, double offset) const {
  double deepest = 0.0;
  for (ContactElement& c : contacts) {
    const BeamElement& ea = m_model.elements[c.a.element];
    const BeamElement& eb = m_model.elements[c.b.element];
    const int side = rule(ea.fiber, eb.fiber);
    if (side == 0) continue;
    c.normal = side * direction;
    c.prescribed = true;
    c.offset = offset;
    Vec3 x, g1, g2;
    section_at(q.data() + ea.first_dof, c.a.eta, x, g1, g2);
    border_point(g1, g2, c.normal, m_model.sections[ea.section].a, m_model.sections[ea.section].b, c.a.xi1, c.a.xi2);
    section_at(q.data() + eb.first_dof, c.b.eta, x, g1, g2);
    border_point(g1, g2, -c.normal, m_model.sections[eb.section].a, m_model.sections[eb.section].b, c.b.xi1, c.b.xi2);
    const Vec3 d = particle_position(c.b, q.data() + eb.first_dof) - particle_position(c.a, q.data() + ea.first_dof);
    deepest = std::max(deepest, -d.dot(c.normal));
  }
  return deepest;
}

std::map<int, double> ContactManager::zone_penetration(const std::vector<ContactElement>& contacts,
                                                      const std::vector<ContactResponse>& responses) const {
  std::map<int, double> worst;
  for (size_t k = 0; k < contacts.size(); ++k) {
    const double ratio = -responses[k].gap / (m_spec.max_penetration * pair_radius(contacts[k]));
    auto [it, inserted] = worst.try_emplace(contacts[k].zone, ratio);
    if (!inserted) it->second = std::max(it->second, ratio);
  }
  return worst;
}

int ContactManager::adapt_penalty(std::vector<ContactElement>& contacts,
                                  const std::vector<ContactResponse>& responses) const {
  // Zone -> largest penetration / allowed, then its penalty factor. Penetration falls roughly
  // as 1/k at a given force: aim at 70 % of the allowed one.
  std::map<int, double> factor = zone_penetration(contacts, responses);
  int raised = 0;
  for (auto& [zone, f] : factor) {
    if (f <= 1.0) {
      f = 1.0;
      continue;
    }
    ++raised;
    f = std::min(100.0, f / 0.7);
  }
  for (ContactElement& c : contacts) c.law.stiffness *= factor.at(c.zone);
  return raised;
}

int ContactManager::soften_penalty(std::vector<ContactElement>& contacts, const std::vector<ContactResponse>& responses,
                                   double floor) const {
  std::map<int, double> factor = zone_penetration(contacts, responses);  // then the penalty factor
  for (auto& [zone, f] : factor) f = f < 0.35 ? std::max(0.25, f / 0.7) : 1.0;
  std::set<int> softened;
  for (ContactElement& c : contacts) {
    const double f = factor.at(c.zone);
    if (f >= 1.0 || c.law.stiffness <= floor) continue;
    c.law.stiffness = std::max(floor, c.law.stiffness * f);
    softened.insert(c.zone);
  }
  return static_cast<int>(softened.size());
}

bool ContactManager::passed_through(const std::vector<ContactElement>& contacts,
                                    const std::vector<ContactResponse>& responses,
                                    std::pair<Index, Index>* where) const {
  for (size_t k = 0; k < contacts.size(); ++k)
    if (contacts[k].fresh && -responses[k].gap > 0.5 * pair_radius(contacts[k]) &&
        -responses[k].gap > 4.0 * m_spec.max_penetration * pair_radius(contacts[k])) {
      if (debug_newton())
        fmt::print(stderr, " passed through: elements {} and {}, penetration {:.3e} (radius {:.3e})\n",
                   contacts[k].a.element, contacts[k].b.element, -responses[k].gap, pair_radius(contacts[k]));
      if (where) *where = {contacts[k].a.element, contacts[k].b.element};
      return true;
    }
  return false;
}

namespace {

// Parameters (s, t) in [0, 1]^2 of the closest points of segments p0-p1 and q0-q1.
void closest_points(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, double& s, double& t) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r), c = d1.dot(r), b = d1.dot(d2);
  const double denom = a * e - b * b;
  s = denom > 1e-14 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
}

}  // namespace

bool ContactManager::crossed(const VecX& q_start, const VecX& q, std::pair<Index, Index>* where) const {
  double motion = 0.0;
  for (Index k = 0; k < m_model.num_nodes(); ++k)
    motion = std::max(motion, (q.segment<3>(9 * k) - q_start.segment<3>(9 * k)).norm());
  if (motion == 0.0) return false;
  const VecX mid = 0.5 * (q + q_start);
  BroadPhaseParams params;
  params.margin = 0.5 * motion + (m_spec.margin > 0 ? m_spec.margin : 0.0);
  params.self_exclusion = m_spec.self_exclusion;
  BroadPhase broad(m_model, params);
  auto chord = [&](const VecX& x, Index e, Vec3& a, Vec3& b) {
    const Index d = m_model.elements[e].first_dof;
    a = x.segment<3>(d);
    b = x.segment<3>(d + 18);
  };
  auto radius = [&](Index e) {
    const Section& sec = m_model.sections[m_model.fibers[m_model.elements[e].fiber].section];
    return std::max(sec.a, sec.b);
  };
  for (const ElementPair& pr : broad.find_pairs(mid)) {
    Vec3 a0, a1, b0, b1, c0, c1, e0, e1;
    chord(q_start, pr.first, a0, a1);
    chord(q_start, pr.second, b0, b1);
    chord(q, pr.first, c0, c1);
    chord(q, pr.second, e0, e1);
    const Vec3 n_start = (a1 - a0).cross(b1 - b0), n_end = (c1 - c0).cross(e1 - e0);
    if (n_start.norm() < 0.05 * (a1 - a0).norm() * (b1 - b0).norm() || n_end.dot(n_start) <= 0.0) continue;
    double s0, t0, s1, t1;
    closest_points(a0, a1, b0, b1, s0, t0);
    closest_points(c0, c1, e0, e1, s1, t1);
    const double side0 = (b0 + t0 * (b1 - b0) - a0 - s0 * (a1 - a0)).dot(n_start);
    const double side1 = (e0 + t1 * (e1 - e0) - c0 - s1 * (c1 - c0)).dot(n_start);
    if (side0 * side1 >= 0.0) continue;
    // The common-normal side changed: at the moment it was zero (linear in time), were the
    // chords within the sum of the radii (through each other) or apart (around an end)?
    const double tau = side0 / (side0 - side1);
    const Vec3 pa0 = a0 + tau * (c0 - a0), pa1 = a1 + tau * (c1 - a1);
    const Vec3 pb0 = b0 + tau * (e0 - b0), pb1 = b1 + tau * (e1 - b1);
    double s, t;
    closest_points(pa0, pa1, pb0, pb1, s, t);
    const double gap = (pb0 + t * (pb1 - pb0) - pa0 - s * (pa1 - pa0)).norm();
    // Through each other: closer than half the sum of the radii when the side changed. Fibers
    // side by side (touching, with the allowed penetration) at a small angle change side with
    // the slightest motion across their plane, their lines meeting beyond the chords' ends:
    // that is not a crossing.
    if (gap < 0.5 * (radius(pr.first) + radius(pr.second))) {
      if (debug_newton())
        fmt::print(stderr, " crossed: elements {} and {}, gap {:.3e} at tau {:.3f}\n", pr.first, pr.second, gap, tau);
      if (where) *where = {pr.first, pr.second};
      return true;
    }
  }
  return false;
}

double ContactManager::penetration_ratio(const std::vector<ContactElement>& contacts, const VecX& q) const {
  double worst = 0.0;
  for (const ContactElement& c : contacts) {
    const Vec3 d = particle_position(c.b, q.data() + m_model.elements[c.b.element].first_dof) -
                   particle_position(c.a, q.data() + m_model.elements[c.a.element].first_dof);
    worst = std::max(worst, -(d.dot(c.normal) + c.offset) / (m_spec.max_penetration * pair_radius(c)));
  }
  return worst;
}

void ContactManager::add_stats(const std::vector<ContactElement>& contacts,
                               const std::vector<ContactResponse>& responses, ContactStats& out) const {
  out.zones = m_zones;
  out.elements = static_cast<int>(contacts.size());
  out.max_penetration_ratio = 0.0;
  out.total_normal_force = 0.0;
  for (size_t k = 0; k < contacts.size(); ++k) {
    out.max_penetration_ratio = std::max(out.max_penetration_ratio, -responses[k].gap / pair_radius(contacts[k]));
    out.total_normal_force += responses[k].normal_force;
  }
}

}  // namespace fibra
