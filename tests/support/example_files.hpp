#pragma once
// The example case files (examples/*/*.toml), for the tests that read or run every example.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fibra::test {

/// True if the case file goes on from an earlier run ([start]): it reads only once that run's
/// result directory exists (tests/verification/test_continue.cpp reads the examples that do).
inline bool goes_on_from_an_earlier_run(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("[start]", 0) == 0) return true;
  return false;
}

/// Every examples/*/*.toml that reads alone (not going on from an earlier run), sorted.
inline std::vector<std::filesystem::path> standalone_examples() {
  namespace fs = std::filesystem;
  std::vector<fs::path> out;
  for (const fs::directory_entry& dir : fs::directory_iterator(fs::path(FIBRA_SOURCE_DIR) / "examples")) {
    if (!dir.is_directory()) continue;
    for (const fs::directory_entry& f : fs::directory_iterator(dir.path()))
      if (f.is_regular_file() && f.path().extension() == ".toml" && !goes_on_from_an_earlier_run(f.path()))
        out.push_back(f.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace fibra::test
