#include "fibra/solver/problem.hpp"

#include "fibra/solver/krylov.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>


namespace fibra {

Problem::Problem(const Model& model, BodySystem* bodies)
    : m_model(model),
      m_bodies(bodies),
      m_beams(model),
      m_contact(model),
      m_bindings(bodies ? std::make_unique<BindingTerm>(*bodies) : nullptr),
      m_drag(model, bodies),
      m_loads(model),
      m_pattern(model.group_sizes(), {}),
      m_fixed(model.num_dofs(), 0) {
  m_terms = {&m_beams, &m_contact};
  if (m_bindings) m_terms.push_back(m_bindings.get());
  m_terms.push_back(&m_drag);
  m_terms.push_back(&m_loads);
  build_pattern();
}

void Problem::build_pattern() {
  std::vector<const StencilSet*> sets;
  for (const EnergyTerm* t : m_terms)
    if (const StencilSet* s = t->stencils()) sets.push_back(s);
  m_pattern = BlockPattern(m_model.group_sizes(), sets);
  m_diagonal.resize(m_model.num_dofs());
  for (Index d = 0; d < m_model.num_dofs(); ++d) m_diagonal[d] = m_pattern.find(d, d);
  for (EnergyTerm* t : m_terms) t->pattern_changed(m_pattern);
}

bool Problem::set_contacts(std::vector<ContactElement> contacts, const FrictionParams& friction) {
  const bool changed = m_contact.set_contacts(std::move(contacts), friction);
  if (changed) build_pattern();
  return changed;
}

void Problem::begin_lagged(const VecX& q) {
  for (EnergyTerm* t : m_terms) t->begin_lagged(q);
}

bool Problem::update_lagged(const VecX& q, const LaggedTolerance& tolerance) {
  bool settled = true;
  for (EnergyTerm* t : m_terms) settled = t->update_lagged(q, tolerance) && settled;
  return settled;
}

void Problem::begin_fixed_point(const VecX& q) {
  for (EnergyTerm* t : m_terms) t->begin_fixed_point(q);
}

FixedPointChange Problem::update_fixed_point(const VecX& q) {
  FixedPointChange all;
  for (EnergyTerm* t : m_terms) {
    const FixedPointChange c = t->update_fixed_point(q);
    all.turn = std::max(all.turn, c.turn);
    all.idle_turn = std::max(all.idle_turn, c.idle_turn);
    all.relative = std::max(all.relative, c.relative);
    all.slide = std::max(all.slide, c.slide);
  }
  return all;
}

LaggedStates Problem::save_lagged() const {
  LaggedStates s;
  for (const EnergyTerm* t : m_terms) s.terms.push_back(t->save());
  return s;
}

bool Problem::restore_lagged(const LaggedStates& states) {
  if (states.terms.size() != m_terms.size())
    throw std::logic_error("Problem::restore_lagged: a state of another problem");
  bool changed = false;
  for (size_t k = 0; k < m_terms.size(); ++k)
    if (states.terms[k]) changed = m_terms[k]->restore(*states.terms[k]) || changed;
  if (changed) build_pattern();
  return changed;
}

void Problem::commit(VecX& q) {
  for (EnergyTerm* t : m_terms) t->commit(q);
}

double Problem::step_bound(const VecX& q, const VecX& dq) const {
  double bound = 1.0;
  for (const EnergyTerm* t : m_terms) bound = std::min(bound, t->step_bound(q, dq));
  return bound;
}

Index Problem::projected_hessian(const VecX& q, std::vector<double>& hessian) {
  bool any = false;
  for (EnergyTerm* t : m_terms) any = t->set_projected(true) || any;
  if (!any) return 0;
  evaluate(q, nullptr, &hessian);
  Index projected = 0;
  for (EnergyTerm* t : m_terms) {
    t->set_projected(false);
    projected += t->take_projections();
  }
  return projected;
}

AssemblyTarget Problem::target(VecX* gradient, std::vector<double>* hessian) {
  m_group_fixed.assign(m_model.num_groups(), 0);
  for (Index d = 0; d < static_cast<Index>(m_fixed.size()); ++d)
    if (m_fixed[d]) m_group_fixed[m_pattern.group_of_dof(d)] = 1;
  return {&m_pattern, &m_fixed, &m_group_fixed, gradient, hessian};
}

double Problem::evaluate(const VecX& q, VecX* gradient, std::vector<double>* hessian) {
  const auto t0 = std::chrono::steady_clock::now();
  if (gradient) gradient->setZero(q.size());
  if (hessian) hessian->assign(m_pattern.nonzeros(), 0.0);
  const AssemblyTarget into = target(gradient, hessian);
  double energy = 0.0;
  for (EnergyTerm* t : m_terms) energy += t->assemble(q, into);
  if (hessian) {
    double scale = 0.0;
    Index count = 0;
    for (Index d = 0; d < q.size(); ++d)
      if (!m_fixed[d]) {
        scale += std::abs((*hessian)[m_diagonal[d]]);
        ++count;
      }
    scale = count ? scale / count : 1.0;
    for (Index d = 0; d < q.size(); ++d)
      if (m_fixed[d]) (*hessian)[m_diagonal[d]] = scale;
  }
  m_times.assembly += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ++m_times.evaluations;
  return energy;
}

}  // namespace fibra

namespace fibra {

namespace {

// Smallest eigenvalue of a symmetric matrix relative to its largest magnitude, and the
// position of the eigenvector's largest component.
struct LocalSpectrum {
  double min = 0, relative = 0;
  Index at = 0;
};

// Of the rows and columns `keep` of h only (the free dofs).
LocalSpectrum local_spectrum(const Eigen::MatrixXd& full, const std::vector<Index>& keep) {
  LocalSpectrum s;
  Eigen::MatrixXd h(keep.size(), keep.size());
  for (size_t i = 0; i < keep.size(); ++i)
    for (size_t j = 0; j < keep.size(); ++j) h(i, j) = full(keep[i], keep[j]);
  if (h.rows() == 0 || h.isZero(0.0)) return s;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(h);
  const VecX& v = eig.eigenvalues();
  const double scale = std::max(std::abs(v[0]), std::abs(v[v.size() - 1]));
  s.min = v[0];
  s.relative = v[0] / scale;
  eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&s.at);
  s.at = keep[s.at];
  return s;
}

}  // namespace

std::string Problem::step_energies(const VecX& q, const VecX& dq) {
  VecX g(q.size()), hdq(q.size());
  std::vector<double> h;
  std::vector<VecX> scratch;
  const AssemblyTarget with_derivatives = target(&g, &h);
  AssemblyTarget energy_only = with_derivatives;
  energy_only.gradient = nullptr;
  energy_only.values = nullptr;
  const VecX trial = q + dq;
  std::string out;
  for (EnergyTerm* t : m_terms) {
    g.setZero();
    h.assign(m_pattern.nonzeros(), 0.0);
    const double e0 = t->assemble(q, with_derivatives);
    const double e1 = t->assemble(trial, energy_only);
    symmetric_multiply(m_pattern, h, 0.0, dq, hdq, scratch);
    out += fmt::format("   {}: change {:.4e} J, model {:.4e} J (slope {:.4e}, curvature {:.4e})\n", t->name(), e1 - e0,
                       g.dot(dq) + 0.5 * dq.dot(hdq), g.dot(dq), dq.dot(hdq));
    out += t->explain_step(q, dq);
  }
  return out;
}

std::string Problem::local_spectra(const VecX& q) const {
  // Negative beyond rounding: below -1e-10 of the local matrix's largest eigenvalue.
  constexpr double kRounding = -1e-10;
  std::string out;
  std::vector<Index> keep;
  for (const EnergyTerm* term : m_terms) {
    const Index count = term->num_local();
    if (count == 0) continue;
    Index negative = 0, worst_index = 0;
    LocalSpectrum worst;
    for (Index k = 0; k < count; ++k) {
      // The free local dofs of the stencil (its groups' dofs in order, eliminated ones left out).
      keep.clear();
      Index local = 0;
      for (Index g : term->local_groups(k))
        for (int i = 0; i < m_pattern.group_size(g); ++i, ++local)
          if (!m_fixed[m_pattern.group_dof(g) + i]) keep.push_back(local);
      const LocalSpectrum ls = local_spectrum(term->local_hessian(k, q), keep);
      if (ls.relative >= kRounding) continue;
      ++negative;
      if (ls.min < worst.min) worst = ls, worst_index = k;
    }
    out += fmt::format("  {}: {} of {} local Hessians indefinite", term->name(), negative, count);
    if (negative > 0) {
      // The local dof of the eigenvector's largest component, as a group and a component.
      Index group = 0, local = worst.at;
      for (Index g : term->local_groups(worst_index)) {
        group = g;
        if (local < m_pattern.group_size(g)) break;
        local -= m_pattern.group_size(g);
      }
      out += fmt::format("; most negative {:.3e} ({:.2e} of its largest) in #{} at group {} component {}",
                         worst.min, worst.relative, worst_index, group, local);
    }
    out += "\n";
  }
  return out;
}

}  // namespace fibra
