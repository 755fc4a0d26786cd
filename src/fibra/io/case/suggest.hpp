#pragma once
/// Key paths, spelling suggestions ("did you mean") and lists of names for the messages of the
/// case reader.
#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace fibra::case_file {

/// `path.key`, or `key` at the top level.
std::string join(const std::string& path, std::string_view key);

/// `path[i]`.
std::string item(const std::string& path, std::size_t i);

/// `s` in lower case (ASCII).
std::string lowercase(std::string_view s);

/// Case-insensitive edit distance counting adjacent transpositions as one edit.
std::size_t edit_distance(std::string_view a_in, std::string_view b_in);

/// The candidate closest to `word`, when it is close enough to be a likely misspelling.
template <class Range>
std::optional<std::string> closest(std::string_view word, const Range& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = SIZE_MAX;
  const std::string lower_word = lowercase(word);
  for (const auto& candidate_in : candidates) {
    const std::string_view candidate(candidate_in);
    const std::size_t distance = edit_distance(word, candidate);
    const std::size_t threshold = std::max<std::size_t>(1, (candidate.size() + 1) / 3);
    const std::string lower_candidate = lowercase(candidate);
    const std::size_t shorter = std::min(lower_word.size(), lower_candidate.size());
    const bool prefix = shorter >= 3 && lower_word.compare(0, shorter, lower_candidate, 0, shorter) == 0;
    if ((distance <= threshold || prefix) && distance < best_distance) {
      best = std::string(candidate);
      best_distance = distance;
    }
  }
  return best;
}

/// " (did you mean "x"?)" or "".
template <class Range>
std::string did_you_mean(std::string_view word, const Range& candidates) {
  if (auto best = closest(word, candidates)) return fmt::format(" (did you mean \"{}\"?)", *best);
  return "";
}

/// "a, b, c" for a list of names.
template <class Range>
std::string list_names(const Range& names) {
  std::string out;
  for (const auto& name : names) {
    if (!out.empty()) out += ", ";
    out += std::string_view(name);
  }
  return out;
}

/// Lists of names longer than this are given only in part in messages.
constexpr std::size_t kListedNames = 20;

/// "a, b, c" for at most kListedNames names, then "... (N in all)".
template <class Range>
std::string list_some_names(const Range& names) {
  std::string out;
  std::size_t count = 0;
  for (const auto& name : names) {
    if (count++ >= kListedNames) continue;
    if (!out.empty()) out += ", ";
    out += std::string_view(name);
  }
  if (count > kListedNames) out += fmt::format(", ... ({} in all)", count);
  return out;
}

}  // namespace fibra::case_file
