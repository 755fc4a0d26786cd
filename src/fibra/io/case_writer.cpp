#include "fibra/io/case_writer.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "fibra/io/case/schema.hpp"

namespace fibra {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;  // as in the reader: angles in degrees

/// The shortest decimal form that reads back to the same double (fmt's default), valid TOML.
std::string number(double x) { return fmt::format("{}", x); }

/// The angle `radians` in degrees, chosen so that the reader's `degrees * kDegree` gives
/// `radians` back exactly when a neighbouring double does.
double degrees(double radians) {
  const double d = radians / kDegree;
  if (d * kDegree == radians) return d;
  double up = d, down = d;
  for (int k = 0; k < 4; ++k) {
    up = std::nextafter(up, HUGE_VAL);
    down = std::nextafter(down, -HUGE_VAL);
    if (up * kDegree == radians) return up;
    if (down * kDegree == radians) return down;
  }
  return d;
}

/// A TOML basic string, quoted and escaped.
std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (const char ch : s) {
    switch (ch) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\f':
        out += "\\f";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) {
          out += fmt::format("\\u{:04X}", static_cast<unsigned char>(ch));
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

// Every key is named as the schema declares it (io/case/schema.hpp): a key the schema does not
// have is a std::logic_error.

/// `name = value`, `name` a key of the table `section` of the schema.
std::string entry(std::string_view section, std::string_view name, const std::string& value) {
  return fmt::format("{} = {}", case_file::schema_key(section, name).name, value);
}

/// The line `name = value` of the table `section`.
std::string line(std::string_view section, std::string_view name, const std::string& value) {
  return entry(section, name, value) + "\n";
}

/// The table `header` (`[solver]`) with every key of the table `section` of the schema, in its
/// order, at its value in `values` (which has a value for each key and no other).
std::string whole_table(std::string_view header, std::string_view section,
                        const std::map<std::string_view, std::string>& values) {
  std::string out = fmt::format("\n{}\n", header);
  const case_file::SectionSpec& spec = case_file::schema_section(section);
  for (const case_file::KeySpec& k : spec.keys) {
    const auto it = values.find(k.name);
    if (it == values.end())
      throw std::logic_error(fmt::format("the case writer has no value for the key {}.{}", section, k.name));
    out += fmt::format("{} = {}\n", k.name, it->second);
  }
  if (values.size() != spec.keys.size())
    throw std::logic_error(fmt::format("the case writer writes keys of {} the schema does not have", section));
  return out;
}

std::string vec3(const Vec3& v) { return fmt::format("[{}, {}, {}]", number(v[0]), number(v[1]), number(v[2])); }

/// An array of 3 components, each a number or "free".
std::string components(const std::array<std::optional<double>, 3>& c) {
  std::string out = "[";
  for (std::size_t i = 0; i < 3; ++i) {
    if (i > 0) out += ", ";
    out += c[i] ? number(*c[i]) : "\"free\"";
  }
  return out + "]";
}

/// An array whose items are written one per line when there are more than `inline_max`.
std::string array(const std::vector<std::string>& items, std::size_t inline_max = 4) {
  if (items.size() <= inline_max) {
    std::string out = "[";
    for (std::size_t i = 0; i < items.size(); ++i) out += (i > 0 ? ", " : "") + items[i];
    return out + "]";
  }
  std::string out = "[\n";
  for (const std::string& s : items) out += "  " + s + ",\n";
  return out + "]";
}

/// The keys of a node reference: `fiber = "f", node = "last"` (separated by `separator`).
std::string node_keys(const NodeRef& n, std::string_view separator) {
  std::string where;
  switch (n.kind) {
    case NodeRef::Kind::First:
      where = entry("node", "node", toml_string("first"));
      break;
    case NodeRef::Kind::Last:
      where = entry("node", "node", toml_string("last"));
      break;
    case NodeRef::Kind::NodeIndex:
      where = entry("node", "node", std::to_string(n.index));
      break;
    case NodeRef::Kind::Fraction:
      where = entry("node", "at", number(n.fraction));
      break;
  }
  return fmt::format("{}{}{}", entry("node", "fiber", toml_string(n.fiber)), separator, where);
}

/// The `dofs` of a fix, or "" when it holds nothing.
std::string dofs_value(const FixSpec& f) {
  const auto& d = f.dofs;
  const bool position = f.position();
  const bool sections = f.sections();
  bool none = true;
  for (bool b : d) none = none && !b;
  if (none) return "";
  if (position && sections) return "\"all\"";
  if (position && !d[3] && !d[4] && !d[5] && !d[6] && !d[7] && !d[8]) return "\"position\"";
  if (sections && !d[0] && !d[1] && !d[2]) return "\"sections\"";
  static constexpr const char* kNames[9] = {"x", "y", "z", "g1x", "g1y", "g1z", "g2x", "g2y", "g2z"};
  std::vector<std::string> items;
  for (int k = 0; k < 3; ++k)
    if (d[k]) items.push_back(toml_string(kNames[k]));
  for (int vector_index = 0; vector_index < 2; ++vector_index) {
    const int first = 3 + 3 * vector_index;
    if (d[first] && d[first + 1] && d[first + 2]) {
      items.push_back(toml_string(vector_index == 0 ? "g1" : "g2"));
      continue;
    }
    for (int k = first; k < first + 3; ++k)
      if (d[k]) items.push_back(toml_string(kNames[k]));
  }
  return array(items, 11);
}

void write_material(std::string& out, const MaterialSpec& m) {
  out += "\n[[material]]\n";
  out += line("material", "name", toml_string(m.name));
  const bool transverse = m.model == MaterialSpec::Model::Transverse;
  out += line("material", "model", toml_string(transverse ? "transverse" : "isotropic"));
  out += line("material", "young", number(m.young));
  out += line("material", "poisson", number(m.poisson));
  if (transverse) {
    out += line("material", "young_transverse", number(m.young_transverse));
    out += line("material", "shear_axial", number(m.shear_axial));
    out += line("material", "poisson_transverse", number(m.poisson_transverse));
  }
}

void write_fiber(std::string& out, const FiberSpec& f) {
  out += "\n[[fiber]]\n";
  out += line("fiber", "name", toml_string(f.name));
  out += line("fiber", "material", toml_string(f.material));
  if (f.semi_axis_1 == f.semi_axis_2 && f.radius == f.semi_axis_1) {
    out += line("fiber", "radius", number(f.radius));
  } else {
    out += line("fiber", "semi_axes", fmt::format("[{}, {}]", number(f.semi_axis_1), number(f.semi_axis_2)));
  }
  if (f.section_direction) out += line("fiber", "section_direction", vec3(*f.section_direction));
  const PathSpec& p = f.path;
  switch (p.kind) {
    case PathSpec::Kind::Polyline: {
      std::vector<std::string> points;
      for (const Vec3& x : p.points) points.push_back(vec3(x));
      out += line("fiber", "points", array(points, 3));
      break;
    }
    case PathSpec::Kind::Arc:
      out += line("fiber", "arc",
                  fmt::format("{{ {}, {}, {}, {}, {} }}", entry("fiber.arc", "center", vec3(p.center)),
                              entry("fiber.arc", "axis", vec3(p.axis)), entry("fiber.arc", "radius", number(p.radius)),
                              entry("fiber.arc", "start_angle", number(degrees(p.start_angle))),
                              entry("fiber.arc", "angle", number(degrees(p.angle)))));
      break;
    case PathSpec::Kind::Helix:
      out += line("fiber", "helix",
                  fmt::format("{{ {}, {}, {}, {}, {}, {} }}", entry("fiber.helix", "center", vec3(p.center)),
                              entry("fiber.helix", "axis", vec3(p.axis)),
                              entry("fiber.helix", "radius", number(p.radius)),
                              entry("fiber.helix", "pitch", number(p.pitch)),
                              entry("fiber.helix", "turns", number(p.turns)),
                              entry("fiber.helix", "start_angle", number(degrees(p.start_angle)))));
      break;
  }
  out += line("fiber", "elements", std::to_string(f.elements));
}

void write_body(std::string& out, const BodySpec& b) {
  out += "\n[[body]]\n";
  out += line("body", "name", toml_string(b.name));
  out += line("body", "center", vec3(b.center));
  if (b.axes != Mat3::Identity()) {
    // Rows D1, D2, D3: the columns of the frame.
    out += line("body", "axes",
                fmt::format("[{}, {}, {}]", vec3(b.axes.col(0)), vec3(b.axes.col(1)), vec3(b.axes.col(2))));
  }
}

void write_binding(std::string& out, const BindingSpec& b) {
  out += "\n[[binding]]\n";
  out += line("binding", "body", toml_string(b.body));
  if (!b.ends.empty()) {
    std::vector<std::string> ends;
    for (const NodeRef& n : b.ends) ends.push_back(fmt::format("{{ {} }}", node_keys(n, ", ")));
    out += line("binding", "ends", array(ends, 2));
  }
  if (!b.bodies.empty()) {
    std::vector<std::string> bodies;
    for (const std::string& name : b.bodies) bodies.push_back(toml_string(name));
    out += line("binding", "bodies", array(bodies, 8));
  }
  if (!b.grip.empty()) {
    std::string axes;
    for (int a : b.grip) axes += fmt::format("{}{}", axes.empty() ? "" : ", ", a);
    out += line("binding", "grip", fmt::format("[{}]", axes));
  }
  if (b.spin) out += line("binding", "spin", "true");
}

void write_tow(std::string& out, const TowSpec& t) {
  out += "\n[[tow]]\n";
  out += line("tow", "name", toml_string(t.name));
  out += line("tow", "direction", toml_string(t.direction == TowSpec::Direction::Warp ? "warp" : "weft"));
  out += line("tow", "index", std::to_string(t.index));
  std::vector<std::string> fibers;
  for (const std::string& name : t.fibers) fibers.push_back(toml_string(name));
  out += line("tow", "fibers", array(fibers, 8));
}

void write_weave(std::string& out, const std::vector<std::vector<int>>& matrix) {
  out += "\n[weave]\n";
  out += "# rows = wefts, columns = warps, 1 = warp above\n";
  std::vector<std::string> rows;
  for (const std::vector<int>& row : matrix) {
    std::vector<std::string> entries;
    for (int e : row) entries.push_back(std::to_string(e));
    rows.push_back(array(entries, row.size()));
  }
  out += line("weave", "matrix", array(rows, 2));
}

void write_step(std::string& out, const StepSpec& s) {
  out += "\n[[step]]\n";
  out += line("step", "name", toml_string(s.name));
  out += line("step", "kind", toml_string(StepSpec::kind_name(s.kind)));
  if (s.kind == StepSpec::Kind::Biaxial) out += line("step", "strain", number(s.strain)) + line("step", "ratio", number(s.ratio));
  if (s.kind == StepSpec::Kind::Shear) {
    out += line("step", "angle", number(s.angle));
    if (s.free_height) out += line("step", "height", toml_string("free"));
  }
  if (s.is_proximal()) out += line("step", "tolerance", number(s.tolerance));
  out += line("step", "increments", std::to_string(s.increments));
  out += line("step", "max_increments", std::to_string(s.max_increments));
  for (const LoadSpec& l : s.loads) {
    out += "\n  [[step.load]]\n";
    out += fmt::format("  {}\n", node_keys(l.node, "\n  "));
    out += "  " + line("step.load", "force", vec3(l.force));
    out += "  " + line("step.load", "moment", vec3(l.moment));
  }
  for (const DisplacementSpec& d : s.displacements) {
    out += "\n  [[step.displacement]]\n";
    out += fmt::format("  {}\n", node_keys(d.node, "\n  "));
    out += "  " + line("step.displacement", "value", components(d.value));
  }
  for (const BodyStepSpec& b : s.bodies) {
    out += "\n  [[step.body]]\n";
    out += "  " + line("step.body", "name", toml_string(b.name));
    if (b.has_displacement) out += "  " + line("step.body", "displacement", components(b.displacement));
    if (b.has_rotation) out += "  " + line("step.body", "rotation", components(b.rotation));
    if (b.force) out += "  " + line("step.body", "force", vec3(*b.force));
    if (b.moment) out += "  " + line("step.body", "moment", vec3(*b.moment));
  }
}

void write_solver(std::string& out, const SolverSpec& s) {
  out += whole_table("[solver]", "solver",
                     {{"residual_tolerance", number(s.residual_tolerance)},
                      {"displacement_tolerance", number(s.displacement_tolerance)},
                      {"max_iterations", std::to_string(s.max_iterations)},
                      {"max_cuts", std::to_string(s.max_cuts)},
                      {"linear_solver", toml_string(s.linear_solver)},
                      {"krylov_precision", toml_string(s.krylov_precision)},
                      {"binding_tolerance", number(s.binding_tolerance)},
                      {"max_binding_updates", std::to_string(s.max_binding_updates)}});
}

void write_contact(std::string& out, const ContactSpec& c) {
  out += whole_table("[contact]", "contact",
                     {{"friction", number(c.friction)},
                      {"max_penetration", number(c.max_penetration)},
                      {"elastic_slip", number(c.elastic_slip)},
                      {"stiffness", number(c.stiffness)},
                      {"regularization", number(c.regularization)},
                      {"margin", number(c.margin)},
                      {"spacing", number(c.spacing)},
                      {"self_exclusion", number(c.self_exclusion)},
                      {"max_detections", std::to_string(c.max_detections)},
                      {"max_normal_updates", std::to_string(c.max_normal_updates)},
                      {"normal_tolerance", number(c.normal_tolerance)}});
}

void write_output(std::string& out, const OutputSpec& o) {
  std::string checkpoint;
  switch (o.checkpoint) {
    case OutputSpec::Checkpoint::Auto: checkpoint = toml_string("auto"); break;
    case OutputSpec::Checkpoint::Never: checkpoint = toml_string("never"); break;
    case OutputSpec::Checkpoint::Increments: checkpoint = std::to_string(o.checkpoint_increments); break;
    case OutputSpec::Checkpoint::Seconds: checkpoint = toml_string(fmt::format("{} s", number(o.checkpoint_seconds))); break;
  }
  out += whole_table("[output]", "output",
                     {{"every", std::to_string(o.every)},
                      {"tube_sides", std::to_string(o.tube_sides)},
                      {"plots", o.plots ? "true" : "false"},
                      {"test_levels", o.test_levels ? "true" : "false"},
                      {"checkpoint", checkpoint}});
}

}  // namespace

std::string write_case_toml(const Case& c) {
  std::string out;
  // A continued case is written whole (its model inline): it reads alone, but starts from the
  // reference configuration; the comment keeps where its run started.
  if (!c.start.empty())
    out += fmt::format("# This run went on from the state (state.bin) of the result directory {}\n", c.start);
  if (!c.title.empty()) out += line("top", "title", toml_string(c.title));
  for (const MaterialSpec& m : c.materials) write_material(out, m);
  for (const FiberSpec& f : c.fibers) write_fiber(out, f);
  for (const FixSpec& f : c.fixes) {
    const std::string dofs = dofs_value(f);
    if (dofs.empty()) continue;  // holds nothing
    out += "\n[[fix]]\n";
    out += node_keys(f.node, "\n") + "\n";
    out += line("fix", "dofs", dofs);
  }
  for (const BodySpec& b : c.bodies) write_body(out, b);
  for (const BindingSpec& b : c.bindings) write_binding(out, b);
  for (const TowSpec& t : c.tows) write_tow(out, t);
  if (!c.weave.empty()) write_weave(out, c.weave);
  for (const StepSpec& s : c.steps) write_step(out, s);
  write_solver(out, c.solver);
  if (c.contact.enabled) write_contact(out, c.contact);
  write_output(out, c.output);
  if (out.front() == '\n') out.erase(0, 1);  // no title
  return out;
}

}  // namespace fibra
