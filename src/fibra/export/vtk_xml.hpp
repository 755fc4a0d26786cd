#pragma once
/// Pieces of the VTK XML formats (.vtp, .vti) written by the export: arrays stored raw in one
/// appended block (header_type UInt64: each array's byte count as 8 bytes, then its bytes), in
/// the machine's byte order, which the file header states.
#include <cstdint>
#include <string>
#include <vector>

namespace fibra {

/// "LittleEndian" or "BigEndian": this machine's byte order.
const char* vtk_byte_order();

/// The XML declaration and the opening VTKFile tag of a file of `type` ("PolyData", ...).
std::string vtk_file_header(const std::string& type);

/// The appended data of one VTK XML file.
class VtkAppendedData {
 public:
  /// Stores the values and returns their DataArray element. `type` is the VTK name of T
  /// ("Float64", "Int32", "Int64").
  template <class T>
  std::string data_array(const char* type, const std::string& name, int components, const std::vector<T>& values) {
    return add(type, name, components, values.data(), values.size() * sizeof(T));
  }
  /// The AppendedData element holding every array stored, and the end of the file.
  std::string close() const;

 private:
  std::string add(const char* type, const std::string& name, int components, const void* data, std::uint64_t bytes);
  std::string m_bytes;
};

}  // namespace fibra
