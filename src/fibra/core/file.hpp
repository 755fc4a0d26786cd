#pragma once
/// Writing result files so that a reader never sees half of one.
#include <cstddef>
#include <string>
#include <string_view>

namespace fibra {

/// Writes `bytes` to PATH.tmp, then renames it over `path` (a reader sees the old file or the
/// new one, never a part); removes PATH.tmp and throws RunError naming the file on failure.
void write_file_atomic(const std::string& path, std::string_view bytes);

}  // namespace fibra
