#pragma once
/// For the harnesses of readers that take a path (read_state_file, read_nodes_csv): each input
/// is written to one file of the process's own, which the reader then opens.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include <unistd.h>

namespace fibra::fuzz {

/// The path of this process's input file: in $TMPDIR (or /tmp), named after the process id, so
/// that harnesses run at the same time do not share one.
inline const std::string& input_path(const char* extension) {
  static const std::string path = [extension] {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir && *dir ? dir : "/tmp") + "/fibra-fuzz-" + std::to_string(getpid()) + extension;
  }();
  return path;
}

/// Writes `size` bytes at `data` to input_path(extension) and returns that path.
inline const std::string& write_input(const std::uint8_t* data, std::size_t size, const char* extension) {
  const std::string& path = input_path(extension);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) std::abort();  // the harness itself cannot work: not a finding in fibra
  return path;
}

}  // namespace fibra::fuzz
