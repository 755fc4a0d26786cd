#include "fibra/run/resolve.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "fibra/body/bodies.hpp"
#include "fibra/core/error.hpp"
#include "fibra/model/fabric.hpp"

namespace fibra {
namespace {

/// Every node a fix, a load or a prescribed displacement names exists.
void resolve_nodes(const Case& c, const Model& model) {
  for (size_t i = 0; i < c.fixes.size(); ++i) model.node_index(c.fixes[i].node, c.file, fmt::format("fix[{}]", i));
  for (size_t s = 0; s < c.steps.size(); ++s) {
    const StepSpec& st = c.steps[s];
    for (size_t i = 0; i < st.loads.size(); ++i)
      model.node_index(st.loads[i].node, c.file, fmt::format("step[{}].load[{}]", s, i));
    for (size_t i = 0; i < st.displacements.size(); ++i)
      model.node_index(st.displacements[i].node, c.file, fmt::format("step[{}].displacement[{}]", s, i));
  }
}

/// No step loads a component that is prescribed (by this entry or since an earlier step): a
/// prescribed component takes no load, its reaction is computed. (The reader checks the bodies'
/// names.)
void resolve_step_bodies(const Case& c, const Model& model) {
  std::vector<std::string> held(model.num_dofs());  // the step that prescribes the dof, or ""
  for (size_t s = 0; s < c.steps.size(); ++s)
    for (size_t i = 0; i < c.steps[s].bodies.size(); ++i) {
      const BodyStepSpec& bs = c.steps[s].bodies[i];
      const std::string key = fmt::format("step[{}].body[{}]", s, i);
      const int b = model.body_index(bs.name);
      if (b < 0) throw std::logic_error("resolve_case: a step's body not in the model (the reader checks it)");
      const Index d0 = model.bodies[b].first_dof;
      for (int k = 0; k < 3; ++k) {
        if (bs.has_displacement) held[d0 + k] = bs.displacement[k] ? c.steps[s].name : "";
        if (bs.has_rotation) held[d0 + 3 + k] = bs.rotation[k] ? c.steps[s].name : "";
      }
      static constexpr const char* kAxis[3] = {"x", "y", "z"};
      for (int k = 0; k < 3; ++k) {
        if (bs.force && (*bs.force)[k] != 0.0 && !held[d0 + k].empty())
          throw InputError(c.file, key + ".force",
                           fmt::format("a force along {} on body \"{}\", whose displacement along {} is prescribed "
                                       "(since step \"{}\"): release it with \"free\" or drop the force",
                                       kAxis[k], bs.name, kAxis[k], held[d0 + k]));
        if (bs.moment && (*bs.moment)[k] != 0.0 && !held[d0 + 3 + k].empty())
          throw InputError(c.file, key + ".moment",
                           fmt::format("a moment about {} on body \"{}\", whose rotation about {} is prescribed "
                                       "(since step \"{}\"): release it with \"free\" or drop the moment",
                                       kAxis[k], bs.name, kAxis[k], held[d0 + 3 + k]));
      }
    }
}

/// A weave step pushes crossing tows apart through their contacts: it needs [contact] (the
/// reader checks its tows and pattern, and the test steps' edge bodies). A shear with its
/// height free keeps the force across its top edge (the weft tension): it finds one, from the
/// state it starts from and the steps before it.
void resolve_fabric_steps(const Case& c, const Model& model, const std::optional<SolverState>& start) {
  const int top = model.body_index(kEdgeBodies[3]);
  // The force along y on the top edge in force at the start of each step (the loads carry on
  // from step to step; an entry replaces them).
  double top_force = top >= 0 && start ? start->force_end[model.bodies[top].first_dof + 1] : 0.0;
  for (size_t s = 0; s < c.steps.size(); ++s) {
    const StepSpec& st = c.steps[s];
    if (st.kind == StepSpec::Kind::Weave && !c.contact.enabled)
      throw InputError(c.file, fmt::format("step[{}].kind", s),
                       "a weave step pushes crossing tows apart through their contacts: it needs [contact]");
    if (st.kind == StepSpec::Kind::Shear && st.free_height && top_force == 0.0)
      throw InputError(c.file, fmt::format("step[{}].height", s),
                       "height = \"free\" leaves the top edge (edge.y+) under the force it had across the shear, "
                       "and it has none: give the fabric a weft tension ([fabric] tension) or hold the height "
                       "(\"held\")");
    for (const BodyStepSpec& bs : st.bodies)
      if (top >= 0 && bs.name == kEdgeBodies[3] && bs.force) top_force = (*bs.force)[1];
  }
}

/// check_start_state with the case's body system (null without bodies).
void check_start(const BodySystem* bodies, const Model& model, const SolverState& s, const std::string& file) {
  check_state_fits(s, model, bodies ? bodies->num_bindings() : 0, file);
  if (bodies) {
    BodySystem copy = *bodies;
    try {
      copy.restore(s.bodies);
    } catch (const std::invalid_argument& e) {
      throw InputError(file, "(file)", fmt::format("the bodies' state does not fit this case: {}", e.what()));
    }
  }
}

}  // namespace

ResolvedCase::ResolvedCase(const Case& c) : model(build_model(c)) {
  resolve_nodes(c, model);
  // The bindings: bodies, members and grips, resolved against the model's geometry (a bound
  // node's section vectors, members that define a mean rotation) as the body system is built.
  if (!model.bodies.empty()) bodies = std::make_unique<BodySystem>(c, model);
  resolve_step_bodies(c, model);
  if (!c.start.empty()) {
    start = read_state_file(c.start_state);
    check_start(bodies.get(), model, *start, c.start_state);
  }
  resolve_fabric_steps(c, model, start);
}

ResolvedCase resolve_case(const Case& c) { return ResolvedCase(c); }

void check_start_state(const Case& c, const Model& model, const SolverState& s, const std::string& file) {
  std::optional<BodySystem> bodies;
  if (!model.bodies.empty()) bodies.emplace(c, model);
  check_start(bodies ? &*bodies : nullptr, model, s, file);
}

}  // namespace fibra
