#pragma once
/// The schema of a case file: every key of every table declared once, with its type, default,
/// allowed values, unit and meaning. The reader takes the keys of each table from it (what
/// "unknown key" refuses and what "did you mean" suggests), and the key tables of
/// docs/case-file.md are its markdown (case_schema_markdown; tests/io/test_case_schema.cpp
/// compares them).
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace fibra::case_file {

inline constexpr double kNotANumber = std::numeric_limits<double>::quiet_NaN();

/// One key of a table of a case file. The texts are those of the docs (markdown).
struct KeySpec {
  std::string_view name = {};
  std::string_view type = {};           ///< "number", "integer", "string", "vector", "array of tables", ...
  std::string_view default_value = {};  ///< when left out: a value (`1e-8`), "required", "none", ...
  std::string_view allowed = {};        ///< the values accepted beyond the type ("> 0"); "" for any
  std::string_view unit = {};           ///< the SI unit the meaning gives in brackets (m, Pa, N, degrees, ...); "" for none
  std::string_view meaning = {};
  /// The variant of the table the key belongs to alone: the `model` of a material
  /// ("transverse"); at the top level, "model" for the keys of a case that builds its model and
  /// "start" for [start], which takes the model of an earlier run. "" when it belongs to every
  /// variant.
  std::string_view variant = {};
  /// A plain number or integer key (read as it is, with a lower bound alone): the value when it
  /// is left out, which the case's structs hold (model/case.hpp), and the bound the reader
  /// checks: > minimum when `exclusive`, else >= minimum. NaN for the other keys.
  double number_default = kNotANumber;
  double minimum = kNotANumber;
  bool exclusive = false;
  /// A string key that is one of a few words: the words, in the order the reader lists them.
  std::span<const std::string_view> choices = {};
  /// A required key: what its value is, as the reader's message says when the key is missing
  /// ("missing required key (expected a number > 0 [Pa])"). "@tables" stands for the format's
  /// words for an array of tables ("an array of tables ([[step]])" or "an array of objects"),
  /// "@table" for a table ("a table" or "an object").
  std::string_view expected = {};

  /// Whether the key is a plain number or integer (number_default and minimum given).
  constexpr bool bounded() const { return minimum == minimum; }
};

/// One table of a case file. Its name is the path of the table with its array indices left out
/// ("fiber", "fiber.arc", "step.load"), except "top" (the top level), "node" (the keys of a node
/// reference) and "fabric.direction" (fabric.warp and fabric.weft).
struct SectionSpec {
  std::string_view name;
  std::span<const KeySpec> keys;  ///< in the order of the docs and of the reader's lists of keys
  bool node_reference = false;    ///< the table also holds the keys of a node reference, first
  bool default_column = true;     ///< its docs table shows the Default column
  bool allowed_column = true;     ///< its docs table shows the Allowed column
};

/// Every table of a case file, in the order of docs/case-file.md.
const std::vector<SectionSpec>& case_schema();

/// The table named `name` (SectionSpec::name); std::logic_error when there is none.
const SectionSpec& schema_section(std::string_view name);

/// The key `key` of the table `section`; std::logic_error when there is none.
const KeySpec& schema_key(std::string_view section, std::string_view key);

/// The words a string key `section.key` may be (KeySpec::choices).
std::vector<std::string_view> schema_choices(std::string_view section, std::string_view key);

/// The names of the keys of table `section` (those of a node reference first, when it holds
/// one). With a `variant`, only the keys of every variant and those of that one.
std::vector<std::string_view> schema_keys(std::string_view section, std::string_view variant = {});

/// The markdown table of the keys of `sections` (names separated by spaces), as
/// docs/case-file.md shows it. Several sections make one table with a first column "Table"
/// naming each key's (the last part of its name); the columns are those of the first.
std::string case_schema_markdown(std::string_view sections);

/// The markdown text `markdown` with each table that follows a line `<!-- schema: NAMES -->`
/// (its lines that start with `|`) replaced by case_schema_markdown(NAMES): docs/case-file.md as
/// the schema makes it (the program case_schema_docs writes it).
std::string with_case_schema_tables(std::string_view markdown);

}  // namespace fibra::case_file
