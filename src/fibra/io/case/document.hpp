#pragma once
/// The document tree of a case file: TOML and JSON are both converted to it, so that the schema
/// is checked once, by the Reader (io/case/reader.hpp).
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace fibra::case_file {

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
const Value* find(const Value& table, std::string_view key);

/// The document tree of a TOML case file's text; InputError on a syntax error.
Value toml_document(const std::string& text, const std::string& file_label);

/// The document tree of a JSON case file's text; InputError on a syntax error, a duplicate key,
/// a number beyond the range of a double, nesting too deep, or a top level that is not an object.
Value json_document(const std::string& text, const std::string& file_label);

/// Every value of a document tree under its dotted key path (`step[2].strain`), as text.
void flatten(const Value& v, const std::string& path, std::map<std::string, std::string>& out);

}  // namespace fibra::case_file
