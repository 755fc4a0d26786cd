// The readers of [[step]].
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
#include "fibra/model/fabric.hpp"

namespace fibra::case_file {

StepSpec Reader::read_step(const Value& t, const std::string& path, std::size_t k,
                           const std::vector<FiberSpec>& fibers, const std::vector<BodySpec>& bodies) const {
  check_keys(t, path, schema_keys("step"));
  StepSpec step;
  if (const Value* v = find(t, "name")) {
    step.name = to_name(*v, join(path, "name"));
  } else {
    step.name = fmt::format("step{}", k);
  }
  if (const Value* v = find(t, "kind")) {
    const std::string key = join(path, "kind");
    const std::string kind = to_string(*v, key);
    if (kind == "standard" || kind == "load") {
      step.kind = StepSpec::Kind::Standard;
    } else if (kind == "weave") {
      step.kind = StepSpec::Kind::Weave;
    } else if (kind == "relax") {
      step.kind = StepSpec::Kind::Relax;
    } else if (kind == "biaxial") {
      step.kind = StepSpec::Kind::Biaxial;
    } else if (kind == "shear") {
      step.kind = StepSpec::Kind::Shear;
    } else {
      const Keys words = schema_choices("step", "kind");
      fail(key,
           fmt::format("expected \"load\" (or \"standard\"), \"weave\", \"relax\", \"biaxial\" or \"shear\", got \"{}\"{}",
                       kind, did_you_mean(kind, words)),
           v);
    }
  }
  // The test parameters: each only with its kind, and required there.
  const bool biaxial = step.kind == StepSpec::Kind::Biaxial, shear = step.kind == StepSpec::Kind::Shear;
  for (const char* name : {"strain", "ratio", "angle", "height"}) {
    const Value* v = find(t, name);
    const bool for_shear = std::string(name) == "angle" || std::string(name) == "height";
    if (v && !(for_shear ? shear : biaxial))
      fail(join(path, name),
           fmt::format("`{}` belongs to {} steps; this step's kind is not", name,
                       for_shear ? "kind = \"shear\"" : "kind = \"biaxial\""),
           v);
  }
  if (biaxial) {
    const Value* v = find(t, "strain");
    if (!v) fail(join(path, "strain"), "a biaxial step needs `strain` (the warp axial strain at its end, e.g. 0.02)", &t);
    step.strain = to_number(*v, join(path, "strain"));
    if (!(step.strain > -0.5 && step.strain < 0.5 && step.strain != 0.0))
      fail(join(path, "strain"), fmt::format("expected a strain in (-0.5, 0.5), not 0, got {}", step.strain), v);
    if (const Value* r = find(t, "ratio")) {
      step.ratio = to_number(*r, join(path, "ratio"));
      if (!(step.ratio >= 0.0 && step.ratio <= 10.0))
        fail(join(path, "ratio"),
             fmt::format("expected a ratio in [0, 10] (weft elongation / warp elongation; 0: weft edges free), got {}",
                         step.ratio),
             r);
    }
  }
  if (shear) {
    const Value* v = find(t, "angle");
    if (!v) fail(join(path, "angle"), "a shear step needs `angle` (the shear angle at its end, in degrees, e.g. 25)", &t);
    step.angle = to_number(*v, join(path, "angle"));
    if (!(std::abs(step.angle) > 0.0 && std::abs(step.angle) < 80.0))
      fail(join(path, "angle"), fmt::format("expected an angle in degrees in (-80, 80), not 0, got {}", step.angle), v);
    if (const Value* h = find(t, "height")) step.free_height = one_of(*h, join(path, "height"), schema_choices("step", "height")) == "free";
  }
  if (const Value* v = find(t, "tolerance")) {
    const std::string key = join(path, "tolerance");
    if (!step.is_proximal())
      fail(key, "`tolerance` belongs to relax, biaxial and shear steps (the drag force at which they settle); this "
                "step's kind is not", v);
    step.tolerance = fraction(*v, key, "the reference force");
  }
  read_bounded(t, path, "step", "increments", step.increments);
  if (const Value* v = find(t, "max_increments")) {
    const std::string key = join(path, "max_increments");
    step.max_increments = to_int(*v, key, 0);
    if (step.max_increments != 0 && step.max_increments < step.increments) {
      fail(key,
           fmt::format("must be 0 (automatic) or >= increments ({}), got {}", step.increments,
                       step.max_increments),
           v);
    }
  }
  if (const Value* v = find(t, "load")) {
    const std::string key = join(path, "load");
    const std::vector<Value>& loads = to_table_array(*v, key, "step.load");
    for (std::size_t i = 0; i < loads.size(); ++i) {
      step.loads.push_back(read_load(loads[i], item(key, i), fibers));
    }
  }
  if (const Value* v = find(t, "displacement")) {
    const std::string key = join(path, "displacement");
    const std::vector<Value>& displacements = to_table_array(*v, key, "step.displacement");
    for (std::size_t i = 0; i < displacements.size(); ++i) {
      step.displacements.push_back(read_displacement(displacements[i], item(key, i), fibers));
    }
  }
  if (const Value* v = find(t, "body")) {
    const std::string key = join(path, "body");
    const std::vector<Value>& entries = to_table_array(*v, key, "step.body");
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const std::string entry_path = item(key, i);
      BodyStepSpec b = read_step_body(entries[i], entry_path, bodies);
      for (std::size_t j = 0; j < step.bodies.size(); ++j) {
        if (step.bodies[j].name == b.name) {
          fail(join(entry_path, "name"),
               fmt::format("body \"{}\" is listed twice in this step (already {})", b.name, item(key, j)),
               find(entries[i], "name"));
        }
      }
      step.bodies.push_back(std::move(b));
    }
  }
  return step;
}

void Reader::read_steps(const Value& root, Case& c, const std::vector<FiberSpec>& all_fibers,
                        const std::vector<BodySpec>& all_bodies) const {
  const std::string fabric_word = m_json ? "a fabric object" : "a [fabric]";
  const Value& v = require_key(root, "", "top", "step");
  const std::vector<Value>& tables = to_table_array(v, "step", "step");
  if (tables.empty()) fail("step", "at least one step is required", &v);
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const std::string path = item("step", i);
    StepSpec s = read_step(tables[i], path, i, all_fibers, all_bodies);
    for (std::size_t j = 0; j < c.steps.size(); ++j) {
      if (c.steps[j].name == s.name) {
        fail(join(path, "name"),
             fmt::format("duplicate step name \"{}\" (already used by step[{}])", s.name, j),
             find(tables[i], "name") ? find(tables[i], "name") : &tables[i]);
      }
    }
    // Biaxial and shear steps drive the four edge bodies a fabric generates.
    if (s.is_test() && !c.fabric) {
      for (const char* edge : kEdgeBodies) {
        if (std::none_of(c.bodies.begin(), c.bodies.end(), [&](const BodySpec& b) { return b.name == edge; }))
          fail(join(path, "kind"),
               fmt::format("a {} step drives the edge bodies of a fabric (edge.x-, edge.x+, edge.y-, edge.y+); "
                           "there is no body \"{}\": give {}",
                           StepSpec::kind_name(s.kind), edge, fabric_word),
               find(tables[i], "kind"));
      }
    }
    // A weave step orients the contacts between crossing tows by the weave pattern.
    if (s.kind == StepSpec::Kind::Weave) {
      const std::string key = join(path, "kind");
      if (c.tows.empty() && !c.fabric) {
        fail(key,
             fmt::format("a weave step needs tows: define {} entries (or {})", m_json ? "tow" : "[[tow]]",
                         fabric_word),
             find(tables[i], "kind"));
      }
      if (c.weave.empty() && !c.fabric) {
        fail(key,
             fmt::format("a weave step needs the weave pattern: give {} (matrix or pattern)",
                         m_json ? "a weave object" : "a [weave] table"),
             find(tables[i], "kind"));
      }
    }
    c.steps.push_back(std::move(s));
  }
}
}  // namespace fibra::case_file
