#pragma once
/// Reading and validating case files (TOML or JSON, one schema; see docs/case-file.md).
/// Every problem in the input is reported as an InputError naming the file, the dotted key
/// path (e.g. `fiber[1].radius`, `step[0].load[2].force`) and what was expected. A [fabric]
/// is expanded (expand_fabric, model/fabric.hpp): the case holds its generated fibers, bodies,
/// bindings, tows, weave and edge conditions after those of the file, which may refer to them.
/// A model whose estimated size exceeds `limits` (model/model_size.hpp) is refused before
/// anything of that size is made, naming the key that sets the size.
#include <map>
#include <string>

#include "fibra/model/case.hpp"
#include "fibra/model/model_size.hpp"

namespace fibra {

/// Reads and validates the case file at `path`; ".toml" or ".json" selects the format.
Case read_case(const std::string& path, const SizeLimits& limits = machine_size_limits());

/// Parses and validates a TOML case held in `text`; `file_label` stands for the file name.
Case parse_case_toml(const std::string& text, const std::string& file_label,
                     const SizeLimits& limits = machine_size_limits());

/// Parses and validates a JSON case held in `text`; `file_label` stands for the file name.
Case parse_case_json(const std::string& text, const std::string& file_label,
                     const SizeLimits& limits = machine_size_limits());

/// Every value of a case file's text under its dotted key path (`fabric.warp.spacing`,
/// `step[2].strain`), as text: what two versions of a case file differ in (a resumed run
/// refuses an edited case, naming the keys). Throws InputError on a syntax error.
std::map<std::string, std::string> case_file_keys(const std::string& text, bool json, const std::string& file_label);

}  // namespace fibra
