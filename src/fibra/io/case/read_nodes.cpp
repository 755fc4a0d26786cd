// The readers of node references, [[fix]], [[step.load]] and [[step.displacement]].
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

NodeRef Reader::read_node(const Value& t, const std::string& path,
                          const std::vector<FiberSpec>& fibers) const {
  NodeRef ref;
  const std::string fiber_key = join(path, "fiber");
  const Value& fiber = require_key(t, path, "node", "fiber");
  ref.fiber = to_string(fiber, fiber_key);
  const FiberSpec* it = &expect_fiber(ref.fiber, fiber, fiber_key, fibers);

  const Value* node = find(t, "node");
  const Value* at = find(t, "at");
  if (node && at) fail(path, "give either node or at, not both", &t);
  if (!node && !at) {
    fail(join(path, "node"),
         "missing required key (expected node = \"first\", \"last\" or a node index, or "
         "at = a fraction of the fiber length in [0, 1])",
         &t);
  }
  if (node) {
    const std::string key = join(path, "node");
    const Index count = 2 * static_cast<Index>(it->elements) + 1;
    if (node->type == Value::Type::String) {
      if (node->text == "first") {
        ref.kind = NodeRef::Kind::First;
      } else if (node->text == "last") {
        ref.kind = NodeRef::Kind::Last;
      } else {
        const Keys words = {"first", "last"};
        fail(key,
             fmt::format("expected \"first\", \"last\" or a node index (integer), got \"{}\"{}",
                         node->text, did_you_mean(node->text, words)),
             node);
      }
    } else if (node->type == Value::Type::Integer) {
      if (node->integer < 0 || node->integer >= count) {
        fail(key,
             fmt::format("node index out of range: fiber \"{}\" has {} nodes (indices 0 to {}), got {}",
                         it->name, count, count - 1, node->integer),
             node);
      }
      ref.kind = NodeRef::Kind::NodeIndex;
      ref.index = node->integer;
    } else {
      fail(key,
           fmt::format("expected \"first\", \"last\" or a node index (integer), got {}",
                       describe(*node)),
           node);
    }
  } else {
    const std::string key = join(path, "at");
    ref.kind = NodeRef::Kind::Fraction;
    ref.fraction = to_number(*at, key);
    if (!(ref.fraction >= 0 && ref.fraction <= 1)) {
      fail(key, fmt::format("must be in [0, 1] (a fraction of the fiber length), got {}", ref.fraction),
           at);
    }
  }
  return ref;
}

FixSpec Reader::read_fix(const Value& t, const std::string& path,
                         const std::vector<FiberSpec>& fibers) const {
  check_keys(t, path, schema_keys("fix"));
  FixSpec fix;
  fix.node = read_node(t, path, fibers);
  if (const Value* v = find(t, "dofs")) {
    const std::string key = join(path, "dofs");
    const auto set = [&](int from, int to, bool on) {
      for (int k = from; k < to; ++k) fix.dofs[k] = on;
    };
    if (v->type == Value::Type::Array) {
      // A list of components: x, y, z (of x0), g1, g2 (whole vectors) or g1x ... g2z.
      const Keys words = {"x", "y", "z", "g1", "g2", "g1x", "g1y", "g1z", "g2x", "g2y", "g2z"};
      set(0, 9, false);
      if (v->items.empty()) fail(key, "expected a non-empty list of components", v);
      for (std::size_t i = 0; i < v->items.size(); ++i) {
        const std::string item_key = fmt::format("{}[{}]", key, i);
        const std::string c = to_string(v->items[i], item_key);
        const auto it = std::find(words.begin(), words.end(), c);
        if (it == words.end())
          fail(item_key,
               fmt::format("expected one of x, y, z, g1, g2, g1x, g1y, g1z, g2x, g2y, g2z, got \"{}\"{}", c,
                           did_you_mean(c, words)),
               &v->items[i]);
        const int w = static_cast<int>(it - words.begin());
        if (w < 3) fix.dofs[w] = true;
        else if (w == 3) set(3, 6, true);
        else if (w == 4) set(6, 9, true);
        else fix.dofs[w - 5 + 3] = true;
      }
    } else {
      const std::string dofs = to_string(*v, key);
      if (dofs == "all") {
        set(0, 9, true);
      } else if (dofs == "position") {
        set(0, 3, true);
        set(3, 9, false);
      } else if (dofs == "sections") {
        set(0, 3, false);
        set(3, 9, true);
      } else {
        const Keys words = {"all", "position", "sections"};
        fail(key,
             fmt::format("expected \"all\", \"position\", \"sections\" or a list of components, got \"{}\"{}",
                         dofs, did_you_mean(dofs, words)),
             v);
      }
    }
  }
  return fix;
}

LoadSpec Reader::read_load(const Value& t, const std::string& path,
                           const std::vector<FiberSpec>& fibers) const {
  check_keys(t, path, schema_keys("step.load"));
  LoadSpec load;
  load.node = read_node(t, path, fibers);
  const Value* force = find(t, "force");
  const Value* moment = find(t, "moment");
  if (!force && !moment) {
    fail(join(path, "force"),
         "missing required key (expected force and/or moment, each an array of 3 numbers)", &t);
  }
  if (force) load.force = to_vec3(*force, join(path, "force"));
  if (moment) load.moment = to_vec3(*moment, join(path, "moment"));
  return load;
}

DisplacementSpec Reader::read_displacement(const Value& t, const std::string& path,
                                           const std::vector<FiberSpec>& fibers) const {
  check_keys(t, path, schema_keys("step.displacement"));
  DisplacementSpec d;
  d.node = read_node(t, path, fibers);
  const std::string key = join(path, "value");
  const Value& v = require_key(t, path, "step.displacement", "value");
  d.value = to_components(v, key);
  const bool any = std::any_of(d.value.begin(), d.value.end(), [](const auto& x) { return x.has_value(); });
  if (!any) fail(key, "all 3 components are \"free\": at least one must be a number", &v);
  return d;
}
}  // namespace fibra::case_file
