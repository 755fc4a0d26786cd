#include "fibra/io/case_reader.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>
#include <toml++/toml.h>
#include <unordered_set>
#include <utility>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/model/fabric.hpp"
#include "fibra/model/model.hpp"

namespace fibra {
namespace {

// ------------------------------------------------------------------------------------------
// A small generic document tree. TOML and JSON are both converted to it, so the schema is
// checked once, in Reader below.

/// One value of a parsed case file.
struct Value {
  enum class Type { Null, Boolean, Integer, Float, String, Array, Table, Other };
  Type type = Type::Null;
  bool boolean = false;
  std::int64_t integer = 0;
  double number = 0;
  std::string text;               ///< String contents; for Other, a description ("a date")
  std::vector<Value> items;       ///< Array elements, or Table values (parallel to keys)
  std::vector<std::string> keys;  ///< Table keys, in file order for JSON
  int line = 0;                   ///< source line (TOML only), 0 when unknown
};

/// The value stored under `key` in a Table, or nullptr.
const Value* find(const Value& table, std::string_view key) {
  for (std::size_t i = 0; i < table.keys.size(); ++i) {
    if (table.keys[i] == key) return &table.items[i];
  }
  return nullptr;
}

/// Converts a toml++ node (recursively) to the generic tree.
Value from_toml(const toml::node& node) {
  Value value;
  value.line = static_cast<int>(node.source().begin.line);
  switch (node.type()) {
    case toml::node_type::table:
      value.type = Value::Type::Table;
      for (auto&& [key, child] : *node.as_table()) {
        value.keys.emplace_back(key.str());
        value.items.push_back(from_toml(child));
      }
      break;
    case toml::node_type::array:
      value.type = Value::Type::Array;
      for (auto&& child : *node.as_array()) value.items.push_back(from_toml(child));
      break;
    case toml::node_type::string:
      value.type = Value::Type::String;
      value.text = node.as_string()->get();
      break;
    case toml::node_type::integer:
      value.type = Value::Type::Integer;
      value.integer = node.as_integer()->get();
      break;
    case toml::node_type::floating_point:
      value.type = Value::Type::Float;
      value.number = node.as_floating_point()->get();
      break;
    case toml::node_type::boolean:
      value.type = Value::Type::Boolean;
      value.boolean = node.as_boolean()->get();
      break;
    case toml::node_type::date:
      value.type = Value::Type::Other;
      value.text = "a date";
      break;
    case toml::node_type::time:
      value.type = Value::Type::Other;
      value.text = "a time";
      break;
    case toml::node_type::date_time:
      value.type = Value::Type::Other;
      value.text = "a date-time";
      break;
    default:
      value.type = Value::Type::Null;
      break;
  }
  return value;
}

/// SAX handler building the generic tree from JSON; rejects duplicate keys.
class JsonBuilder {
 public:
  using number_integer_t = nlohmann::json::number_integer_t;
  using number_unsigned_t = nlohmann::json::number_unsigned_t;
  using number_float_t = nlohmann::json::number_float_t;
  using string_t = nlohmann::json::string_t;
  using binary_t = nlohmann::json::binary_t;

  bool null() { return add(Value{}); }
  bool boolean(bool b) {
    Value v;
    v.type = Value::Type::Boolean;
    v.boolean = b;
    return add(std::move(v));
  }
  bool number_integer(number_integer_t i) {
    Value v;
    v.type = Value::Type::Integer;
    v.integer = i;
    return add(std::move(v));
  }
  bool number_unsigned(number_unsigned_t u) {
    Value v;
    if (u <= static_cast<number_unsigned_t>(INT64_MAX)) {
      v.type = Value::Type::Integer;
      v.integer = static_cast<std::int64_t>(u);
    } else {
      v.type = Value::Type::Float;
      v.number = static_cast<double>(u);
    }
    return add(std::move(v));
  }
  bool number_float(number_float_t x, const string_t& /*text*/) {
    Value v;
    v.type = Value::Type::Float;
    v.number = x;
    return add(std::move(v));
  }
  bool string(string_t& s) {
    Value v;
    v.type = Value::Type::String;
    v.text = s;
    return add(std::move(v));
  }
  bool binary(binary_t& /*b*/) {
    Value v;
    v.type = Value::Type::Other;
    v.text = "binary data";
    return add(std::move(v));
  }
  bool start_object(std::size_t /*elements*/) {
    if (too_deep()) return false;
    Value v;
    v.type = Value::Type::Table;
    m_stack.push_back(Frame{std::move(v), next_path()});
    return true;
  }
  bool end_object() { return end_container(); }
  bool start_array(std::size_t /*elements*/) {
    if (too_deep()) return false;
    Value v;
    v.type = Value::Type::Array;
    m_stack.push_back(Frame{std::move(v), next_path()});
    return true;
  }
  bool end_array() { return end_container(); }
  bool key(string_t& k) {
    Frame& frame = m_stack.back();
    if (find(frame.value, k) != nullptr) {
      m_error_key = frame.path.empty() ? k : frame.path + "." + k;
      m_error = "duplicate key";
      return false;
    }
    frame.value.keys.push_back(k);
    return true;
  }
  bool parse_error(std::size_t position, const std::string& last_token, const nlohmann::json::exception& ex) {
    m_error_position = position;
    // A number beyond the range of a double (1e999): the value's key, as for inf and nan.
    if (dynamic_cast<const nlohmann::json::out_of_range*>(&ex) != nullptr && !m_stack.empty()) {
      m_error_key = next_path();
      m_error = fmt::format("expected a finite number, got {}, beyond the largest double (about 1.8e308)",
                            last_token);
      return false;
    }
    std::string message = ex.what();
    // Drop the "[json.exception.parse_error.101] " prefix.
    if (auto end = message.find("] "); !message.empty() && message[0] == '[' &&
                                       end != std::string::npos) {
      message.erase(0, end + 2);
    }
    m_error_key = "(file)";
    m_error = "JSON syntax error: " + message;
    return false;
  }

  Value& root() { return m_root; }                        ///< the document
  const std::string& error() const { return m_error; }    ///< why parsing stopped
  const std::string& error_key() const { return m_error_key; }
  /// The byte offset where parsing stopped, when it stopped on the text (0 otherwise).
  std::size_t error_position() const { return m_error_position; }
  /// Containers nest at most this deep (as in TOML files).
  static constexpr std::size_t kMaxDepth = 256;

 private:
  bool too_deep() {
    if (m_stack.size() < kMaxDepth) return false;
    // The key of the outermost container (a whole path would be kMaxDepth indices long).
    m_error_key = m_stack.size() > 1 && !m_stack[1].path.empty() ? m_stack[1].path : "(file)";
    m_error = fmt::format("arrays and objects nested deeper than {} levels", kMaxDepth);
    return true;
  }

  struct Frame {
    Value value;
    std::string path;
  };

  std::string next_path() const {
    if (m_stack.empty()) return "";
    const Frame& top = m_stack.back();
    if (top.value.type == Value::Type::Table) {
      const std::string& k = top.value.keys.back();
      return top.path.empty() ? k : top.path + "." + k;
    }
    return fmt::format("{}[{}]", top.path, top.value.items.size());
  }
  bool end_container() {
    Value v = std::move(m_stack.back().value);
    m_stack.pop_back();
    return add(std::move(v));
  }
  bool add(Value v) {
    if (m_stack.empty()) {
      m_root = std::move(v);
    } else {
      m_stack.back().value.items.push_back(std::move(v));
    }
    return true;
  }

  std::vector<Frame> m_stack;
  Value m_root;
  std::string m_error;
  std::string m_error_key;
  std::size_t m_error_position = 0;
};

// ------------------------------------------------------------------------------------------
// Key paths and spelling suggestions.

std::string join(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string item(const std::string& path, std::size_t i) { return fmt::format("{}[{}]", path, i); }

std::string lowercase(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// Case-insensitive edit distance counting adjacent transpositions as one edit.
std::size_t edit_distance(std::string_view a_in, std::string_view b_in) {
  const std::string a = lowercase(a_in);
  const std::string b = lowercase(b_in);
  const std::size_t n = a.size();
  const std::size_t m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

/// The candidate closest to `word`, when it is close enough to be a likely misspelling.
template <class Range>
std::optional<std::string> closest(std::string_view word, const Range& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = SIZE_MAX;
  const std::string lower_word = lowercase(word);
  for (const auto& candidate_in : candidates) {
    const std::string_view candidate(candidate_in);
    const std::size_t distance = edit_distance(word, candidate);
    const std::size_t threshold = std::max<std::size_t>(1, (candidate.size() + 1) / 3);
    const std::string lower_candidate = lowercase(candidate);
    const std::size_t shorter = std::min(lower_word.size(), lower_candidate.size());
    const bool prefix = shorter >= 3 && lower_word.compare(0, shorter, lower_candidate, 0, shorter) == 0;
    if ((distance <= threshold || prefix) && distance < best_distance) {
      best = std::string(candidate);
      best_distance = distance;
    }
  }
  return best;
}

/// " (did you mean "x"?)" or "".
template <class Range>
std::string did_you_mean(std::string_view word, const Range& candidates) {
  if (auto best = closest(word, candidates)) return fmt::format(" (did you mean \"{}\"?)", *best);
  return "";
}

/// "a, b, c" for a list of names.
template <class Range>
std::string list_names(const Range& names) {
  std::string out;
  for (const auto& name : names) {
    if (!out.empty()) out += ", ";
    out += std::string_view(name);
  }
  return out;
}

/// Lists of names longer than this are given only in part in messages.
constexpr std::size_t kListedNames = 20;

/// "a, b, c" for at most kListedNames names, then "... (N in all)".
template <class Range>
std::string list_some_names(const Range& names) {
  std::string out;
  std::size_t count = 0;
  for (const auto& name : names) {
    if (count++ >= kListedNames) continue;
    if (!out.empty()) out += ", ";
    out += std::string_view(name);
  }
  if (count > kListedNames) out += fmt::format(", ... ({} in all)", count);
  return out;
}

constexpr double kDegree = std::numbers::pi / 180.0;

/// A key allowed only in another variant of a table, with the message explaining why.
struct KeyHint {
  std::string_view key;
  std::string_view message;
};

using Keys = std::vector<std::string_view>;

/// The keys of the top level of a case file.
const Keys kTopLevelKeys = {"title", "material", "fiber",  "fabric",  "fix",    "body",  "binding",
                            "tow",   "weave",    "start", "step",    "solver", "contact", "output"};
// The model keys: a case with [start] takes its model from the earlier run instead.
const Keys kModelKeys = {"material", "fiber", "fabric", "fix", "body", "binding", "tow", "weave"};

/// The first words of the named weave patterns (model/fabric.hpp), for suggestions.
const Keys kWeaveWords = {"plain", "twill", "basket", "satin"};

// ------------------------------------------------------------------------------------------
// Schema validation, written once for both formats.

class Reader {
 public:
  Reader(std::string file, bool json, SizeLimits limits)
      : m_file(std::move(file)), m_json(json), m_limits(limits) {}

  Case read(const Value& root) const;

 private:
  /// [[step]]: names checked against every fiber and body (generated ones included).
  void read_steps(const Value& root, Case& c, const std::vector<FiberSpec>& all_fibers,
                  const std::vector<BodySpec>& all_bodies) const;
  /// A case with [start]: the model of an earlier run's result directory (its case.toml), its
  /// state at the end of its last step, and this file's steps (solver, contact and output
  /// settings replace the earlier run's when given).
  Case read_continued(const Value& root, const Value& start) const;
  [[noreturn]] void fail(const std::string& key, const std::string& message, const Value* at) const {
    std::string full = message;
    if (at != nullptr && at->line > 0) full += fmt::format(" (line {})", at->line);
    throw InputError(m_file, key, full);
  }

  std::string describe(const Value& v) const {
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

  /// "an array of tables ([[fiber]])" or "an array of objects".
  std::string table_array_word(std::string_view name) const {
    if (m_json) return "an array of objects";
    return fmt::format("an array of tables ([[{}]])", name);
  }

  std::string table_word() const { return m_json ? "an object" : "a table"; }

  // -- tables --------------------------------------------------------------------------

  /// Fails on the first key of `table` that is not in `known`.
  void check_keys(const Value& table, const std::string& path, const Keys& known,
                  const std::vector<KeyHint>& hints = {}) const {
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
    if (!m_json && !path.empty() &&
        std::find(kTopLevelKeys.begin(), kTopLevelKeys.end(), key) != kTopLevelKeys.end()) {
      message += "; a top-level key must be written before the first [table] header";
    }
    fail(join(path, key), message, first_bad);
  }

  const Value& require(const Value& table, const std::string& path, std::string_view key,
                       std::string_view expected) const {
    if (const Value* v = find(table, key)) return *v;
    fail(join(path, key), fmt::format("missing required key (expected {})", expected), &table);
  }

  // -- conversions ---------------------------------------------------------------------

  double to_number(const Value& v, const std::string& key) const {
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

  std::int64_t to_integer(const Value& v, const std::string& key) const {
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

  int to_int(const Value& v, const std::string& key, int minimum) const {
    const std::int64_t i = to_integer(v, key);
    if (i < minimum) fail(key, fmt::format("must be >= {}, got {}", minimum, i), &v);
    if (i > INT_MAX) fail(key, fmt::format("must be <= {}, got {}", INT_MAX, i), &v);
    return static_cast<int>(i);
  }

  std::string to_string(const Value& v, const std::string& key) const {
    if (v.type != Value::Type::String) fail(key, fmt::format("expected a string, got {}", describe(v)), &v);
    return v.text;
  }

  /// A string that must be one of `words`: `expected "a", "b" or "c", got "x"` otherwise, with
  /// the nearest word suggested.
  std::string one_of(const Value& v, const std::string& key, const Keys& words) const {
    std::string text = to_string(v, key);
    if (std::find(words.begin(), words.end(), text) != words.end()) return text;
    std::string list;
    for (std::size_t i = 0; i < words.size(); ++i)
      list += fmt::format("{}\"{}\"", i == 0 ? "" : i + 1 == words.size() ? " or " : ", ", words[i]);
    fail(key, fmt::format("expected {}, got \"{}\"{}", list, text, did_you_mean(text, words)), &v);
  }

  std::string to_name(const Value& v, const std::string& key) const {
    std::string name = to_string(v, key);
    if (name.empty()) fail(key, "expected a non-empty name, got an empty string", &v);
    return name;
  }

  bool to_bool(const Value& v, const std::string& key) const {
    if (v.type != Value::Type::Boolean) {
      fail(key, fmt::format("expected a boolean (true or false), got {}", describe(v)), &v);
    }
    return v.boolean;
  }

  std::vector<double> to_numbers(const Value& v, const std::string& key, std::size_t n) const {
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

  Vec3 to_vec3(const Value& v, const std::string& key) const {
    const std::vector<double> x = to_numbers(v, key, 3);
    return Vec3(x[0], x[1], x[2]);
  }

  Vec3 to_direction(const Value& v, const std::string& key) const {
    const Vec3 d = to_vec3(v, key);
    if (!(d.norm() > 0)) fail(key, "expected a nonzero vector, got [0, 0, 0]", &v);
    return d.normalized();
  }

  void expect_table(const Value& v, const std::string& key) const {
    if (v.type != Value::Type::Table) {
      fail(key, fmt::format("expected {}, got {}", table_word(), describe(v)), &v);
    }
  }

  const std::vector<Value>& to_table_array(const Value& v, const std::string& key,
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

  double positive(const Value& v, const std::string& key) const {
    const double x = to_number(v, key);
    if (!(x > 0)) fail(key, fmt::format("must be > 0, got {}", x), &v);
    return x;
  }

  /// A relative tolerance in (0, 1); `relative_to` says what it is relative to (for the message).
  double fraction(const Value& v, const std::string& key, const char* relative_to) const {
    const double x = to_number(v, key);
    if (!(x > 0 && x < 1)) fail(key, fmt::format("expected a number in (0, 1) (relative to {}), got {}", relative_to, x), &v);
    return x;
  }

  /// An array of 3 components, each a number (prescribed) or "free" (std::nullopt).
  std::array<std::optional<double>, 3> to_components(const Value& v, const std::string& key) const {
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

  /// Checks that `name`, read from `v` at `key`, is the name of one of `bodies`.
  void expect_body(const std::string& name, const Value& v, const std::string& key,
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

  /// The fiber named `name`, read from `v` at `key`; fails naming the closest defined fiber.
  const FiberSpec& expect_fiber(const std::string& name, const Value& v, const std::string& key,
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

  /// Checks that `name`, read from `v` at `key`, is the name of one of `materials`.
  void expect_material(const std::string& name, const Value& v, const std::string& key,
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

  /// A weave repeat written as an array of rows of 0/1 integers, checked by check_weave().
  std::vector<std::vector<int>> to_weave_matrix(const Value& v, const std::string& key) const;
  /// The repeat of a named weave pattern (named_weave()), read from the string `v` at `key`.
  std::vector<std::vector<int>> to_named_weave(const Value& v, const std::string& key, std::string& pattern) const;

  // -- sections ------------------------------------------------------------------------

  MaterialSpec read_material(const Value& t, const std::string& path) const;
  FiberSpec read_fiber(const Value& t, const std::string& path,
                       const std::vector<MaterialSpec>& materials) const;
  PathSpec read_path(const Value& t, const std::string& path) const;
  NodeRef read_node(const Value& t, const std::string& path,
                    const std::vector<FiberSpec>& fibers) const;
  FixSpec read_fix(const Value& t, const std::string& path,
                   const std::vector<FiberSpec>& fibers) const;
  BodySpec read_body(const Value& t, const std::string& path) const;
  BindingSpec read_binding(const Value& t, const std::string& path, std::size_t k,
                           const std::vector<FiberSpec>& fibers, const std::vector<BodySpec>& bodies,
                           const std::vector<BindingSpec>& earlier, std::size_t generated) const;
  StepSpec read_step(const Value& t, const std::string& path, std::size_t k,
                     const std::vector<FiberSpec>& fibers, const std::vector<BodySpec>& bodies) const;
  FabricSpec read_fabric(const Value& t, const std::string& path,
                         const std::vector<MaterialSpec>& materials) const;
  FabricDirectionSpec read_fabric_direction(const Value& fabric, const std::string& path, const char* name,
                                            const Value* shared_tow, const Value* shared_fiber,
                                            const std::vector<MaterialSpec>& materials) const;
  TowSpec read_tow(const Value& t, const std::string& path, const std::vector<FiberSpec>& fibers,
                   const std::vector<TowSpec>& earlier, std::size_t generated) const;
  BodyStepSpec read_step_body(const Value& t, const std::string& path,
                              const std::vector<BodySpec>& bodies) const;
  LoadSpec read_load(const Value& t, const std::string& path,
                     const std::vector<FiberSpec>& fibers) const;
  DisplacementSpec read_displacement(const Value& t, const std::string& path,
                                     const std::vector<FiberSpec>& fibers) const;
  SolverSpec read_solver(const Value& t, const std::string& path) const;
  OutputSpec read_output(const Value& t, const std::string& path) const;
  void read_checkpoint(const Value& v, const std::string& key, OutputSpec& o) const;
  ContactSpec read_contact(const Value& t, const std::string& path) const;

  /// Refuses the model of a [fabric] (table `t` at `path`, read into `f`) when its estimated size
  /// exceeds the limits, before it is expanded, naming the key that makes it large: the element
  /// length when the same fibers in 2 elements each would fit, else the tow or fiber count.
  void check_fabric_size(const Value& t, const std::string& path, const FabricSpec& f) const;

  std::string m_file;
  bool m_json;
  SizeLimits m_limits;
};

MaterialSpec Reader::read_material(const Value& t, const std::string& path) const {
  MaterialSpec m;
  if (const Value* v = find(t, "model"))
    m.model = one_of(*v, join(path, "model"), {"isotropic", "transverse"}) == "isotropic"
                  ? MaterialSpec::Model::Isotropic
                  : MaterialSpec::Model::Transverse;
  if (m.model == MaterialSpec::Model::Isotropic) {
    const std::string_view only = "only allowed with model = \"transverse\"";
    check_keys(t, path, {"name", "model", "young", "poisson"},
               {{"young_transverse", only}, {"shear_axial", only}, {"poisson_transverse", only}});
  } else {
    check_keys(t, path,
               {"name", "model", "young", "poisson", "young_transverse", "shear_axial",
                "poisson_transverse"});
  }

  m.name = to_name(require(t, path, "name", "a string"), join(path, "name"));
  m.young = positive(require(t, path, "young", "a number > 0 [Pa]"), join(path, "young"));
  const std::string poisson_key = join(path, "poisson");
  if (m.model == MaterialSpec::Model::Isotropic) {
    const Value& v = require(t, path, "poisson", "a number in [0, 0.5)");
    m.poisson = to_number(v, poisson_key);
    if (!(m.poisson >= 0 && m.poisson < 0.5)) {
      fail(poisson_key, fmt::format("must be in [0, 0.5) for an isotropic material, got {}", m.poisson),
           &v);
    }
    return m;
  }

  m.poisson = to_number(require(t, path, "poisson", "a number (nu_LT)"), poisson_key);
  m.young_transverse = positive(require(t, path, "young_transverse", "a number > 0 [Pa]"),
                                join(path, "young_transverse"));
  m.shear_axial =
      positive(require(t, path, "shear_axial", "a number > 0 [Pa]"), join(path, "shear_axial"));
  const std::string nu_tt_key = join(path, "poisson_transverse");
  const Value& nu_tt = require(t, path, "poisson_transverse", "a number in (-1, 1)");
  m.poisson_transverse = to_number(nu_tt, nu_tt_key);
  // The normal block of the compliance matrix (axis 3 = fiber axis) is
  //   [ 1/ET     -nuTT/ET  -nuLT/EL ]
  //   [ -nuTT/ET  1/ET     -nuLT/EL ]
  //   [ -nuLT/EL -nuLT/EL   1/EL    ]
  // with determinant (1 + nuTT)/ET * ((1 - nuTT)/(ET EL) - 2 nuLT^2/EL^2); the shear terms are
  // 1/G_LT and 2 (1 + nuTT)/ET. It is positive definite iff nuTT > -1 and
  // 1 - nuTT - 2 nuLT^2 ET/EL > 0.
  if (!(m.poisson_transverse > -1)) {
    fail(nu_tt_key,
         fmt::format("must be > -1 (otherwise the compliance matrix is not positive definite), got {}",
                     m.poisson_transverse),
         &nu_tt);
  }
  const double margin = 1 - m.poisson_transverse -
                        2 * m.poisson * m.poisson * m.young_transverse / m.young;
  if (!(margin > 0)) {
    fail(path,
         fmt::format("the compliance matrix is not positive definite: need 1 - poisson_transverse - "
                     "2 poisson^2 young_transverse / young > 0, got {}",
                     margin),
         &t);
  }
  return m;
}

PathSpec Reader::read_path(const Value& t, const std::string& path) const {
  const Value* points = find(t, "points");
  const Value* arc = find(t, "arc");
  const Value* helix = find(t, "helix");
  std::vector<std::string_view> given;
  if (points) given.push_back("points");
  if (arc) given.push_back("arc");
  if (helix) given.push_back("helix");
  if (given.empty()) {
    fail(join(path, "points"),
         "missing the fiber path: give exactly one of points (a polyline), arc or helix", &t);
  }
  if (given.size() > 1) {
    fail(path,
         fmt::format("give exactly one of points, arc or helix, not several (found {})",
                     list_names(given)),
         &t);
  }

  PathSpec p;
  if (points) {
    p.kind = PathSpec::Kind::Polyline;
    const std::string key = join(path, "points");
    if (points->type != Value::Type::Array) {
      fail(key, fmt::format("expected an array of points (arrays of 3 numbers), got {}",
                            describe(*points)),
           points);
    }
    if (points->items.size() < 2) {
      fail(key, fmt::format("expected at least 2 points, got {}", points->items.size()), points);
    }
    for (std::size_t i = 0; i < points->items.size(); ++i) {
      p.points.push_back(to_vec3(points->items[i], item(key, i)));
    }
    double extent = 0;
    for (const Vec3& x : p.points) extent = std::max(extent, (x - p.points.front()).norm());
    for (std::size_t i = 1; i < p.points.size(); ++i) {
      if (!std::isfinite((p.points[i] - p.points[i - 1]).squaredNorm())) {
        fail(item(key, i),
             fmt::format("points {} and {} are too far apart: the square of their distance overflows (give the "
                         "geometry in smaller units or nearer the origin)",
                         i - 1, i),
             &points->items[i]);
      }
      if ((p.points[i] - p.points[i - 1]).norm() <= 1e-12 * extent) {
        fail(item(key, i),
             fmt::format("points {} and {} coincide (consecutive points must be distinct)", i - 1, i),
             &points->items[i]);
      }
    }
    return p;
  }

  const bool is_arc = arc != nullptr;
  const Value& table = is_arc ? *arc : *helix;
  const std::string base = join(path, is_arc ? "arc" : "helix");
  expect_table(table, base);
  if (is_arc) {
    p.kind = PathSpec::Kind::Arc;
    check_keys(table, base, {"center", "axis", "radius", "start_angle", "angle"});
  } else {
    p.kind = PathSpec::Kind::Helix;
    check_keys(table, base, {"center", "axis", "radius", "pitch", "turns", "start_angle"});
  }
  if (const Value* v = find(table, "center")) p.center = to_vec3(*v, join(base, "center"));
  if (const Value* v = find(table, "axis")) p.axis = to_direction(*v, join(base, "axis"));
  p.radius = positive(require(table, base, "radius", "a number > 0 [m]"), join(base, "radius"));
  if (const Value* v = find(table, "start_angle")) p.start_angle = to_number(*v, join(base, "start_angle")) * kDegree;
  if (is_arc) {
    const std::string angle_key = join(base, "angle");
    const Value& angle = require(table, base, "angle", "a nonzero number of degrees");
    const double degrees = to_number(angle, angle_key);
    if (degrees == 0) fail(angle_key, "must be nonzero (the sweep of the arc, in degrees), got 0", &angle);
    p.angle = degrees * kDegree;
  } else {
    const std::string pitch_key = join(base, "pitch");
    const Value& pitch = require(table, base, "pitch", "a number >= 0 [m per turn]");
    p.pitch = to_number(pitch, pitch_key);
    if (!(p.pitch >= 0)) fail(pitch_key, fmt::format("must be >= 0, got {}", p.pitch), &pitch);
    p.turns = positive(require(table, base, "turns", "a number > 0"), join(base, "turns"));
  }
  return p;
}

FiberSpec Reader::read_fiber(const Value& t, const std::string& path,
                             const std::vector<MaterialSpec>& materials) const {
  check_keys(t, path,
             {"name", "material", "radius", "semi_axes", "section_direction", "points", "arc",
              "helix", "elements"});
  FiberSpec f;
  f.name = to_name(require(t, path, "name", "a string"), join(path, "name"));

  const std::string material_key = join(path, "material");
  const Value& material = require(t, path, "material", "a string naming a [[material]]");
  f.material = to_string(material, material_key);
  expect_material(f.material, material, material_key, materials);

  const Value* radius = find(t, "radius");
  const Value* semi_axes = find(t, "semi_axes");
  if (radius && semi_axes) fail(path, "give either radius or semi_axes, not both", &t);
  if (radius) {
    f.radius = positive(*radius, join(path, "radius"));
    f.semi_axis_1 = f.semi_axis_2 = f.radius;
  } else if (semi_axes) {
    const std::string key = join(path, "semi_axes");
    const std::vector<double> a = to_numbers(*semi_axes, key, 2);
    if (!(a[0] > 0 && a[1] > 0)) {
      fail(key, fmt::format("both semi-axes must be > 0, got [{}, {}]", a[0], a[1]), semi_axes);
    }
    f.semi_axis_1 = a[0];
    f.semi_axis_2 = a[1];
    f.radius = std::sqrt(a[0] * a[1]);
  } else {
    fail(join(path, "radius"),
         "missing the section: give radius (a number > 0) or semi_axes (an array of 2 numbers > 0)",
         &t);
  }

  f.path = read_path(t, path);

  if (const Value* v = find(t, "section_direction")) {
    const std::string key = join(path, "section_direction");
    const Vec3 d = to_direction(*v, key);
    if (f.path.kind == PathSpec::Kind::Polyline) {
      const Vec3 tangent = (f.path.points[1] - f.path.points[0]).normalized();
      if (d.cross(tangent).norm() <= 1e-8) {
        fail(key,
             "must not be parallel to the start tangent of the fiber (the first segment of points)",
             v);
      }
    }
    f.section_direction = d;
  }

  const std::string elements_key = join(path, "elements");
  const Value& elements = require(t, path, "elements", "an integer >= 1");
  f.elements = to_int(elements, elements_key, 1);
  if (const std::string why = size_excess(fiber_size(f.elements), m_limits); !why.empty())
    fail(elements_key, fmt::format("{} elements make a model too large to run: {}", f.elements, why), &elements);
  return f;
}

NodeRef Reader::read_node(const Value& t, const std::string& path,
                          const std::vector<FiberSpec>& fibers) const {
  NodeRef ref;
  const std::string fiber_key = join(path, "fiber");
  const Value& fiber = require(t, path, "fiber", "a string naming a [[fiber]]");
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
  check_keys(t, path, {"fiber", "node", "at", "dofs"});
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
  check_keys(t, path, {"fiber", "node", "at", "force", "moment"});
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
  check_keys(t, path, {"fiber", "node", "at", "value"});
  DisplacementSpec d;
  d.node = read_node(t, path, fibers);
  const std::string key = join(path, "value");
  const Value& v = require(t, path, "value", "an array of 3 components, each a number or \"free\"");
  d.value = to_components(v, key);
  const bool any = std::any_of(d.value.begin(), d.value.end(), [](const auto& x) { return x.has_value(); });
  if (!any) fail(key, "all 3 components are \"free\": at least one must be a number", &v);
  return d;
}

BodySpec Reader::read_body(const Value& t, const std::string& path) const {
  check_keys(t, path, {"name", "center", "axes"});
  BodySpec b;
  b.name = to_name(require(t, path, "name", "a string"), join(path, "name"));
  b.center = to_vec3(require(t, path, "center", "an array of 3 numbers [m]"), join(path, "center"));
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
  check_keys(t, path, {"body", "ends", "bodies", "grip", "spin"});
  BindingSpec b;
  b.line = static_cast<int>(k);
  {
    const std::string key = join(path, "body");
    const Value& v = require(t, path, "body", "a string naming a [[body]]");
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
      check_keys(ends[i], end_path, {"fiber", "node", "at"});
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
  check_keys(t, path, {"name", "displacement", "rotation", "force", "moment"});
  BodyStepSpec s;
  {
    const std::string key = join(path, "name");
    const Value& v = require(t, path, "name", "a string naming a [[body]]");
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

StepSpec Reader::read_step(const Value& t, const std::string& path, std::size_t k,
                           const std::vector<FiberSpec>& fibers, const std::vector<BodySpec>& bodies) const {
  check_keys(t, path,
             {"name", "kind", "increments", "max_increments", "load", "displacement", "body", "strain", "ratio", "angle",
              "height", "tolerance"});
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
      const Keys words = {"standard", "load", "weave", "relax", "biaxial", "shear"};
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
    if (const Value* h = find(t, "height")) step.free_height = one_of(*h, join(path, "height"), {"held", "free"}) == "free";
  }
  if (const Value* v = find(t, "tolerance")) {
    const std::string key = join(path, "tolerance");
    if (!step.is_proximal())
      fail(key, "`tolerance` belongs to relax, biaxial and shear steps (the drag force at which they settle); this "
                "step's kind is not", v);
    step.tolerance = fraction(*v, key, "the reference force");
  }
  if (const Value* v = find(t, "increments")) step.increments = to_int(*v, join(path, "increments"), 1);
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
      require(fabric, path, name, fmt::format("{} such as {{ tows = 5, spacing = 1.0e-3 }}", table_word()));
  expect_table(d, base);
  check_keys(d, base, {"tows", "spacing", "tow", "fiber"});
  FabricDirectionSpec s;
  s.tows = to_int(require(d, base, "tows", "an integer >= 1"), join(base, "tows"), 1);
  s.spacing = positive(require(d, base, "spacing", "a number > 0 [m]"), join(base, "spacing"));

  const Value* own_tow = find(d, "tow");
  const Value* own_fiber = find(d, "fiber");
  const std::string own_tow_path = join(base, "tow");
  const std::string own_fiber_path = join(base, "fiber");
  const std::string shared_tow_path = join(path, "tow");
  const std::string shared_fiber_path = join(path, "fiber");
  if (own_tow) {
    expect_table(*own_tow, own_tow_path);
    check_keys(*own_tow, own_tow_path, {"fibers", "width", "thickness"});
  }
  if (own_fiber) {
    expect_table(*own_fiber, own_fiber_path);
    check_keys(*own_fiber, own_fiber_path, {"radius", "material", "element_length"});
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
  check_keys(t, path, {"pattern", "matrix", "warp", "weft", "margin", "tension", "grip", "tow", "fiber"});
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
    check_keys(*shared_tow, base, {"fibers", "width", "thickness"});
    if (const Value* v = find(*shared_tow, "fibers")) to_int(*v, join(base, "fibers"), 1);
    if (const Value* v = find(*shared_tow, "width")) positive(*v, join(base, "width"));
    if (const Value* v = find(*shared_tow, "thickness")) positive(*v, join(base, "thickness"));
  }
  if (shared_fiber) {
    const std::string base = join(path, "fiber");
    expect_table(*shared_fiber, base);
    check_keys(*shared_fiber, base, {"radius", "material", "element_length"});
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
  check_keys(t, path, {"name", "direction", "index", "fibers"});
  // earlier[j]: the tows the [fabric] generates (j < generated), then tow[j - generated].
  const auto describe_tow = [&](std::size_t j) {
    if (j < generated) return fmt::format("tow \"{}\" (generated by the [fabric])", earlier[j].name);
    return fmt::format("tow \"{}\" (tow[{}])", earlier[j].name, j - generated);
  };
  TowSpec tow;
  {
    const std::string key = join(path, "name");
    const Value& v = require(t, path, "name", "a string");
    tow.name = to_name(v, key);
    for (std::size_t j = 0; j < earlier.size(); ++j) {
      if (earlier[j].name == tow.name) {
        fail(key, fmt::format("duplicate tow name \"{}\" (already used by {})", tow.name, describe_tow(j)), &v);
      }
    }
  }
  {
    const Value& v = require(t, path, "direction", "\"warp\" or \"weft\"");
    tow.direction = one_of(v, join(path, "direction"), {"warp", "weft"}) == "warp" ? TowSpec::Direction::Warp
                                                                                  : TowSpec::Direction::Weft;
  }
  {
    const std::string key = join(path, "index");
    const Value& v = require(t, path, "index", "an integer >= 0, the position among the tows of its direction");
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
    const Value& v = require(t, path, "fibers", "an array of fiber names");
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

SolverSpec Reader::read_solver(const Value& t, const std::string& path) const {
  expect_table(t, path);
  // Former settings of the method, now its own rules (docs/theory/solver.md): named as such,
  // not as unknown keys.
  static const Keys kRules = {"line_search", "test_predictor", "ordering", "binding_stiffness", "max_step",
                              "weave_drag", "relax_drag", "drag_axial", "test_inexact", "test_penetration_slack",
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
  check_keys(t, path,
             {"residual_tolerance", "displacement_tolerance", "max_iterations", "max_cuts", "linear_solver",
              "krylov_precision", "binding_tolerance", "max_binding_updates"});
  SolverSpec s;
  if (const Value* v = find(t, "residual_tolerance")) {
    s.residual_tolerance = positive(*v, join(path, "residual_tolerance"));
  }
  if (const Value* v = find(t, "displacement_tolerance")) {
    s.displacement_tolerance = positive(*v, join(path, "displacement_tolerance"));
  }
  if (const Value* v = find(t, "max_iterations")) {
    s.max_iterations = to_int(*v, join(path, "max_iterations"), 1);
  }
  if (const Value* v = find(t, "max_cuts")) s.max_cuts = to_int(*v, join(path, "max_cuts"), 0);
  if (const Value* v = find(t, "linear_solver"))
    s.linear_solver = one_of(*v, join(path, "linear_solver"), {"cholmod", "eigen"});
  if (const Value* v = find(t, "krylov_precision"))
    s.krylov_precision = one_of(*v, join(path, "krylov_precision"), {"auto", "single", "double"});
  if (const Value* v = find(t, "binding_tolerance")) {
    s.binding_tolerance = positive(*v, join(path, "binding_tolerance"));
  }
  if (const Value* v = find(t, "max_binding_updates")) {
    s.max_binding_updates = to_int(*v, join(path, "max_binding_updates"), 1);
  }
  return s;
}

ContactSpec Reader::read_contact(const Value& t, const std::string& path) const {
  expect_table(t, path);
  check_keys(t, path,
             {"friction", "max_penetration", "elastic_slip", "stiffness", "regularization", "margin", "spacing",
              "self_exclusion", "max_detections", "max_normal_updates", "normal_tolerance"});
  ContactSpec c;
  c.enabled = true;
  const auto non_negative = [&](const char* name, double& out) {
    if (const Value* v = find(t, name)) {
      const std::string key = join(path, name);
      out = to_number(*v, key);
      if (!(out >= 0)) fail(key, fmt::format("expected a number >= 0, got {}", out), v);
    }
  };
  non_negative("friction", c.friction);
  if (const Value* v = find(t, "max_penetration")) {
    const std::string key = join(path, "max_penetration");
    c.max_penetration = to_number(*v, key);
    if (!(c.max_penetration > 0 && c.max_penetration < 1))
      fail(key, fmt::format("expected a fraction of the radius in (0, 1), got {}", c.max_penetration), v);
  }
  non_negative("elastic_slip", c.elastic_slip);
  non_negative("stiffness", c.stiffness);
  if (const Value* v = find(t, "regularization")) {
    const std::string key = join(path, "regularization");
    c.regularization = to_number(*v, key);
    if (!(c.regularization > 0 && c.regularization <= 1))
      fail(key, fmt::format("expected a fraction of the allowed penetration in (0, 1], got {}", c.regularization), v);
  }
  non_negative("margin", c.margin);
  non_negative("spacing", c.spacing);
  non_negative("self_exclusion", c.self_exclusion);
  if (const Value* v = find(t, "max_detections")) c.max_detections = to_int(*v, join(path, "max_detections"), 1);
  if (const Value* v = find(t, "max_normal_updates"))
    c.max_normal_updates = to_int(*v, join(path, "max_normal_updates"), 1);
  if (const Value* v = find(t, "normal_tolerance")) c.normal_tolerance = positive(*v, join(path, "normal_tolerance"));
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
  check_keys(t, path, {"every", "tube_sides", "plots", "test_levels", "checkpoint"});
  OutputSpec o;
  if (const Value* v = find(t, "every")) o.every = to_int(*v, join(path, "every"), 1);
  if (const Value* v = find(t, "tube_sides")) o.tube_sides = to_int(*v, join(path, "tube_sides"), 3);
  if (const Value* v = find(t, "plots")) o.plots = to_bool(*v, join(path, "plots"));
  if (const Value* v = find(t, "test_levels")) o.test_levels = to_bool(*v, join(path, "test_levels"));
  if (const Value* v = find(t, "checkpoint")) read_checkpoint(*v, join(path, "checkpoint"), o);
  return o;
}

void Reader::read_steps(const Value& root, Case& c, const std::vector<FiberSpec>& all_fibers,
                        const std::vector<BodySpec>& all_bodies) const {
  const std::string fabric_word = m_json ? "a fabric object" : "a [fabric]";
  const Value& v = require(root, "", "step", table_array_word("step"));
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

Case Reader::read_continued(const Value& root, const Value& start) const {
  for (const std::string_view key : kModelKeys)
    if (const Value* v = find(root, key))
      fail(std::string(key),
           fmt::format("a case with [start] takes its model (materials, fibers, fabric, bodies, ...) from the run it "
                       "goes on from: remove the {} here, or remove [start] to build the model from this file",
                       key),
           v);
  expect_table(start, "start");
  check_keys(start, "start", {"from", "step"});
  const Value& from_value =
      require(start, "start", "from", "a string: the result directory (--out) of an earlier run to go on from");
  const std::string from = to_string(from_value, "start.from");
  namespace fs = std::filesystem;
  fs::path dir(from);
  if (dir.is_relative()) dir = fs::path(m_file).parent_path() / dir;
  dir = dir.lexically_normal();
  std::error_code ec;
  if (!fs::is_directory(dir, ec) || !fs::is_regular_file(dir / "case.toml", ec))
    fail("start.from",
         fmt::format("no result directory \"{}\" (expected the output directory of an earlier run, holding its "
                     "case.toml and state/; a relative path is taken from this file's directory)",
                     dir.string()),
         &from_value);
  // The earlier run's model as it ran (its case.toml: a fabric expanded into fibers, bodies and
  // tows); its errors name that file.
  Case c = read_case((dir / "case.toml").string(), m_limits);
  c.start = dir.string();
  // The state: at the end of the step named, or of the last step that ended.
  const auto state_of = [&](const std::string& step) { return dir / "state" / (step_file_stem(step) + ".bin"); };
  if (const Value* v = find(start, "step")) {
    c.start_step = to_string(*v, "start.step");
    std::vector<std::string> names;
    for (const StepSpec& s : c.steps) names.push_back(s.name);
    if (std::find(names.begin(), names.end(), c.start_step) == names.end())
      fail("start.step",
           fmt::format("the run in \"{}\" has no step \"{}\"{} (its steps: {})", dir.string(), c.start_step,
                       did_you_mean(c.start_step, names), list_names(names)),
           v);
    if (!fs::is_regular_file(state_of(c.start_step), ec))
      fail("start.step",
           fmt::format("the run in \"{}\" did not end its step \"{}\" (no {})", dir.string(), c.start_step,
                       state_of(c.start_step).string()),
           v);
  } else {
    for (auto s = c.steps.rbegin(); s != c.steps.rend() && c.start_step.empty(); ++s)
      if (fs::is_regular_file(state_of(s->name), ec)) c.start_step = s->name;
    if (c.start_step.empty())
      fail("start.from",
           fmt::format("the run in \"{}\" ended no step (no state/<step>.bin): nothing to go on from", dir.string()),
           &from_value);
  }
  c.start_state = state_of(c.start_step).string();
  if (const Value* v = find(root, "title")) c.title = to_string(*v, "title");
  c.steps.clear();
  read_steps(root, c, c.fibers, c.bodies);
  if (const Value* v = find(root, "solver")) c.solver = read_solver(*v, "solver");
  if (const Value* v = find(root, "output")) c.output = read_output(*v, "output");
  if (const Value* v = find(root, "contact")) c.contact = read_contact(*v, "contact");
  return c;
}

Case Reader::read(const Value& root) const {
  check_keys(root, "", kTopLevelKeys);
  if (const Value* start = find(root, "start")) return read_continued(root, *start);
  Case c;
  c.file = m_file;  // expand_fabric names it in its messages
  if (const Value* v = find(root, "title")) c.title = to_string(*v, "title");

  // Materials.
  {
    const Value& v = require(root, "", "material", table_array_word("material"));
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
    check_keys(*v, "weave", {"matrix", "pattern"});
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

std::string read_text(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, "(file)", "cannot read the file: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw InputError(path, "(file)",
                     fmt::format("cannot open the file: {}",
                                 error != 0 ? std::strerror(error) : "unknown error"));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "(file)", "cannot read the file: I/O error");
  return text.str();
}

}  // namespace

namespace {

// The document tree of a TOML or JSON case file's text; InputError on a syntax error.
Value toml_document(const std::string& text, const std::string& file_label) {
  try {
    return from_toml(toml::parse(text, std::string_view(file_label)));
  } catch (const toml::parse_error& e) {
    const auto& begin = e.source().begin;
    throw InputError(file_label, "(file)",
                     fmt::format("TOML syntax error at line {}, column {}: {}", begin.line,
                                 begin.column, e.description()));
  }
}

Value json_document(const std::string& text, const std::string& file_label) {
  JsonBuilder builder;
  if (!nlohmann::json::sax_parse(text, &builder)) {
    const std::string key = builder.error_key().empty() ? "(file)" : builder.error_key();
    std::string message = builder.error().empty() ? "JSON syntax error" : builder.error();
    if (key != "(file)" && builder.error_position() > 0) {
      // The line of a value refused while parsing (the syntax errors give their own).
      const std::size_t end = std::min(builder.error_position(), text.size());
      message += fmt::format(" (line {})", 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(end), '\n'));
    }
    throw InputError(file_label, key, message);
  }
  if (builder.root().type != Value::Type::Table) {
    throw InputError(file_label, "(file)", "expected a JSON object at the top level");
  }
  return builder.root();
}

}  // namespace

Case parse_case_toml(const std::string& text, const std::string& file_label, const SizeLimits& limits) {
  return finish(toml_document(text, file_label), file_label, false, limits);
}

Case parse_case_json(const std::string& text, const std::string& file_label, const SizeLimits& limits) {
  return finish(json_document(text, file_label), file_label, true, limits);
}

namespace {

// Every value of a document tree under its dotted key path (`step[2].strain`), as text.
void flatten(const Value& v, const std::string& path, std::map<std::string, std::string>& out) {
  switch (v.type) {
    case Value::Type::Table:
      if (v.keys.empty()) out[path] = "{}";
      for (std::size_t i = 0; i < v.keys.size(); ++i)
        flatten(v.items[i], path.empty() ? v.keys[i] : path + "." + v.keys[i], out);
      break;
    case Value::Type::Array:
      if (v.items.empty()) out[path] = "[]";
      for (std::size_t i = 0; i < v.items.size(); ++i) flatten(v.items[i], fmt::format("{}[{}]", path, i), out);
      break;
    case Value::Type::Boolean: out[path] = v.boolean ? "true" : "false"; break;
    case Value::Type::Integer: out[path] = std::to_string(v.integer); break;
    case Value::Type::Float: out[path] = fmt::format("{}", v.number); break;
    case Value::Type::String: out[path] = "\"" + v.text + "\""; break;
    case Value::Type::Null: out[path] = "null"; break;
    case Value::Type::Other: out[path] = v.text; break;
  }
}

}  // namespace

std::map<std::string, std::string> case_file_keys(const std::string& text, bool json, const std::string& file_label) {
  std::map<std::string, std::string> out;
  flatten(json ? json_document(text, file_label) : toml_document(text, file_label), "", out);
  return out;
}

Case read_case(const std::string& path, const SizeLimits& limits) {
  const std::string extension = lowercase(std::filesystem::path(path).extension().string());
  if (extension != ".toml" && extension != ".json") {
    throw InputError(path, "(file)",
                     fmt::format("unknown case file type \"{}\": expected a .toml or .json file",
                                 extension));
  }
  const std::string text = read_text(path);
  return extension == ".toml" ? parse_case_toml(text, path, limits) : parse_case_json(text, path, limits);
}

}  // namespace fibra
