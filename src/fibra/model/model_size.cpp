#include "fibra/model/model_size.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include "fibra/beam/beam_element.hpp"

namespace fibra {
namespace {

/// Bytes per stored matrix entry: the value (8) and row index (4) of the assembled matrix, and
/// at least one entry of the factor (fill-in only adds to the matrix's pattern), in double (8)
/// and in the preconditioner's rounded copy (4 in floats; 2 in halves, counted as 4).
constexpr double kBytesPerEntry = 8 + 4 + 8 + 4;
/// Vectors of the dofs' size the model and the solver keep.
constexpr double kVectors = 10;

/// The memory limit in a cgroup file (v2 "memory.max", v1 "memory.limit_in_bytes"), or +inf
/// when absent or unlimited ("max").
double cgroup_limit(const char* path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return std::numeric_limits<double>::infinity();
  try {
    return std::stod(text);
  } catch (const std::exception&) {
    return std::numeric_limits<double>::infinity();
  }
}

}  // namespace

double ModelSize::bytes() const {
  return kBytesPerEntry * matrix_entries() + static_cast<double>(sizeof(BeamElement)) * elements +
         kVectors * sizeof(double) * dofs();
}

ModelSize& ModelSize::operator+=(const ModelSize& other) {
  fibers += other.fibers;
  elements += other.elements;
  bodies += other.bodies;
  return *this;
}

ModelSize fiber_size(double elements) { return ModelSize{1, elements, 0}; }

SizeLimits machine_size_limits() {
  // Read once per process: every case read and every model built asks.
  static const SizeLimits limits = [] {
    SizeLimits l;
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    double memory = pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page)
                                          : std::numeric_limits<double>::infinity();
    memory = std::min({memory, cgroup_limit("/sys/fs/cgroup/memory.max"),
                       cgroup_limit("/sys/fs/cgroup/memory/memory.limit_in_bytes")});
    l.memory = memory;
    return l;
  }();
  return limits;
}

std::string format_bytes(double bytes) {
  if (!std::isfinite(bytes)) return fmt::format("{} B", bytes);
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024 && u < 6) {
    bytes /= 1024;
    ++u;
  }
  if (u == 0) return fmt::format("{:.0f} B", bytes);
  return fmt::format("{:.3g} {}", bytes, units[u]);
}

std::string size_excess(const ModelSize& size, const SizeLimits& limits) {
  // Written so that NaN counts fail too.
  const bool entries = !(size.matrix_entries() <= limits.matrix_entries);
  const bool memory = !(size.bytes() <= limits.memory);
  if (!entries && !memory) return "";
  std::string why = fmt::format(
      "estimated {:.3g} elements, {:.3g} nodes, {:.3g} dofs, {:.3g} stiffness matrix entries and at least {} of "
      "memory",
      size.elements, size.nodes(), size.dofs(), size.matrix_entries(), format_bytes(size.bytes()));
  if (entries)
    why += fmt::format("; the sparse solver holds at most {:.0f} matrix entries (32-bit indices)",
                       limits.matrix_entries);
  if (memory) why += fmt::format("; this machine has {} of memory", format_bytes(limits.memory));
  return why;
}

}  // namespace fibra
