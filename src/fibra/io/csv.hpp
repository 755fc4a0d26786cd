#pragma once
/// Comma-separated fields as fibra's CSV files write and read them.
#include <string>
#include <vector>

namespace fibra {

/// A CSV field: quoted (with doubled quotes) when it holds a separator, quote or line break.
std::string csv_field(const std::string& s);

/// Splits one CSV line (without its line break) into `fields` (a quoted field: "..." with
/// doubled quotes). Returns false on an unterminated quote or text after a closing quote.
bool split_csv_line(const std::string& line, std::vector<std::string>& fields);

}  // namespace fibra
