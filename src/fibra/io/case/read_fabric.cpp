// The readers of [fabric], of weave patterns and matrices, and of [[tow]].
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

std::vector<std::vector<int>> Reader::to_weave_matrix(const Value& v, const std::string& key) const {
  const std::string expected = "expected the weave repeat: an array of rows (wefts), each an array of 0/1 "
                               "integers, one per warp (1 = warp above)";
  if (v.type != Value::Type::Array) fail(key, fmt::format("{}, got {}", expected, describe(v)), &v);
  std::vector<std::vector<int>> matrix;
  for (std::size_t j = 0; j < v.items.size(); ++j) {
    const Value& row = v.items[j];
    const std::string row_key = item(key, j);
    if (row.type != Value::Type::Array) fail(row_key, fmt::format("{}, got {}", expected, describe(row)), &row);
    std::vector<int>& out = matrix.emplace_back();
    for (std::size_t i = 0; i < row.items.size(); ++i) {
      const Value& e = row.items[i];
      if (e.type != Value::Type::Integer) {
        fail(item(row_key, i), fmt::format("expected 0 or 1 (an integer), got {}", describe(e)), &row);
      }
      if (e.integer < INT_MIN || e.integer > INT_MAX) {
        fail(item(row_key, i), fmt::format("expected 0 or 1, got {}", e.integer), &row);
      }
      out.push_back(static_cast<int>(e.integer));
    }
  }
  if (const std::string why = check_weave(matrix); !why.empty()) fail(key, why, &v);
  return matrix;
}

std::vector<std::vector<int>> Reader::to_named_weave(const Value& v, const std::string& key,
                                                     std::string& pattern) const {
  pattern = to_string(v, key);
  std::string error;
  std::vector<std::vector<int>> matrix = named_weave(pattern, error);
  if (!error.empty() || matrix.empty()) {
    if (error.empty()) error = fmt::format("unknown pattern \"{}\"", pattern);
    // A misspelt first word ("twil 2/1"): suggest the pattern with it corrected.
    std::string word = lowercase(pattern);
    word.erase(0, word.find_first_not_of(" \t"));
    const std::size_t end = word.find(' ');
    const std::string rest = end == std::string::npos ? "" : word.substr(end);
    word = word.substr(0, end);
    if (std::find(kWeaveWords.begin(), kWeaveWords.end(), word) == kWeaveWords.end()) {
      if (auto best = closest(word, kWeaveWords)) {
        // Right after the pattern when the message quotes it.
        const std::string suggestion = fmt::format(" (did you mean \"{}{}\"?)", *best, rest);
        const std::string quoted = fmt::format("\"{}\"", pattern);
        const std::size_t at = error.find(quoted);
        error.insert(at == std::string::npos ? error.size() : at + quoted.size(), suggestion);
      }
    }
    fail(key, error, &v);
  }
  return matrix;
}

FabricDirectionSpec Reader::read_fabric_direction(const Value& fabric, const std::string& path, const char* name,
                                                  const Value* shared_tow, const Value* shared_fiber,
                                                  const std::vector<MaterialSpec>& materials) const {
  const std::string base = join(path, name);
  const Value& d =
      require_key(fabric, path, "fabric", name);
  expect_table(d, base);
  check_keys(d, base, schema_keys("fabric.direction"));
  FabricDirectionSpec s;
  s.tows = to_int(require_key(d, base, "fabric.direction", "tows"), join(base, "tows"), 1);
  s.spacing = positive(require_key(d, base, "fabric.direction", "spacing"), join(base, "spacing"));

  const Value* own_tow = find(d, "tow");
  const Value* own_fiber = find(d, "fiber");
  const std::string own_tow_path = join(base, "tow");
  const std::string own_fiber_path = join(base, "fiber");
  const std::string shared_tow_path = join(path, "tow");
  const std::string shared_fiber_path = join(path, "fiber");
  if (own_tow) {
    expect_table(*own_tow, own_tow_path);
    check_keys(*own_tow, own_tow_path, schema_keys("fabric.tow"));
  }
  if (own_fiber) {
    expect_table(*own_fiber, own_fiber_path);
    check_keys(*own_fiber, own_fiber_path, schema_keys("fabric.fiber"));
  }
  // A key of this direction's own table, else of the shared one; missing from both: an error
  // at the key of the table this direction uses.
  struct Found {
    const Value* value;
    std::string key;
  };
  const auto lookup = [&](const Value* own, const std::string& own_path, const Value* shared,
                          const std::string& shared_path, std::string_view key, std::string_view expected) {
    if (own != nullptr) {
      if (const Value* v = find(*own, key)) return Found{v, join(own_path, key)};
    }
    if (shared != nullptr) {
      if (const Value* v = find(*shared, key)) return Found{v, join(shared_path, key)};
    }
    const Value* at = own != nullptr ? own : shared != nullptr ? shared : &d;
    fail(own != nullptr ? join(own_path, key) : join(shared_path, key),
         fmt::format("missing required key (expected {}): the {} tows take it from {} or, when not given there, "
                     "from the shared {}",
                     expected, name, own_path, shared_path),
         at);
  };

  const Found fibers = lookup(own_tow, own_tow_path, shared_tow, shared_tow_path, "fibers", "an integer >= 1");
  s.tow.fibers = to_int(*fibers.value, fibers.key, 1);
  const Found width = lookup(own_tow, own_tow_path, shared_tow, shared_tow_path, "width", "a number > 0 [m]");
  s.tow.width = positive(*width.value, width.key);
  const Found thickness =
      lookup(own_tow, own_tow_path, shared_tow, shared_tow_path, "thickness", "a number > 0 [m], <= width");
  s.tow.thickness = positive(*thickness.value, thickness.key);
  if (!(s.tow.thickness <= s.tow.width)) {
    fail(thickness.key,
         fmt::format("must be <= the width of the {} tows ({}, from {}), got {}", name, s.tow.width, width.key,
                     s.tow.thickness),
         thickness.value);
  }

  const Found radius = lookup(own_fiber, own_fiber_path, shared_fiber, shared_fiber_path, "radius", "a number > 0 [m]");
  s.fiber.radius = positive(*radius.value, radius.key);
  const Found material =
      lookup(own_fiber, own_fiber_path, shared_fiber, shared_fiber_path, "material", "a string naming a [[material]]");
  s.fiber.material = to_string(*material.value, material.key);
  expect_material(s.fiber.material, *material.value, material.key, materials);
  const Found element_length = lookup(own_fiber, own_fiber_path, shared_fiber, shared_fiber_path, "element_length",
                                      "a number > 0 [m]");
  s.fiber.element_length = positive(*element_length.value, element_length.key);
  return s;
}

FabricSpec Reader::read_fabric(const Value& t, const std::string& path,
                               const std::vector<MaterialSpec>& materials) const {
  expect_table(t, path);
  check_keys(t, path, schema_keys("fabric"));
  FabricSpec f;
  const Value* pattern = find(t, "pattern");
  const Value* matrix = find(t, "matrix");
  if (pattern && matrix) fail(path, "give either pattern or matrix, not both", &t);
  if (pattern) {
    f.matrix = to_named_weave(*pattern, join(path, "pattern"), f.pattern);
  } else if (matrix) {
    f.pattern = "matrix";
    f.matrix = to_weave_matrix(*matrix, join(path, "matrix"));
  } else {
    fail(join(path, "pattern"),
         "missing the weave: give pattern (\"plain\", \"twill 2/1\", \"satin 5\", ...) or matrix (the repeat: rows = "
         "wefts, columns = warps, 1 = warp above)",
         &t);
  }

  // The shared tables; each key is checked here even when both directions override it.
  const Value* shared_tow = find(t, "tow");
  const Value* shared_fiber = find(t, "fiber");
  if (shared_tow) {
    const std::string base = join(path, "tow");
    expect_table(*shared_tow, base);
    check_keys(*shared_tow, base, schema_keys("fabric.tow"));
    if (const Value* v = find(*shared_tow, "fibers")) to_int(*v, join(base, "fibers"), 1);
    if (const Value* v = find(*shared_tow, "width")) positive(*v, join(base, "width"));
    if (const Value* v = find(*shared_tow, "thickness")) positive(*v, join(base, "thickness"));
  }
  if (shared_fiber) {
    const std::string base = join(path, "fiber");
    expect_table(*shared_fiber, base);
    check_keys(*shared_fiber, base, schema_keys("fabric.fiber"));
    if (const Value* v = find(*shared_fiber, "radius")) positive(*v, join(base, "radius"));
    if (const Value* v = find(*shared_fiber, "material")) {
      expect_material(to_string(*v, join(base, "material")), *v, join(base, "material"), materials);
    }
    if (const Value* v = find(*shared_fiber, "element_length")) positive(*v, join(base, "element_length"));
  }
  f.warp = read_fabric_direction(t, path, "warp", shared_tow, shared_fiber, materials);
  f.weft = read_fabric_direction(t, path, "weft", shared_tow, shared_fiber, materials);

  f.margin = 0.5 * std::max(f.warp.spacing, f.weft.spacing);
  if (const Value* v = find(t, "margin")) {
    const std::string key = join(path, "margin");
    f.margin = to_number(*v, key);
    if (!(f.margin >= 0)) fail(key, fmt::format("expected a length >= 0 [m], got {}", f.margin), v);
  }
  if (const Value* v = find(t, "tension")) {
    const std::string key = join(path, "tension");
    f.tension = to_number(*v, key);
    if (!(f.tension >= 0)) {
      fail(key, fmt::format("expected a force per fiber >= 0 [N] (0 = automatic), got {}", f.tension), v);
    }
  }
  if (const Value* v = find(t, "grip")) {
    const std::string key = join(path, "grip");
    const std::string g = to_string(*v, key);
    if (g == "averaged") {
      f.grip = FabricSpec::Grip::Averaged;
    } else if (g == "width") {
      f.grip = FabricSpec::Grip::Width;
    } else if (g == "clamped") {
      f.grip = FabricSpec::Grip::Clamped;
    } else {
      fail(key,
           fmt::format("expected \"averaged\" (the ends' mean held), \"width\" (each end held across the tow in the "
                       "fabric's plane) or \"clamped\" (each end held across the tow), got \"{}\"",
                       g),
           v);
    }
  }
  return f;
}

void Reader::check_fabric_size(const Value& t, const std::string& path, const FabricSpec& f) const {
  const ModelSize size = fabric_size(f);
  const std::string why = size_excess(size, m_limits);
  if (why.empty()) return;
  // Where direction `dir` took `key` of `table` from: its own table, else the shared one.
  struct Source {
    std::string key;
    const Value* value;
  };
  const auto source = [&](const char* dir, const char* table, const char* key) {
    const std::string own_path = join(join(path, dir), table);
    if (const Value* d = find(t, dir))
      if (const Value* own = find(*d, table))
        if (const Value* v = find(*own, key)) return Source{join(own_path, key), v};
    const Value* shared = find(t, table);
    return Source{join(join(path, table), key), shared != nullptr ? find(*shared, key) : nullptr};
  };
  const char* names[2] = {"warp", "weft"};
  const FabricDirectionSpec* dirs[2] = {&f.warp, &f.weft};
  double fibers[2], elements[2];
  for (int k = 0; k < 2; ++k) {
    fibers[k] = static_cast<double>(dirs[k]->tows) * static_cast<double>(dirs[k]->tow.fibers);
    elements[k] = fabric_fiber_elements(f, k == 0);
  }
  ModelSize coarse = size;
  coarse.elements = 2 * (fibers[0] + fibers[1]);
  if (size_excess(coarse, m_limits).empty()) {
    const int k = fibers[1] * elements[1] > fibers[0] * elements[0] ? 1 : 0;
    const Source s = source(names[k], "fiber", "element_length");
    fail(s.key,
         fmt::format("{:.6g} m cuts each of the {:.6g} {} fibers ({:.6g} m long) into {:.6g} elements: a model too "
                     "large to run: {}",
                     dirs[k]->fiber.element_length, fibers[k], names[k], fabric_fiber_length(f, k == 0), elements[k],
                     why),
         s.value);
  }
  const int k = fibers[1] > fibers[0] ? 1 : 0;
  const Source s = dirs[k]->tows >= dirs[k]->tow.fibers
                       ? Source{join(join(path, names[k]), "tows"), find(*find(t, names[k]), "tows")}
                       : source(names[k], "tow", "fibers");
  fail(s.key,
       fmt::format("{} tows of {} fibers make {:.6g} {} fibers: a model too large to run: {}", dirs[k]->tows,
                   dirs[k]->tow.fibers, fibers[k], names[k], why),
       s.value);
}

TowSpec Reader::read_tow(const Value& t, const std::string& path, const std::vector<FiberSpec>& fibers,
                         const std::vector<TowSpec>& earlier, std::size_t generated) const {
  check_keys(t, path, schema_keys("tow"));
  // earlier[j]: the tows the [fabric] generates (j < generated), then tow[j - generated].
  const auto describe_tow = [&](std::size_t j) {
    if (j < generated) return fmt::format("tow \"{}\" (generated by the [fabric])", earlier[j].name);
    return fmt::format("tow \"{}\" (tow[{}])", earlier[j].name, j - generated);
  };
  TowSpec tow;
  {
    const std::string key = join(path, "name");
    const Value& v = require_key(t, path, "tow", "name");
    tow.name = to_name(v, key);
    for (std::size_t j = 0; j < earlier.size(); ++j) {
      if (earlier[j].name == tow.name) {
        fail(key, fmt::format("duplicate tow name \"{}\" (already used by {})", tow.name, describe_tow(j)), &v);
      }
    }
  }
  {
    const Value& v = require_key(t, path, "tow", "direction");
    tow.direction = one_of(v, join(path, "direction"), schema_choices("tow", "direction")) == "warp" ? TowSpec::Direction::Warp
                                                                                  : TowSpec::Direction::Weft;
  }
  {
    const std::string key = join(path, "index");
    const Value& v = require_key(t, path, "tow", "index");
    tow.index = to_int(v, key, 0);
    for (std::size_t j = 0; j < earlier.size(); ++j) {
      if (earlier[j].direction == tow.direction && earlier[j].index == tow.index) {
        fail(key,
             fmt::format("{} tow index {} is already used by {}",
                         tow.direction == TowSpec::Direction::Warp ? "warp" : "weft", tow.index, describe_tow(j)),
             &v);
      }
    }
  }
  {
    const std::string key = join(path, "fibers");
    const Value& v = require_key(t, path, "tow", "fibers");
    if (v.type != Value::Type::Array) {
      fail(key, fmt::format("expected an array of fiber names (strings), got {}", describe(v)), &v);
    }
    if (v.items.empty()) fail(key, "expected at least one fiber name, got an empty array", &v);
    for (std::size_t i = 0; i < v.items.size(); ++i) {
      const std::string member_key = item(key, i);
      const Value& e = v.items[i];
      const std::string name = to_string(e, member_key);
      expect_fiber(name, e, member_key, fibers);
      if (const auto it = std::find(tow.fibers.begin(), tow.fibers.end(), name); it != tow.fibers.end()) {
        fail(member_key,
             fmt::format("fiber \"{}\" is listed twice in this tow (already {})", name,
                         item(key, static_cast<std::size_t>(it - tow.fibers.begin()))),
             &e);
      }
      for (std::size_t j = 0; j < earlier.size(); ++j) {
        if (std::find(earlier[j].fibers.begin(), earlier[j].fibers.end(), name) != earlier[j].fibers.end()) {
          fail(member_key,
               fmt::format("fiber \"{}\" is already in {}: a fiber belongs to at most one tow", name, describe_tow(j)),
               &e);
        }
      }
      tow.fibers.push_back(name);
    }
  }
  return tow;
}
}  // namespace fibra::case_file
