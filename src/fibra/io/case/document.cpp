#include "fibra/io/case/document.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <toml++/toml.h>
#include <utility>

#include "fibra/core/error.hpp"

namespace fibra::case_file {

/// The value stored under `key` in a Table, or nullptr.
const Value* find(const Value& table, std::string_view key) {
  for (std::size_t i = 0; i < table.keys.size(); ++i) {
    if (table.keys[i] == key) return &table.items[i];
  }
  return nullptr;
}

namespace {

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

}  // namespace

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
}  // namespace fibra::case_file
