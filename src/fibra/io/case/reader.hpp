#pragma once
/// The schema of a case file (io/case/schema.hpp) checked on its document tree
/// (io/case/document.hpp), written once for both formats: the Reader's core (failures,
/// descriptions of values, key checks, conversions) is in reader.cpp, each section's reader in
/// read_<section>.cpp.
#include <array>
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fibra/io/case/document.hpp"
#include "fibra/io/case/schema.hpp"
#include "fibra/model/case.hpp"
#include "fibra/model/model_size.hpp"

namespace fibra::case_file {

constexpr double kDegree = std::numbers::pi / 180.0;

/// A key allowed only in another variant of a table, with the message explaining why.
struct KeyHint {
  std::string_view key;
  std::string_view message;
};

using Keys = std::vector<std::string_view>;

/// The first words of the named weave patterns (model/fabric.hpp), for suggestions.
inline const Keys kWeaveWords = {"plain", "twill", "basket", "satin"};

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
  [[noreturn]] void fail(const std::string& key, const std::string& message, const Value* at) const;

  std::string describe(const Value& v) const;

  /// "an array of tables ([[fiber]])" or "an array of objects".
  std::string table_array_word(std::string_view name) const;

  std::string table_word() const;

  // -- tables --------------------------------------------------------------------------

  /// Fails on the first key of `table` that is not in `known`.
  void check_keys(const Value& table, const std::string& path, const Keys& known,
                  const std::vector<KeyHint>& hints = {}) const;

  const Value& require(const Value& table, const std::string& path, std::string_view key,
                       std::string_view expected) const;
  /// The required key `key` of schema table `section`: missing, the message says what the
  /// schema expects (KeySpec::expected).
  const Value& require_key(const Value& table, const std::string& path, std::string_view section,
                           std::string_view key) const;

  // -- conversions ---------------------------------------------------------------------

  double to_number(const Value& v, const std::string& key) const;

  std::int64_t to_integer(const Value& v, const std::string& key) const;

  int to_int(const Value& v, const std::string& key, int minimum) const;

  std::string to_string(const Value& v, const std::string& key) const;

  /// A string that must be one of `words`: `expected "a", "b" or "c", got "x"` otherwise, with
  /// the nearest word suggested.
  std::string one_of(const Value& v, const std::string& key, const Keys& words) const;

  std::string to_name(const Value& v, const std::string& key) const;

  bool to_bool(const Value& v, const std::string& key) const;

  std::vector<double> to_numbers(const Value& v, const std::string& key, std::size_t n) const;

  Vec3 to_vec3(const Value& v, const std::string& key) const;

  Vec3 to_direction(const Value& v, const std::string& key) const;

  void expect_table(const Value& v, const std::string& key) const;

  const std::vector<Value>& to_table_array(const Value& v, const std::string& key,
                                           std::string_view name) const;

  double positive(const Value& v, const std::string& key) const;

  /// A plain number key `name` of the table `section` of the schema (KeySpec::bounded), read from
  /// the table `t` at `path` into `out` and checked against its minimum; `out` keeps its value
  /// when the key is not given.
  void read_bounded(const Value& t, const std::string& path, std::string_view section, std::string_view name,
                    double& out) const;
  /// The same for a plain integer key.
  void read_bounded(const Value& t, const std::string& path, std::string_view section, std::string_view name,
                    int& out) const;

  /// A relative tolerance in (0, 1); `relative_to` says what it is relative to (for the message).
  double fraction(const Value& v, const std::string& key, const char* relative_to) const;

  /// An array of 3 components, each a number (prescribed) or "free" (std::nullopt).
  std::array<std::optional<double>, 3> to_components(const Value& v, const std::string& key) const;

  /// Checks that `name`, read from `v` at `key`, is the name of one of `bodies`.
  void expect_body(const std::string& name, const Value& v, const std::string& key,
                   const std::vector<BodySpec>& bodies) const;

  /// The fiber named `name`, read from `v` at `key`; fails naming the closest defined fiber.
  const FiberSpec& expect_fiber(const std::string& name, const Value& v, const std::string& key,
                                const std::vector<FiberSpec>& fibers) const;

  /// Checks that `name`, read from `v` at `key`, is the name of one of `materials`.
  void expect_material(const std::string& name, const Value& v, const std::string& key,
                       const std::vector<MaterialSpec>& materials) const;

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

/// Validates `root` and fills in the file and name of the case.
Case finish(const Value& root, const std::string& file_label, bool json, const SizeLimits& limits);

}  // namespace fibra::case_file
