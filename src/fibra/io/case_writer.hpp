#pragma once
/// Writing a case back as a TOML case file (docs/case-file.md): the assembly as the reader
/// holds it, a [fabric] already expanded into its fibers, bodies, bindings, tows and weave.
#include <string>

#include "fibra/model/case.hpp"

namespace fibra {

/// A complete, plain TOML case file for `c`: materials, fibers, fixes, bodies, bindings, tows,
/// [weave], steps (with their loads, displacements and [[step.body]] entries), [solver],
/// [contact] (when enabled) and [output]; never a [fabric] table. Numbers are written in the
/// shortest form that reads back to the same double, and angles in degrees that give the same
/// radians, so parse_case_toml() of the result gives `c` again (except `file`, `name` and
/// `fabric`; directions, normalized again, to within an ulp). A fix that holds nothing is
/// left out.
std::string write_case_toml(const Case& c);

}  // namespace fibra
