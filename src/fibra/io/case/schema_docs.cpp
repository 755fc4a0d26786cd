// case_schema_docs FILE: rewrites the key tables of FILE (docs/case-file.md) as the case file
// schema makes them (with_case_schema_tables, io/case/schema.hpp); the rest of FILE is kept.
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "fibra/io/case/schema.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: case_schema_docs FILE (docs/case-file.md)\n";
    return 2;
  }
  std::ifstream in(argv[1], std::ios::binary);
  if (!in) {
    std::cerr << "case_schema_docs: cannot read " << argv[1] << "\n";
    return 1;
  }
  std::ostringstream text;
  text << in.rdbuf();
  in.close();
  const std::string updated = fibra::case_file::with_case_schema_tables(text.str());
  if (updated == text.str()) return 0;
  std::ofstream out(argv[1], std::ios::binary | std::ios::trunc);
  out << updated;
  if (!out.flush()) {
    std::cerr << "case_schema_docs: cannot write " << argv[1] << "\n";
    return 1;
  }
  std::cout << "case_schema_docs: rewrote the key tables of " << argv[1] << "\n";
  return 0;
}
