// The readers of [solver], [contact] and [output].
#include "fibra/io/case/reader.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/case/suggest.hpp"

namespace fibra::case_file {

SolverSpec Reader::read_solver(const Value& t, const std::string& path) const {
  expect_table(t, path);
  // Former settings of the method, now its own rules (docs/theory/solver.md): named as such,
  // not as unknown keys.
  static const Keys kRules = {"line_search",      "test_predictor",    "ordering",         "binding_stiffness",
                              "max_step",         "weave_drag",        "relax_drag",       "drag_axial",
                              "test_inexact",     "relax_inexact",     "test_penetration_slack",
                              "pseudo_tolerance", "krylov_iterations", "krylov_tolerance"};
  for (std::string_view name : kRules)
    if (const Value* v = find(t, name))
      fail(join(path, name),
           fmt::format("`{}` is not a setting: the solver sets it itself (docs/theory/solver.md); remove it", name), v);
  for (const char* name : {"relax_tolerance", "test_tolerance"})
    if (const Value* v = find(t, name))
      fail(join(path, name),
           fmt::format("`{}` is now the `tolerance` of each relax, biaxial or shear [[step]] (default 1e-4); move it "
                       "there",
                       name),
           v);
  check_keys(t, path, schema_keys("solver"));
  SolverSpec s;
  read_bounded(t, path, "solver", "residual_tolerance", s.residual_tolerance);
  read_bounded(t, path, "solver", "displacement_tolerance", s.displacement_tolerance);
  read_bounded(t, path, "solver", "max_iterations", s.max_iterations);
  read_bounded(t, path, "solver", "max_cuts", s.max_cuts);
  if (const Value* v = find(t, "linear_solver"))
    s.linear_solver = one_of(*v, join(path, "linear_solver"), schema_choices("solver", "linear_solver"));
  if (const Value* v = find(t, "krylov_precision"))
    s.krylov_precision = one_of(*v, join(path, "krylov_precision"), schema_choices("solver", "krylov_precision"));
  read_bounded(t, path, "solver", "binding_tolerance", s.binding_tolerance);
  read_bounded(t, path, "solver", "max_binding_updates", s.max_binding_updates);
  return s;
}

ContactSpec Reader::read_contact(const Value& t, const std::string& path) const {
  expect_table(t, path);
  check_keys(t, path, schema_keys("contact"));
  ContactSpec c;
  c.enabled = true;
  read_bounded(t, path, "contact", "friction", c.friction);
  if (const Value* v = find(t, "max_penetration")) {
    const std::string key = join(path, "max_penetration");
    c.max_penetration = to_number(*v, key);
    if (!(c.max_penetration > 0 && c.max_penetration < 1))
      fail(key, fmt::format("expected a fraction of the radius in (0, 1), got {}", c.max_penetration), v);
  }
  read_bounded(t, path, "contact", "elastic_slip", c.elastic_slip);
  read_bounded(t, path, "contact", "stiffness", c.stiffness);
  if (const Value* v = find(t, "regularization")) {
    const std::string key = join(path, "regularization");
    c.regularization = to_number(*v, key);
    if (!(c.regularization > 0 && c.regularization <= 1))
      fail(key, fmt::format("expected a fraction of the allowed penetration in (0, 1], got {}", c.regularization), v);
  }
  read_bounded(t, path, "contact", "margin", c.margin);
  read_bounded(t, path, "contact", "spacing", c.spacing);
  read_bounded(t, path, "contact", "self_exclusion", c.self_exclusion);
  read_bounded(t, path, "contact", "max_detections", c.max_detections);
  read_bounded(t, path, "contact", "max_normal_updates", c.max_normal_updates);
  read_bounded(t, path, "contact", "normal_tolerance", c.normal_tolerance);
  return c;
}

void Reader::read_checkpoint(const Value& v, const std::string& key, OutputSpec& o) const {
  const std::string expected =
      "expected \"auto\", \"never\", a number of increments (an integer >= 1) or a time such as \"30 s\", "
      "\"10 min\" or \"1 h\"";
  if (v.type == Value::Type::Integer) {
    o.checkpoint = OutputSpec::Checkpoint::Increments;
    o.checkpoint_increments = to_int(v, key, 1);
    return;
  }
  if (v.type != Value::Type::String) fail(key, fmt::format("{}, got {}", expected, describe(v)), &v);
  if (v.text == "auto" || v.text == "never") {
    o.checkpoint = v.text == "auto" ? OutputSpec::Checkpoint::Auto : OutputSpec::Checkpoint::Never;
    return;
  }
  // A time: a positive number and a unit.
  std::istringstream in(v.text);
  double t = 0.0;
  std::string unit, rest;
  in >> t >> unit >> rest;
  const double scale = unit == "s" ? 1.0 : unit == "min" ? 60.0 : unit == "h" ? 3600.0 : 0.0;
  if (!(t > 0.0 && std::isfinite(t)) || scale == 0.0 || !rest.empty())
    fail(key, fmt::format("{}, got \"{}\"", expected, v.text), &v);
  o.checkpoint = OutputSpec::Checkpoint::Seconds;
  o.checkpoint_seconds = t * scale;
}

OutputSpec Reader::read_output(const Value& t, const std::string& path) const {
  expect_table(t, path);
  check_keys(t, path, schema_keys("output"));
  OutputSpec o;
  read_bounded(t, path, "output", "every", o.every);
  read_bounded(t, path, "output", "tube_sides", o.tube_sides);
  if (const Value* v = find(t, "plots")) o.plots = to_bool(*v, join(path, "plots"));
  if (const Value* v = find(t, "test_levels")) o.test_levels = to_bool(*v, join(path, "test_levels"));
  if (const Value* v = find(t, "checkpoint")) read_checkpoint(*v, join(path, "checkpoint"), o);
  return o;
}
}  // namespace fibra::case_file
