// The reader of a case with [start]: the model and state of an earlier run.
#include "fibra/io/case/reader.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/case/suggest.hpp"
#include "fibra/io/case_reader.hpp"

namespace fibra::case_file {

Case Reader::read_continued(const Value& root, const Value& start) const {
  // The keys of the model (the top level's variant "model"), which the earlier run gives.
  for (const KeySpec& k : schema_section("top").keys)
    if (const Value* v = k.variant == "model" ? find(root, k.name) : nullptr)
      fail(std::string(k.name),
           fmt::format("a case with [start] takes its model (materials, fibers, fabric, bodies, ...) from the run it "
                       "goes on from: remove the {} here, or remove [start] to build the model from this file",
                       k.name),
           v);
  expect_table(start, "start");
  check_keys(start, "start", schema_keys("start"));
  const Value& from_value =
      require_key(start, "start", "start", "from");
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
}  // namespace fibra::case_file
