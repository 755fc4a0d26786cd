#include "fibra/io/case_writer.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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
std::string quoted(std::string_view s) {
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
      where = "node = \"first\"";
      break;
    case NodeRef::Kind::Last:
      where = "node = \"last\"";
      break;
    case NodeRef::Kind::NodeIndex:
      where = fmt::format("node = {}", n.index);
      break;
    case NodeRef::Kind::Fraction:
      where = fmt::format("at = {}", number(n.fraction));
      break;
  }
  return fmt::format("fiber = {}{}{}", quoted(n.fiber), separator, where);
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
    if (d[k]) items.push_back(quoted(kNames[k]));
  for (int vector_index = 0; vector_index < 2; ++vector_index) {
    const int first = 3 + 3 * vector_index;
    if (d[first] && d[first + 1] && d[first + 2]) {
      items.push_back(quoted(vector_index == 0 ? "g1" : "g2"));
      continue;
    }
    for (int k = first; k < first + 3; ++k)
      if (d[k]) items.push_back(quoted(kNames[k]));
  }
  return array(items, 11);
}

void write_material(std::string& out, const MaterialSpec& m) {
  out += "\n[[material]]\n";
  out += fmt::format("name = {}\n", quoted(m.name));
  const bool transverse = m.model == MaterialSpec::Model::Transverse;
  out += fmt::format("model = {}\n", quoted(transverse ? "transverse" : "isotropic"));
  out += fmt::format("young = {}\n", number(m.young));
  out += fmt::format("poisson = {}\n", number(m.poisson));
  if (transverse) {
    out += fmt::format("young_transverse = {}\n", number(m.young_transverse));
    out += fmt::format("shear_axial = {}\n", number(m.shear_axial));
    out += fmt::format("poisson_transverse = {}\n", number(m.poisson_transverse));
  }
}

void write_fiber(std::string& out, const FiberSpec& f) {
  out += "\n[[fiber]]\n";
  out += fmt::format("name = {}\n", quoted(f.name));
  out += fmt::format("material = {}\n", quoted(f.material));
  if (f.semi_axis_1 == f.semi_axis_2 && f.radius == f.semi_axis_1) {
    out += fmt::format("radius = {}\n", number(f.radius));
  } else {
    out += fmt::format("semi_axes = [{}, {}]\n", number(f.semi_axis_1), number(f.semi_axis_2));
  }
  if (f.section_direction) out += fmt::format("section_direction = {}\n", vec3(*f.section_direction));
  const PathSpec& p = f.path;
  switch (p.kind) {
    case PathSpec::Kind::Polyline: {
      std::vector<std::string> points;
      for (const Vec3& x : p.points) points.push_back(vec3(x));
      out += fmt::format("points = {}\n", array(points, 3));
      break;
    }
    case PathSpec::Kind::Arc:
      out +=
          fmt::format("arc = {{ center = {}, axis = {}, radius = {}, start_angle = {}, angle = {} }}\n", vec3(p.center),
                      vec3(p.axis), number(p.radius), number(degrees(p.start_angle)), number(degrees(p.angle)));
      break;
    case PathSpec::Kind::Helix:
      out +=
          fmt::format("helix = {{ center = {}, axis = {}, radius = {}, pitch = {}, turns = {}, start_angle = {} }}\n",
                      vec3(p.center), vec3(p.axis), number(p.radius), number(p.pitch), number(p.turns),
                      number(degrees(p.start_angle)));
      break;
  }
  out += fmt::format("elements = {}\n", f.elements);
}

void write_body(std::string& out, const BodySpec& b) {
  out += "\n[[body]]\n";
  out += fmt::format("name = {}\n", quoted(b.name));
  out += fmt::format("center = {}\n", vec3(b.center));
  if (b.axes != Mat3::Identity()) {
    // Rows D1, D2, D3: the columns of the frame.
    out += fmt::format("axes = [{}, {}, {}]\n", vec3(b.axes.col(0)), vec3(b.axes.col(1)), vec3(b.axes.col(2)));
  }
}

void write_binding(std::string& out, const BindingSpec& b) {
  out += "\n[[binding]]\n";
  out += fmt::format("body = {}\n", quoted(b.body));
  if (!b.ends.empty()) {
    std::vector<std::string> ends;
    for (const NodeRef& n : b.ends) ends.push_back(fmt::format("{{ {} }}", node_keys(n, ", ")));
    out += fmt::format("ends = {}\n", array(ends, 2));
  }
  if (!b.bodies.empty()) {
    std::vector<std::string> bodies;
    for (const std::string& name : b.bodies) bodies.push_back(quoted(name));
    out += fmt::format("bodies = {}\n", array(bodies, 8));
  }
  if (!b.grip.empty()) {
    std::string axes;
    for (int a : b.grip) axes += fmt::format("{}{}", axes.empty() ? "" : ", ", a);
    out += fmt::format("grip = [{}]\n", axes);
  }
  if (b.spin) out += "spin = true\n";
}

void write_tow(std::string& out, const TowSpec& t) {
  out += "\n[[tow]]\n";
  out += fmt::format("name = {}\n", quoted(t.name));
  out += fmt::format("direction = {}\n", quoted(t.direction == TowSpec::Direction::Warp ? "warp" : "weft"));
  out += fmt::format("index = {}\n", t.index);
  std::vector<std::string> fibers;
  for (const std::string& name : t.fibers) fibers.push_back(quoted(name));
  out += fmt::format("fibers = {}\n", array(fibers, 8));
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
  out += fmt::format("matrix = {}\n", array(rows, 2));
}

void write_step(std::string& out, const StepSpec& s) {
  out += "\n[[step]]\n";
  out += fmt::format("name = {}\n", quoted(s.name));
  out += fmt::format("kind = {}\n", quoted(StepSpec::kind_name(s.kind)));
  if (s.kind == StepSpec::Kind::Biaxial) out += fmt::format("strain = {}\nratio = {}\n", number(s.strain), number(s.ratio));
  if (s.kind == StepSpec::Kind::Shear) {
    out += fmt::format("angle = {}\n", number(s.angle));
    if (s.free_height) out += "height = \"free\"\n";
  }
  if (s.is_proximal()) out += fmt::format("tolerance = {}\n", number(s.tolerance));
  out += fmt::format("increments = {}\n", s.increments);
  out += fmt::format("max_increments = {}\n", s.max_increments);
  for (const LoadSpec& l : s.loads) {
    out += "\n  [[step.load]]\n";
    out += fmt::format("  {}\n", node_keys(l.node, "\n  "));
    out += fmt::format("  force = {}\n", vec3(l.force));
    out += fmt::format("  moment = {}\n", vec3(l.moment));
  }
  for (const DisplacementSpec& d : s.displacements) {
    out += "\n  [[step.displacement]]\n";
    out += fmt::format("  {}\n", node_keys(d.node, "\n  "));
    out += fmt::format("  value = {}\n", components(d.value));
  }
  for (const BodyStepSpec& b : s.bodies) {
    out += "\n  [[step.body]]\n";
    out += fmt::format("  name = {}\n", quoted(b.name));
    if (b.has_displacement) out += fmt::format("  displacement = {}\n", components(b.displacement));
    if (b.has_rotation) out += fmt::format("  rotation = {}\n", components(b.rotation));
    if (b.force) out += fmt::format("  force = {}\n", vec3(*b.force));
    if (b.moment) out += fmt::format("  moment = {}\n", vec3(*b.moment));
  }
}

void write_solver(std::string& out, const SolverSpec& s) {
  out += "\n[solver]\n";
  out += fmt::format("residual_tolerance = {}\n", number(s.residual_tolerance));
  out += fmt::format("displacement_tolerance = {}\n", number(s.displacement_tolerance));
  out += fmt::format("max_iterations = {}\n", s.max_iterations);
  out += fmt::format("max_cuts = {}\n", s.max_cuts);
  out += fmt::format("linear_solver = {}\n", quoted(s.linear_solver));
  out += fmt::format("krylov_precision = {}\n", quoted(s.krylov_precision));
  out += fmt::format("binding_tolerance = {}\n", number(s.binding_tolerance));
  out += fmt::format("max_binding_updates = {}\n", s.max_binding_updates);
}

void write_contact(std::string& out, const ContactSpec& c) {
  out += "\n[contact]\n";
  out += fmt::format("friction = {}\n", number(c.friction));
  out += fmt::format("max_penetration = {}\n", number(c.max_penetration));
  out += fmt::format("elastic_slip = {}\n", number(c.elastic_slip));
  out += fmt::format("stiffness = {}\n", number(c.stiffness));
  out += fmt::format("regularization = {}\n", number(c.regularization));
  out += fmt::format("margin = {}\n", number(c.margin));
  out += fmt::format("spacing = {}\n", number(c.spacing));
  out += fmt::format("self_exclusion = {}\n", number(c.self_exclusion));
  out += fmt::format("max_detections = {}\n", c.max_detections);
  out += fmt::format("max_normal_updates = {}\n", c.max_normal_updates);
  out += fmt::format("normal_tolerance = {}\n", number(c.normal_tolerance));
}

}  // namespace

std::string write_case_toml(const Case& c) {
  std::string out;
  // A continued case is written whole (its model inline): it reads alone, but starts from the
  // reference configuration; the comment keeps where its run started.
  if (!c.start.empty())
    out += fmt::format("# This run went on from the state (state.bin) of the result directory {}\n", c.start);
  if (!c.title.empty()) out += fmt::format("title = {}\n", quoted(c.title));
  for (const MaterialSpec& m : c.materials) write_material(out, m);
  for (const FiberSpec& f : c.fibers) write_fiber(out, f);
  for (const FixSpec& f : c.fixes) {
    const std::string dofs = dofs_value(f);
    if (dofs.empty()) continue;  // holds nothing
    out += "\n[[fix]]\n";
    out += node_keys(f.node, "\n") + "\n";
    out += fmt::format("dofs = {}\n", dofs);
  }
  for (const BodySpec& b : c.bodies) write_body(out, b);
  for (const BindingSpec& b : c.bindings) write_binding(out, b);
  for (const TowSpec& t : c.tows) write_tow(out, t);
  if (!c.weave.empty()) write_weave(out, c.weave);
  for (const StepSpec& s : c.steps) write_step(out, s);
  write_solver(out, c.solver);
  if (c.contact.enabled) write_contact(out, c.contact);
  out += "\n[output]\n";
  out += fmt::format("every = {}\n", c.output.every);
  out += fmt::format("tube_sides = {}\n", c.output.tube_sides);
  out += fmt::format("plots = {}\n", c.output.plots);
  out += fmt::format("test_levels = {}\n", c.output.test_levels);
  switch (c.output.checkpoint) {
    case OutputSpec::Checkpoint::Auto: out += "checkpoint = \"auto\"\n"; break;
    case OutputSpec::Checkpoint::Never: out += "checkpoint = \"never\"\n"; break;
    case OutputSpec::Checkpoint::Increments: out += fmt::format("checkpoint = {}\n", c.output.checkpoint_increments); break;
    case OutputSpec::Checkpoint::Seconds: out += fmt::format("checkpoint = \"{} s\"\n", number(c.output.checkpoint_seconds)); break;
  }
  if (out.front() == '\n') out.erase(0, 1);  // no title
  return out;
}

}  // namespace fibra
