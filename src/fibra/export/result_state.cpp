#include "fibra/export/result_state.hpp"

#include <filesystem>

#include <fmt/format.h>

#include "fibra/core/error.hpp"
#include "fibra/io/case_reader.hpp"
#include "fibra/io/nodes_csv.hpp"

namespace fibra {

ResultState read_result_state(const std::string& dir, const std::string& command) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(dir, "(directory)",
                     fs::exists(dir, ec) ? "not a directory: expected the output directory of `fibra run`"
                                         : "no such directory: expected the output directory of `fibra run`");
  const fs::path case_file = fs::path(dir) / "case.toml", nodes_file = fs::path(dir) / "nodes.csv";
  for (const fs::path& f : {case_file, nodes_file})
    if (!fs::is_regular_file(f, ec))
      throw InputError(f.string(), "(file)",
                       fmt::format("not found: `{}` reads the case.toml and nodes.csv that `fibra run` writes into "
                                   "its output directory",
                                   command));
  ResultState r;
  r.c = read_case(case_file.string());
  r.model = build_model(r.c);
  r.q = read_nodes_csv(nodes_file.string(), r.model);
  return r;
}

}  // namespace fibra
