#include "fibra/io/nodes_csv.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <vector>

#include "fibra/core/error.hpp"
#include "fibra/io/csv.hpp"

namespace fibra {

const char* const kNodesCsvHeader = "fiber,node,x,y,z,g1x,g1y,g1z,g2x,g2y,g2z";

std::string nodes_csv_text(const Model& model, const VecX& q) {
  std::string text = std::string(kNodesCsvHeader) + "\n";
  for (const Fiber& fib : model.fibers) {
    const std::string name = csv_field(fib.name);
    for (Index j = 0; j < fib.num_nodes; ++j) {
      const double* v = q.data() + kNodeDofs * (fib.first_node + j);
      text += fmt::format("{},{},{},{},{},{},{},{},{},{},{}\n", name, j, v[0], v[1], v[2], v[3], v[4], v[5], v[6],
                          v[7], v[8]);
    }
  }
  return text;
}

VecX read_nodes_csv(const std::string& path, const Model& model) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "(file)", fmt::format("cannot open: {}", std::strerror(errno)));
  const std::string header = kNodesCsvHeader;
  static const char* const kColumns[kNodeDofs] = {"x", "y", "z", "g1x", "g1y", "g1z", "g2x", "g2y", "g2z"};
  std::string line;
  int number = 1;
  if (!std::getline(in, line)) throw InputError(path, "line 1", "empty file: expected the header " + header);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != header)
    throw InputError(path, "line 1", fmt::format("expected the header \"{}\", got \"{}\"", header, line));
  VecX q = model.reference;
  std::vector<char> seen(static_cast<size_t>(model.num_nodes()), 0);
  std::vector<std::string> fields;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::string key = fmt::format("line {}", number);
    if (!split_csv_line(line, fields) || fields.size() != 11)
      throw InputError(path, key, fmt::format("expected 11 comma-separated fields ({}), got \"{}\"", header, line));
    const int f = model.fiber_index(fields[0]);
    if (f < 0) throw InputError(path, key, fmt::format("no fiber named \"{}\" in the case", fields[0]));
    const Fiber& fiber = model.fibers[f];
    Index node = -1;
    {
      const std::string& s = fields[1];
      const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), node);
      if (ec != std::errc() || end != s.data() + s.size() || node < 0 || node >= fiber.num_nodes)
        throw InputError(path, key,
                         fmt::format("node must be an integer from 0 to {} (fiber \"{}\" has {} nodes), got \"{}\"",
                                     fiber.num_nodes - 1, fiber.name, fiber.num_nodes, s));
    }
    const Index global = fiber.first_node + node;
    if (seen[global]) throw InputError(path, key, fmt::format("node {} of fiber \"{}\" given twice", node, fiber.name));
    seen[global] = 1;
    for (int k = 0; k < kNodeDofs; ++k) {
      const std::string& s = fields[2 + k];
      double v = 0;
      const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
      if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
        throw InputError(path, key, fmt::format("column {}: expected a finite number, got \"{}\"", kColumns[k], s));
      q[kNodeDofs * global + k] = v;
    }
  }
  for (const Fiber& fiber : model.fibers) {
    Index count = 0;
    for (Index j = 0; j < fiber.num_nodes; ++j) count += seen[fiber.first_node + j];
    if (count != fiber.num_nodes)
      throw InputError(path, "(file)",
                       fmt::format("fiber \"{}\" has {} of its {} nodes in the file (does it belong to this case?)",
                                   fiber.name, count, fiber.num_nodes));
  }
  return q;
}

}  // namespace fibra
