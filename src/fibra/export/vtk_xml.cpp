#include "fibra/export/vtk_xml.hpp"

#include <bit>
#include <cstring>

#include <fmt/format.h>

namespace fibra {

const char* vtk_byte_order() { return std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian"; }

std::string vtk_file_header(const std::string& type) {
  return fmt::format(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"{}\" version=\"1.0\" byte_order=\"{}\" "
      "header_type=\"UInt64\">\n",
      type, vtk_byte_order());
}

std::string VtkAppendedData::add(const char* type, const std::string& name, int components, const void* data,
                                 std::uint64_t bytes) {
  const std::string element =
      fmt::format("<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{}\"/>\n",
                  type, name, components, m_bytes.size());
  char header[sizeof bytes];
  std::memcpy(header, &bytes, sizeof bytes);
  m_bytes.append(header, sizeof bytes);
  m_bytes.append(static_cast<const char*>(data), bytes);
  return element;
}

std::string VtkAppendedData::close() const {
  std::string out = "<AppendedData encoding=\"raw\">\n_";
  out += m_bytes;
  out += "\n</AppendedData>\n</VTKFile>\n";
  return out;
}

}  // namespace fibra
