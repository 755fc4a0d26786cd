#pragma once
/// Errors reported to the user: bad input (file + key + expectation) and failed runs.
#include <stdexcept>
#include <string>

namespace fibra {

/// Invalid user input. `what()` reads "FILE: KEY: MESSAGE".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& key, const std::string& message)
      : std::runtime_error(file + ": " + key + ": " + message), m_file(file), m_key(key) {}
  const std::string& file() const { return m_file; }  ///< the input file
  const std::string& key() const { return m_key; }    ///< the dotted key path, e.g. fiber[2].radius

 private:
  std::string m_file;
  std::string m_key;
};

/// A failure while running a case (no convergence, singular system, I/O).
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace fibra
