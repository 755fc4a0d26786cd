#include "fibra/model/case.hpp"

#include <cstdio>

namespace fibra {

std::string NodeRef::label() const {
  switch (kind) {
    case Kind::First:
      return "first";
    case Kind::Last:
      return "last";
    case Kind::NodeIndex:
      return std::to_string(index);
    case Kind::Fraction: {
      char buffer[64];
      std::snprintf(buffer, sizeof buffer, "at%g", fraction);
      return buffer;
    }
  }
  return "first";
}

const char* StepSpec::kind_name(Kind k) {
  switch (k) {
    case Kind::Standard:
      break;
    case Kind::Weave:
      return "weave";
    case Kind::Relax:
      return "relax";
    case Kind::Biaxial:
      return "biaxial";
    case Kind::Shear:
      return "shear";
  }
  return "standard";
}

std::string step_file_stem(const std::string& step) {
  std::string out;
  for (char ch : step) {
    const bool keep = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '.' ||
                      ch == '-' || ch == '_';
    out += keep ? ch : '_';
  }
  return out.empty() || out == "." || out == ".." ? "step" : out;
}

}  // namespace fibra
