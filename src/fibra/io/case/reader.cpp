// The Reader's core: failures, descriptions, key checks, conversions, references; the whole case.
#include "fibra/io/case/reader.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/case/suggest.hpp"
#include "fibra/model/fabric.hpp"
#include "fibra/model/model.hpp"

namespace fibra::case_file {

void Reader::fail(const std::string& key, const std::string& message, const Value* at) const {
  std::string full = message;
  if (at != nullptr && at->line > 0) full += fmt::format(" (line {})", at->line);
  throw InputError(m_file, key, full);
}

std::string Reader::describe(const Value& v) const {
  switch (v.type) {
    case Value::Type::Null: return "null";
    case Value::Type::Boolean: return v.boolean ? "a boolean (true)" : "a boolean (false)";
    case Value::Type::Integer: return fmt::format("an integer ({})", v.integer);
    case Value::Type::Float: return fmt::format("a floating-point number ({})", v.number);
    case Value::Type::String: return fmt::format("a string (\"{}\")", v.text);
    case Value::Type::Array:
      return fmt::format("an array of {} element{}", v.items.size(), v.items.size() == 1 ? "" : "s");
    case Value::Type::Table: return m_json ? "an object" : "a table";
    case Value::Type::Other: return v.text;
  }
  return "an unknown value";
}

std::string Reader::table_array_word(std::string_view name) const {
  if (m_json) return "an array of objects";
  return fmt::format("an array of tables ([[{}]])", name);
}

std::string Reader::table_word() const { return m_json ? "an object" : "a table"; }

void Reader::check_keys(const Value& table, const std::string& path, const Keys& known,
                        const std::vector<KeyHint>& hints) const {
  const Value* first_bad = nullptr;
  std::size_t first_index = 0;
  for (std::size_t i = 0; i < table.keys.size(); ++i) {
    if (std::find(known.begin(), known.end(), table.keys[i]) != known.end()) continue;
    const Value* v = &table.items[i];
    if (first_bad == nullptr || (v->line > 0 && v->line < first_bad->line)) {
      first_bad = v;
      first_index = i;
    }
  }
  if (first_bad == nullptr) return;
  const std::string& key = table.keys[first_index];
  for (const KeyHint& hint : hints) {
    if (hint.key == key) fail(join(path, key), std::string(hint.message), first_bad);
  }
  std::string message = fmt::format("unknown key \"{}\"", key);
  if (auto best = closest(key, known)) {
    message += fmt::format(" (did you mean \"{}\"?)", *best);
  } else {
    message += fmt::format("; allowed keys here: {}", list_names(known));
  }
  const Keys top_level = schema_keys("top");
  if (!m_json && !path.empty() && std::find(top_level.begin(), top_level.end(), key) != top_level.end()) {
    message += "; a top-level key must be written before the first [table] header";
  }
  fail(join(path, key), message, first_bad);
}

const Value& Reader::require(const Value& table, const std::string& path, std::string_view key,
                             std::string_view expected) const {
  if (const Value* v = find(table, key)) return *v;
  fail(join(path, key), fmt::format("missing required key (expected {})", expected), &table);
}

const Value& Reader::require_key(const Value& table, const std::string& path, std::string_view section,
                                 std::string_view key) const {
  const std::string_view expected = schema_key(section, key).expected;
  if (expected.empty())
    throw std::logic_error(fmt::format("case schema: {}.{} declares no expected value", section, key));
  std::string text(expected);
  if (text.starts_with("@tables")) text = table_array_word(key) + text.substr(7);
  else if (text.starts_with("@table")) text = table_word() + text.substr(6);
  return require(table, path, key, text);
}

double Reader::to_number(const Value& v, const std::string& key) const {
  double x = 0;
  if (v.type == Value::Type::Integer) {
    x = static_cast<double>(v.integer);
  } else if (v.type == Value::Type::Float) {
    x = v.number;
  } else {
    fail(key, fmt::format("expected a number, got {}", describe(v)), &v);
  }
  if (!std::isfinite(x)) fail(key, fmt::format("expected a finite number, got {}", x), &v);
  return x;
}

std::int64_t Reader::to_integer(const Value& v, const std::string& key) const {
  if (v.type == Value::Type::Integer) return v.integer;
  if (v.type == Value::Type::Float && std::isfinite(v.number) && v.number == std::trunc(v.number)) {
    fail(key,
         fmt::format("expected an integer, got the floating-point number {} (write it without "
                     "a decimal point or exponent)",
                     v.number),
         &v);
  }
  fail(key, fmt::format("expected an integer, got {}", describe(v)), &v);
}

int Reader::to_int(const Value& v, const std::string& key, int minimum) const {
  const std::int64_t i = to_integer(v, key);
  if (i < minimum) fail(key, fmt::format("must be >= {}, got {}", minimum, i), &v);
  if (i > INT_MAX) fail(key, fmt::format("must be <= {}, got {}", INT_MAX, i), &v);
  return static_cast<int>(i);
}

std::string Reader::to_string(const Value& v, const std::string& key) const {
  if (v.type != Value::Type::String) fail(key, fmt::format("expected a string, got {}", describe(v)), &v);
  return v.text;
}

std::string Reader::one_of(const Value& v, const std::string& key, const Keys& words) const {
  std::string text = to_string(v, key);
  if (std::find(words.begin(), words.end(), text) != words.end()) return text;
  std::string list;
  for (std::size_t i = 0; i < words.size(); ++i)
    list += fmt::format("{}\"{}\"", i == 0 ? "" : i + 1 == words.size() ? " or " : ", ", words[i]);
  fail(key, fmt::format("expected {}, got \"{}\"{}", list, text, did_you_mean(text, words)), &v);
}

std::string Reader::to_name(const Value& v, const std::string& key) const {
  std::string name = to_string(v, key);
  if (name.empty()) fail(key, "expected a non-empty name, got an empty string", &v);
  return name;
}

bool Reader::to_bool(const Value& v, const std::string& key) const {
  if (v.type != Value::Type::Boolean) {
    fail(key, fmt::format("expected a boolean (true or false), got {}", describe(v)), &v);
  }
  return v.boolean;
}

std::vector<double> Reader::to_numbers(const Value& v, const std::string& key, std::size_t n) const {
  const std::string expected = fmt::format("expected an array of {} numbers", n);
  if (v.type != Value::Type::Array) fail(key, fmt::format("{}, got {}", expected, describe(v)), &v);
  if (v.items.size() != n) {
    fail(key, fmt::format("{}, got {}", expected, describe(v)), &v);
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) {
    const Value& e = v.items[i];
    if (e.type == Value::Type::Integer) {
      out.push_back(static_cast<double>(e.integer));
    } else if (e.type == Value::Type::Float) {
      if (!std::isfinite(e.number)) {
        fail(key, fmt::format("{} (finite), element {} is {}", expected, i, e.number), &v);
      }
      out.push_back(e.number);
    } else {
      fail(key, fmt::format("{}, element {} is {}", expected, i, describe(e)), &v);
    }
  }
  return out;
}

Vec3 Reader::to_vec3(const Value& v, const std::string& key) const {
  const std::vector<double> x = to_numbers(v, key, 3);
  return Vec3(x[0], x[1], x[2]);
}

Vec3 Reader::to_direction(const Value& v, const std::string& key) const {
  const Vec3 d = to_vec3(v, key);
  if (!(d.norm() > 0)) fail(key, "expected a nonzero vector, got [0, 0, 0]", &v);
  return d.normalized();
}

void Reader::expect_table(const Value& v, const std::string& key) const {
  if (v.type != Value::Type::Table) {
    fail(key, fmt::format("expected {}, got {}", table_word(), describe(v)), &v);
  }
}

const std::vector<Value>& Reader::to_table_array(const Value& v, const std::string& key,
                                                 std::string_view name) const {
  if (v.type != Value::Type::Array) {
    fail(key, fmt::format("expected {}, got {}", table_array_word(name), describe(v)), &v);
  }
  for (std::size_t i = 0; i < v.items.size(); ++i) {
    if (v.items[i].type != Value::Type::Table) {
      fail(item(key, i), fmt::format("expected {}, got {}", table_word(), describe(v.items[i])),
           &v.items[i]);
    }
  }
  return v.items;
}

double Reader::positive(const Value& v, const std::string& key) const {
  const double x = to_number(v, key);
  if (!(x > 0)) fail(key, fmt::format("must be > 0, got {}", x), &v);
  return x;
}

void Reader::read_bounded(const Value& t, const std::string& path, std::string_view section, std::string_view name,
                          double& out) const {
  const Value* v = find(t, name);
  if (v == nullptr) return;
  const KeySpec& spec = schema_key(section, name);
  if (!spec.bounded() || spec.minimum != 0)
    throw std::logic_error(fmt::format("read_bounded: {}.{} is not a number > 0 or >= 0", section, name));
  const std::string key = join(path, name);
  if (spec.exclusive) {
    out = positive(*v, key);
    return;
  }
  out = to_number(*v, key);
  if (!(out >= 0)) fail(key, fmt::format("expected a number >= 0, got {}", out), v);
}

void Reader::read_bounded(const Value& t, const std::string& path, std::string_view section, std::string_view name,
                          int& out) const {
  const Value* v = find(t, name);
  if (v == nullptr) return;
  const KeySpec& spec = schema_key(section, name);
  if (!spec.bounded() || spec.exclusive)
    throw std::logic_error(fmt::format("read_bounded: {}.{} is not an integer >= a minimum", section, name));
  out = to_int(*v, join(path, name), static_cast<int>(spec.minimum));
}

double Reader::fraction(const Value& v, const std::string& key, const char* relative_to) const {
  const double x = to_number(v, key);
  if (!(x > 0 && x < 1)) fail(key, fmt::format("expected a number in (0, 1) (relative to {}), got {}", relative_to, x), &v);
  return x;
}

std::array<std::optional<double>, 3> Reader::to_components(const Value& v, const std::string& key) const {
  const std::string expected = "expected an array of 3 components, each a number or \"free\"";
  if (v.type != Value::Type::Array || v.items.size() != 3) {
    fail(key, fmt::format("{}, got {}", expected, describe(v)), &v);
  }
  std::array<std::optional<double>, 3> out;
  for (std::size_t i = 0; i < 3; ++i) {
    const Value& e = v.items[i];
    if (e.type == Value::Type::String && e.text == "free") continue;
    if (e.type == Value::Type::String) {
      const Keys words = {"free"};
      fail(key, fmt::format("{}, element {} is {}{}", expected, i, describe(e), did_you_mean(e.text, words)),
           &v);
    }
    if (e.type != Value::Type::Integer && e.type != Value::Type::Float) {
      fail(key, fmt::format("{}, element {} is {}", expected, i, describe(e)), &v);
    }
    const double x = e.type == Value::Type::Integer ? static_cast<double>(e.integer) : e.number;
    if (!std::isfinite(x)) fail(key, fmt::format("{}, element {} is {}", expected, i, x), &v);
    out[i] = x;
  }
  return out;
}

void Reader::expect_body(const std::string& name, const Value& v, const std::string& key,
                         const std::vector<BodySpec>& bodies) const {
  for (const BodySpec& b : bodies) {
    if (b.name == name) return;
  }
  std::vector<std::string> names;
  for (const BodySpec& b : bodies) names.push_back(b.name);
  if (names.empty()) {
    fail(key, fmt::format("no body named \"{}\": no {} is defined", name, m_json ? "body" : "[[body]]"),
         &v);
  }
  fail(key,
       fmt::format("no body named \"{}\"{}; defined bodies: {}", name, did_you_mean(name, names),
                   list_some_names(names)),
       &v);
}

const FiberSpec& Reader::expect_fiber(const std::string& name, const Value& v, const std::string& key,
                                      const std::vector<FiberSpec>& fibers) const {
  for (const FiberSpec& f : fibers) {
    if (f.name == name) return f;
  }
  std::vector<std::string> names;
  for (const FiberSpec& f : fibers) names.push_back(f.name);
  fail(key,
       fmt::format("no fiber named \"{}\"{}; defined fibers: {}", name, did_you_mean(name, names),
                   list_some_names(names)),
       &v);
}

void Reader::expect_material(const std::string& name, const Value& v, const std::string& key,
                             const std::vector<MaterialSpec>& materials) const {
  std::vector<std::string> names;
  for (const MaterialSpec& m : materials) {
    if (m.name == name) return;
    names.push_back(m.name);
  }
  fail(key,
       fmt::format("no material named \"{}\"{}; defined materials: {}", name, did_you_mean(name, names),
                   list_names(names)),
       &v);
}

Case Reader::read(const Value& root) const {
  check_keys(root, "", schema_keys("top"));
  if (const Value* start = find(root, "start")) return read_continued(root, *start);
  Case c;
  c.file = m_file;  // expand_fabric names it in its messages
  if (const Value* v = find(root, "title")) c.title = to_string(*v, "title");

  // Materials.
  {
    const Value& v = require_key(root, "", "top", "material");
    const std::vector<Value>& tables = to_table_array(v, "material", "material");
    if (tables.empty()) fail("material", "at least one material is required", &v);
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const std::string path = item("material", i);
      MaterialSpec m = read_material(tables[i], path);
      for (std::size_t j = 0; j < c.materials.size(); ++j) {
        if (c.materials[j].name == m.name) {
          fail(join(path, "name"),
               fmt::format("duplicate material name \"{}\" (already used by material[{}])", m.name, j),
               find(tables[i], "name"));
        }
      }
      c.materials.push_back(std::move(m));
    }
  }

  // A woven fabric (optional), expanded into fibers, bodies, bindings and tows below.
  if (const Value* v = find(root, "fabric")) {
    c.fabric = read_fabric(*v, "fabric", c.materials);
    check_fabric_size(*v, "fabric", *c.fabric);
  }
  const std::string fabric_word = m_json ? "a fabric object" : "a [fabric]";

  // Fibers: at least one, unless a [fabric] makes them.
  const Value* fiber_value = find(root, "fiber");
  if (fiber_value == nullptr && !c.fabric) {
    fail("fiber", fmt::format("missing required key (expected {}, or {})", table_array_word("fiber"), fabric_word),
         &root);
  }
  if (fiber_value != nullptr) {
    const std::vector<Value>& tables = to_table_array(*fiber_value, "fiber", "fiber");
    if (tables.empty() && !c.fabric) {
      fail("fiber", fmt::format("at least one fiber (or {}) is required", fabric_word), fiber_value);
    }
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const std::string path = item("fiber", i);
      FiberSpec f = read_fiber(tables[i], path, c.materials);
      for (std::size_t j = 0; j < c.fibers.size(); ++j) {
        if (c.fibers[j].name == f.name) {
          fail(join(path, "name"),
               fmt::format("duplicate fiber name \"{}\" (already used by fiber[{}])", f.name, j),
               find(tables[i], "name"));
        }
      }
      c.fibers.push_back(std::move(f));
    }
  }

  // Rigid bodies (optional), before the bindings and steps that refer to them.
  if (const Value* v = find(root, "body")) {
    const std::vector<Value>& tables = to_table_array(*v, "body", "body");
    for (std::size_t i = 0; i < tables.size(); ++i) {
      const std::string path = item("body", i);
      BodySpec b = read_body(tables[i], path);
      for (std::size_t j = 0; j < c.bodies.size(); ++j) {
        if (c.bodies[j].name == b.name) {
          fail(join(path, "name"),
               fmt::format("duplicate body name \"{}\" (already used by body[{}])", b.name, j),
               find(tables[i], "name"));
        }
      }
      c.bodies.push_back(std::move(b));
    }
  }

  // The whole model, the file's fibers and bodies with the fabric's, before the fabric is
  // expanded below.
  {
    const ModelSize own = case_size(c);
    const ModelSize fabric = c.fabric ? fabric_size(*c.fabric) : ModelSize{};
    ModelSize size = own;
    size += fabric;
    if (const std::string why = size_excess(size, m_limits); !why.empty()) {
      const bool fibers = !c.fibers.empty();
      fail(fibers ? "fiber" : "body",
           fmt::format("the {} {} of the file ({:.6g} elements in all{}) make a model too large to run: {}",
                       fibers ? c.fibers.size() : c.bodies.size(), fibers ? "fibers" : "bodies", own.elements,
                       c.fabric ? fmt::format(", with the fabric's {:.6g}", fabric.elements) : std::string(), why),
           fibers ? fiber_value : find(root, "body"));
    }
  }

  // What the fabric generates, so that fixes, bindings, tows and steps may name its fibers and
  // bodies: the fabric expanded alone (expand_fabric appends the same entities to `c` at the end).
  Case generated;
  generated.file = m_file;
  if (c.fabric) {
    generated.materials = c.materials;
    generated.fabric = c.fabric;
    expand_fabric(generated);
    const auto clash = [&](const auto& user, const auto& made, const char* what, const char* naming) {
      std::unordered_set<std::string> names;
      for (const auto& x : made) names.insert(x.name);
      const Value* tables = find(root, what);
      for (std::size_t i = 0; i < user.size(); ++i) {
        if (names.count(user[i].name) == 0) continue;
        const Value* at = tables != nullptr && i < tables->items.size() ? find(tables->items[i], "name") : nullptr;
        fail(join(item(what, i), "name"),
             fmt::format("{} name \"{}\" is also the name of a {} the [fabric] generates ({})", what, user[i].name,
                         what, naming),
             at);
      }
    };
    clash(c.fibers, generated.fibers, "fiber", "fibers warp<i>.f<k> and weft<j>.f<k>");
    clash(c.bodies, generated.bodies, "body",
          "bodies warp<i>.start, warp<i>.end, weft<j>.start, weft<j>.end and edge.x-, edge.x+, edge.y-, edge.y+");
  }
  std::vector<FiberSpec> all_fibers = c.fibers;
  all_fibers.insert(all_fibers.end(), generated.fibers.begin(), generated.fibers.end());
  std::vector<BodySpec> all_bodies = c.bodies;
  all_bodies.insert(all_bodies.end(), generated.bodies.begin(), generated.bodies.end());

  // Fixes (optional).
  if (const Value* v = find(root, "fix")) {
    const std::vector<Value>& tables = to_table_array(*v, "fix", "fix");
    for (std::size_t i = 0; i < tables.size(); ++i) {
      c.fixes.push_back(read_fix(tables[i], item("fix", i), all_fibers));
    }
  }

  // Averaged bindings (optional), checked together with those the fabric generates.
  if (const Value* v = find(root, "binding")) {
    const std::vector<Value>& tables = to_table_array(*v, "binding", "binding");
    std::vector<BindingSpec> earlier = generated.bindings;
    for (std::size_t i = 0; i < tables.size(); ++i) {
      BindingSpec b = read_binding(tables[i], item("binding", i), i, all_fibers, all_bodies, earlier,
                                   generated.bindings.size());
      earlier.push_back(b);
      c.bindings.push_back(std::move(b));
    }
  }

  // Tows (optional), checked together with those the fabric generates.
  if (const Value* v = find(root, "tow")) {
    const std::vector<Value>& tables = to_table_array(*v, "tow", "tow");
    std::vector<TowSpec> earlier = generated.tows;
    for (std::size_t i = 0; i < tables.size(); ++i) {
      TowSpec t = read_tow(tables[i], item("tow", i), all_fibers, earlier, generated.tows.size());
      earlier.push_back(t);
      c.tows.push_back(std::move(t));
    }
  }

  // The weave pattern of the tows (optional; a [fabric] has its own).
  if (const Value* v = find(root, "weave")) {
    if (c.fabric) {
      fail("weave",
           fmt::format("the weave of {} is its pattern or matrix: remove the {}", fabric_word,
                       m_json ? "weave object" : "[weave] table"),
           v);
    }
    expect_table(*v, "weave");
    check_keys(*v, "weave", schema_keys("weave"));
    const Value* matrix = find(*v, "matrix");
    const Value* pattern = find(*v, "pattern");
    if (matrix && pattern) fail("weave", "give either pattern or matrix, not both", v);
    if (!matrix && !pattern) {
      fail("weave.matrix",
           "missing the weave: give matrix (the repeat: rows = wefts, columns = warps, 1 = warp above) or pattern "
           "(\"plain\", \"twill 2/1\", \"satin 5\", ...)",
           v);
    }
    std::string name;
    c.weave = matrix ? to_weave_matrix(*matrix, "weave.matrix") : to_named_weave(*pattern, "weave.pattern", name);
  }

  read_steps(root, c, all_fibers, all_bodies);

  if (const Value* v = find(root, "solver")) c.solver = read_solver(*v, "solver");
  if (const Value* v = find(root, "output")) c.output = read_output(*v, "output");
  if (const Value* v = find(root, "contact")) c.contact = read_contact(*v, "contact");

  // Last: the fabric's fibers, bodies, bindings, tows and weave, and the edges' conditions in
  // the first step (for the edges no step lists).
  if (c.fabric) expand_fabric(c);
  return c;
}


/// Validates `root` and fills in the file and name of the case.
Case finish(const Value& root, const std::string& file_label, bool json, const SizeLimits& limits) {
  Case c = Reader(file_label, json, limits).read(root);
  c.file = file_label;
  c.name = std::filesystem::path(file_label).stem().string();
  return c;
}
}  // namespace fibra::case_file
