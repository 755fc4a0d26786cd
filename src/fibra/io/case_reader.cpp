#include "fibra/io/case_reader.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fibra/core/error.hpp"
#include "fibra/io/case/document.hpp"
#include "fibra/io/case/reader.hpp"
#include "fibra/io/case/suggest.hpp"

namespace fibra {
namespace {

std::string read_text(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, "(file)", "cannot read the file: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw InputError(path, "(file)",
                     fmt::format("cannot open the file: {}",
                                 error != 0 ? std::strerror(error) : "unknown error"));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "(file)", "cannot read the file: I/O error");
  return text.str();
}

}  // namespace

Case parse_case_toml(const std::string& text, const std::string& file_label, const SizeLimits& limits) {
  return case_file::finish(case_file::toml_document(text, file_label), file_label, false, limits);
}

Case parse_case_json(const std::string& text, const std::string& file_label, const SizeLimits& limits) {
  return case_file::finish(case_file::json_document(text, file_label), file_label, true, limits);
}

std::map<std::string, std::string> case_file_keys(const std::string& text, bool json, const std::string& file_label) {
  std::map<std::string, std::string> out;
  case_file::flatten(json ? case_file::json_document(text, file_label) : case_file::toml_document(text, file_label),
                     "", out);
  return out;
}

Case read_case(const std::string& path, const SizeLimits& limits) {
  const std::string extension = case_file::lowercase(std::filesystem::path(path).extension().string());
  if (extension != ".toml" && extension != ".json") {
    throw InputError(path, "(file)",
                     fmt::format("unknown case file type \"{}\": expected a .toml or .json file",
                                 extension));
  }
  const std::string text = read_text(path);
  return extension == ".toml" ? parse_case_toml(text, path, limits) : parse_case_json(text, path, limits);
}

}  // namespace fibra
