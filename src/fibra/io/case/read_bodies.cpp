// The readers of [[body]], [[binding]] and [[step.body]].
#include "fibra/io/case/reader.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <string>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/case/suggest.hpp"

namespace fibra::case_file {

BodySpec Reader::read_body(const Value& t, const std::string& path) const {
  check_keys(t, path, schema_keys("body"));
  BodySpec b;
  b.name = to_name(require_key(t, path, "body", "name"), join(path, "name"));
  b.center = to_vec3(require_key(t, path, "body", "center"), join(path, "center"));
  if (const Value* v = find(t, "axes")) {
    const std::string key = join(path, "axes");
    if (v->type != Value::Type::Array || v->items.size() != 3) {
      fail(key,
           fmt::format("expected an array of 3 rows D1, D2, D3 (each an array of 3 numbers), got {}",
                       describe(*v)),
           v);
    }
    for (std::size_t i = 0; i < 3; ++i) b.axes.col(static_cast<Index>(i)) = to_vec3(v->items[i], item(key, i));
    // Orthonormal: D_i . D_j = delta_ij; right-handed: D1 x D2 = D3 (determinant +1).
    constexpr double kTolerance = 1e-9;
    for (int i = 0; i < 3; ++i) {
      for (int j = i; j < 3; ++j) {
        const double dot = b.axes.col(i).dot(b.axes.col(j));
        const double expected = i == j ? 1.0 : 0.0;
        if (!(std::abs(dot - expected) <= kTolerance)) {
          fail(key,
               fmt::format("expected orthonormal axes (rows D1, D2, D3), but D{}.D{} = {} instead of {} "
                           "(tolerance {})",
                           i + 1, j + 1, dot, expected, kTolerance),
               v);
        }
      }
    }
    const double det = b.axes.col(0).cross(b.axes.col(1)).dot(b.axes.col(2));
    if (!(det > 0)) {
      fail(key,
           fmt::format("expected right-handed axes (D3 = D1 x D2), but the rows are left-handed "
                       "(D3 = -D1 x D2, determinant {})",
                       det),
           v);
    }
  }
  return b;
}

BindingSpec Reader::read_binding(const Value& t, const std::string& path, std::size_t k,
                                 const std::vector<FiberSpec>& fibers, const std::vector<BodySpec>& bodies,
                                 const std::vector<BindingSpec>& earlier, std::size_t generated) const {
  // earlier[j]: the bindings the [fabric] generates (j < generated), then binding[j - generated].
  const auto describe_binding = [&](std::size_t j) {
    if (j < generated) return fmt::format("a binding the [fabric] generates (to body \"{}\")", earlier[j].body);
    return fmt::format("binding[{}] (to body \"{}\")", j - generated, earlier[j].body);
  };
  check_keys(t, path, schema_keys("binding"));
  BindingSpec b;
  b.line = static_cast<int>(k);
  {
    const std::string key = join(path, "body");
    const Value& v = require_key(t, path, "binding", "body");
    b.body = to_string(v, key);
    expect_body(b.body, v, key, bodies);
  }

  if (const Value* v = find(t, "ends")) {
    const std::string key = join(path, "ends");
    const std::vector<Value>& ends = to_table_array(*v, key, "binding.ends");
    // Node indices of the references that name a node directly (a fraction is compared as is).
    const auto index_of = [&](const NodeRef& ref) -> Index {
      const auto f =
          std::find_if(fibers.begin(), fibers.end(), [&](const FiberSpec& x) { return x.name == ref.fiber; });
      switch (ref.kind) {
        case NodeRef::Kind::First: return 0;
        case NodeRef::Kind::Last: return 2 * static_cast<Index>(f->elements);
        case NodeRef::Kind::NodeIndex: return ref.index;
        case NodeRef::Kind::Fraction: break;
      }
      return -1;
    };
    for (std::size_t i = 0; i < ends.size(); ++i) {
      const std::string end_path = item(key, i);
      check_keys(ends[i], end_path, schema_keys("node"));
      NodeRef ref = read_node(ends[i], end_path, fibers);
      for (std::size_t j = 0; j < b.ends.size(); ++j) {
        const NodeRef& other = b.ends[j];
        const bool fraction = ref.kind == NodeRef::Kind::Fraction;
        if (other.fiber != ref.fiber || (other.kind == NodeRef::Kind::Fraction) != fraction) continue;
        const bool same = fraction ? other.fraction == ref.fraction : index_of(other) == index_of(ref);
        if (same) {
          fail(end_path,
               fmt::format("duplicate end: node {} of fiber \"{}\" is already {}", ref.label(),
                           ref.fiber, item(key, j)),
               &ends[i]);
        }
      }
      b.ends.push_back(std::move(ref));
    }
  }

  if (const Value* v = find(t, "bodies")) {
    const std::string key = join(path, "bodies");
    if (v->type != Value::Type::Array) {
      fail(key, fmt::format("expected an array of body names (strings), got {}", describe(*v)), v);
    }
    // The body a body is bound to, by the earlier bindings and the members of this one read so far.
    const auto parent_of = [&](const std::string& name) -> const std::string* {
      for (const BindingSpec& e : earlier) {
        if (std::find(e.bodies.begin(), e.bodies.end(), name) != e.bodies.end()) return &e.body;
      }
      if (std::find(b.bodies.begin(), b.bodies.end(), name) != b.bodies.end()) return &b.body;
      return nullptr;
    };
    for (std::size_t i = 0; i < v->items.size(); ++i) {
      const std::string member_key = item(key, i);
      const Value& e = v->items[i];
      const std::string name = to_string(e, member_key);
      expect_body(name, e, member_key, bodies);
      if (name == b.body) fail(member_key, fmt::format("body \"{}\" cannot be bound to itself", name), &e);
      if (const auto it = std::find(b.bodies.begin(), b.bodies.end(), name); it != b.bodies.end()) {
        fail(member_key,
             fmt::format("body \"{}\" is listed twice in this binding (already {})", name,
                         item(key, static_cast<std::size_t>(it - b.bodies.begin()))),
             &e);
      }
      for (std::size_t j = 0; j < earlier.size(); ++j) {
        if (std::find(earlier[j].bodies.begin(), earlier[j].bodies.end(), name) != earlier[j].bodies.end()) {
          fail(member_key,
               fmt::format("body \"{}\" is a member of two bindings, {} and binding[{}] (to body \"{}\"): a body "
                           "can be a member of at most one binding",
                           name, describe_binding(j), k, b.body),
               &e);
        }
      }
      // Binding `name` to b.body closes a cycle when b.body is already bound, through a chain of
      // bindings, to `name`.
      std::vector<std::string> chain = {b.body};
      for (const std::string* up = parent_of(b.body); up != nullptr && chain.size() <= bodies.size();
           up = parent_of(*up)) {
        chain.push_back(*up);
        if (*up == name) {
          chain.push_back(b.body);
          std::string cycle;
          for (const std::string& c : chain) cycle += (cycle.empty() ? "" : " -> ") + c;
          fail(key, fmt::format("bodies bound in a cycle: {}", cycle), v);
        }
      }
      b.bodies.push_back(name);
    }
  }

  if (b.ends.empty() && b.bodies.empty()) {
    fail(path, "a binding needs members: give `ends` and/or `bodies`", &t);
  }

  if (const Value* v = find(t, "grip")) {
    const std::string key = join(path, "grip");
    const std::string expected = "expected an array of the body's axes (1, 2, 3) along which each bound fiber end is held";
    if (v->type != Value::Type::Array) fail(key, fmt::format("{}, got {}", expected, describe(*v)), v);
    for (std::size_t i = 0; i < v->items.size(); ++i) {
      const std::string axis_key = item(key, i);
      const int axis = to_int(v->items[i], axis_key, 1);
      if (axis > 3) fail(axis_key, fmt::format("{}, got axis {}", expected, axis), &v->items[i]);
      if (std::find(b.grip.begin(), b.grip.end(), axis) != b.grip.end()) {
        fail(axis_key, fmt::format("axis {} is listed twice", axis), &v->items[i]);
      }
      b.grip.push_back(axis);
    }
    if (b.grip.size() == 3) {
      fail(key,
           "all three axes: each end would be held rigidly in the body (no freedom left to the fibers along their "
           "length); grip at most two axes, the ones across the fibers",
           v);
    }
    if (!b.grip.empty() && b.ends.empty()) {
      fail(key, "a grip holds bound fiber ends, and this binding has none (only `bodies`)", v);
    }
    std::sort(b.grip.begin(), b.grip.end());
  }
  if (const Value* v = find(t, "spin")) {
    b.spin = to_bool(*v, join(path, "spin"));
    if (b.spin && b.ends.empty()) {
      fail(join(path, "spin"), "`spin` holds bound fiber ends against turning about their axis, and this binding has "
                               "none (only `bodies`)", v);
    }
  }
  return b;
}

BodyStepSpec Reader::read_step_body(const Value& t, const std::string& path,
                                    const std::vector<BodySpec>& bodies) const {
  check_keys(t, path, schema_keys("step.body"));
  BodyStepSpec s;
  {
    const std::string key = join(path, "name");
    const Value& v = require_key(t, path, "step.body", "name");
    s.name = to_string(v, key);
    expect_body(s.name, v, key, bodies);
  }
  const Value* displacement = find(t, "displacement");
  const Value* rotation = find(t, "rotation");
  const Value* force = find(t, "force");
  const Value* moment = find(t, "moment");
  if (!displacement && !rotation && !force && !moment) {
    fail(path,
         fmt::format("nothing given for body \"{}\": expected at least one of displacement, rotation "
                     "(arrays of 3 components, each a number or \"free\"), force or moment (arrays of 3 "
                     "numbers)",
                     s.name),
         &t);
  }
  if (displacement) {
    s.has_displacement = true;
    s.displacement = to_components(*displacement, join(path, "displacement"));
  }
  if (rotation) {
    s.has_rotation = true;
    s.rotation = to_components(*rotation, join(path, "rotation"));
  }
  if (force) s.force = to_vec3(*force, join(path, "force"));
  if (moment) s.moment = to_vec3(*moment, join(path, "moment"));

  // A prescribed component takes no load: its reaction is computed.
  const auto check_conflict = [&](const char* load_name, const Value* load_value, const std::optional<Vec3>& load,
                                  const char* motion_name, const std::array<std::optional<double>, 3>& motion) {
    if (!load) return;
    static constexpr const char* kAxis[3] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i) {
      if ((*load)[i] != 0 && motion[i].has_value()) {
        fail(join(path, load_name),
             fmt::format("{} {} is {} but {} {} is prescribed in the same entry: a prescribed component "
                         "takes no {} (give 0, or make {} {} \"free\")",
                         load_name, kAxis[i], (*load)[i], motion_name, kAxis[i], load_name, motion_name, kAxis[i]),
             load_value);
      }
    }
  };
  check_conflict("force", force, s.force, "displacement", s.displacement);
  check_conflict("moment", moment, s.moment, "rotation", s.rotation);
  return s;
}
}  // namespace fibra::case_file
