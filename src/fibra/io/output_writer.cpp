#include "fibra/io/output_writer.hpp"

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <fmt/format.h>
#include <numbers>
#include <regex>
#include <string_view>
#include <system_error>

#include "fibra/beam/beam_element.hpp"
#include "fibra/core/error.hpp"
#include "fibra/io/csv.hpp"
#include "fibra/io/nodes_csv.hpp"

namespace fibra {

namespace {

namespace fs = std::filesystem;

[[noreturn]] void io_fail(std::string_view what, const std::string& path, int err) {
  throw RunError(fmt::format("{} '{}': {}", what, path, err != 0 ? std::strerror(err) : "unknown error"));
}

/// A file opened for (binary) writing whose every operation is checked.
class CheckedFile {
 public:
  explicit CheckedFile(std::string path) : m_path(std::move(path)) {
    errno = 0;
    m_file = std::fopen(m_path.c_str(), "wb");
    if (!m_file) io_fail("cannot open for writing", m_path, errno);
  }
  ~CheckedFile() {
    if (m_file) std::fclose(m_file);
  }
  CheckedFile(const CheckedFile&) = delete;
  CheckedFile& operator=(const CheckedFile&) = delete;

  void write(const void* data, size_t bytes) {
    if (bytes == 0) return;
    errno = 0;
    if (std::fwrite(data, 1, bytes, m_file) != bytes) io_fail("cannot write", m_path, errno);
  }
  void write(std::string_view text) { write(text.data(), text.size()); }

  /// Flushes and closes, reporting errors that only show up then (e.g. a full disk).
  void close() {
    errno = 0;
    const bool flush_ok = std::fflush(m_file) == 0 && !std::ferror(m_file);
    const int flush_err = errno;
    errno = 0;
    const int rc = std::fclose(m_file);
    m_file = nullptr;
    if (!flush_ok) io_fail("cannot write", m_path, flush_err);
    if (rc != 0) io_fail("cannot close", m_path, errno);
  }

 private:
  std::string m_path;
  std::FILE* m_file = nullptr;
};

/// Numbered files of a ParaView series (and their temporaries), in its subfolder or, as an
/// older run left them, in the output directory itself.
const std::regex& numbered_file() {
  static const std::regex re(R"((fibers|lines|contacts|bodies)_(\d{6})\.vtu(\.tmp)?)");  // group 2: the index
  return re;
}

/// Whether `dir` takes a new file: one is created, written and removed.
void check_writable(const fs::path& dir) {
  const fs::path probe = dir / ".fibra_write_check";
  errno = 0;
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  int err = errno;
  bool ok = f != nullptr;
  if (f) {
    errno = 0;
    ok = std::fputc('\n', f) != EOF && std::fflush(f) == 0;
    err = errno;
    if (std::fclose(f) != 0 && ok) {
      ok = false;
      err = errno;
    }
  }
  std::error_code ec;
  fs::remove(probe, ec);
  if (!ok)
    throw InputError(dir.string(), "(output directory)",
                     fmt::format("cannot write into it: {} (give another --out directory)",
                                 err != 0 ? std::strerror(err) : "unknown error"));
}

/// Writes `path` atomically: `fill` writes into PATH.tmp, which then replaces PATH.
template <class Fill>
void write_atomic(const std::string& path, Fill&& fill) {
  const std::string tmp = path + ".tmp";
  try {
    CheckedFile file(tmp);
    fill(file);
    file.close();
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  errno = 0;
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::error_code ec;
    fs::remove(tmp, ec);
    io_fail("cannot rename " + tmp + " to", path, err);
  }
}

/// Escapes text for an XML attribute value.
std::string xml_attr(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

/// A data array of a .vtu file, stored in the appended raw block.
struct VtuArray {
  std::string name;      ///< empty for Points / Cells arrays that VTK names itself
  std::string type;      ///< VTK type name: Float64, Int64, Int32, UInt8
  int components = 1;
  const void* data = nullptr;
  std::uint64_t bytes = 0;
  std::uint64_t tuples = 0;
};

template <class T>
VtuArray vtu_array(std::string name, std::string type, int components, const std::vector<T>& v) {
  return VtuArray{std::move(name), std::move(type), components, v.data(), v.size() * sizeof(T),
                  v.size() / static_cast<size_t>(components)};
}

void push3(std::vector<double>& v, const Vec3& x) { v.insert(v.end(), {x[0], x[1], x[2]}); }

/// Nodal state used by both .vtu files.
struct NodeState {
  Vec3 x0, g1, g2;        ///< current
  Vec3 x0_ref, g1_ref, g2_ref;  ///< reference
  double strain = 0;
  double force = 0;
};

/// One .vtu piece: points, point data, and cells given by connectivity/offsets/types.
struct VtuPiece {
  std::vector<double> points;         ///< 3 per point
  std::vector<double> displacement;   ///< 3 per point
  std::vector<double> axial_strain;   ///< 1 per point
  std::vector<double> axial_force;    ///< 1 per point
  std::vector<double> g1;             ///< 3 per point
  std::vector<double> g2;             ///< 3 per point
  std::vector<std::int32_t> fiber;    ///< 1 per point
  std::vector<std::int32_t> node;     ///< 1 per point (local node index in the fiber)
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;
  std::vector<std::uint8_t> types;

  /// Appends one point of node `node` of fiber `fiber` with the node's state.
  void add_point(const Vec3& x, const Vec3& u, const NodeState& s, size_t fiber_index, Index node_index) {
    push3(points, x);
    push3(displacement, u);
    axial_strain.push_back(s.strain);
    axial_force.push_back(s.force);
    push3(g1, s.g1);
    push3(g2, s.g2);
    fiber.push_back(static_cast<std::int32_t>(fiber_index));
    node.push_back(static_cast<std::int32_t>(node_index));
  }

  void reserve(size_t n_points) {
    points.reserve(3 * n_points);
    displacement.reserve(3 * n_points);
    axial_strain.reserve(n_points);
    axial_force.reserve(n_points);
    g1.reserve(3 * n_points);
    g2.reserve(3 * n_points);
    fiber.reserve(n_points);
    node.reserve(n_points);
  }
};


/// Writes one .vtu with the given point data, points and cells (appended raw binary).
/// `cell_data` (optional) is written as CellData with `cell_scalars` as its active scalars.
void write_vtu_arrays(const std::string& path, double time, size_t n_points, size_t n_cells,
                      const std::vector<VtuArray>& point_data, const std::vector<VtuArray>& points,
                      const std::vector<VtuArray>& cells, std::string_view scalars, std::string_view vectors,
                      const std::vector<VtuArray>& cell_data = {}, std::string_view cell_scalars = {}) {
  const std::vector<double> time_value{time};
  std::vector<VtuArray> field = {vtu_array("TimeValue", "Float64", 1, time_value)};
  std::uint64_t offset = 0;
  std::vector<const VtuArray*> order;
  std::string xml;
  auto add = [&](const std::vector<VtuArray>& arrays, std::string_view indent, bool tuples) {
    for (const VtuArray& a : arrays) {
      xml += fmt::format("{}<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"{} format=\"appended\" offset=\"{}\"/>\n",
                         indent, a.type, xml_attr(a.name), a.components,
                         tuples ? fmt::format(" NumberOfTuples=\"{}\"", a.tuples) : std::string(), offset);
      offset += sizeof(std::uint64_t) + a.bytes;
      order.push_back(&a);
    }
  };
  const char* byte_order = std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
  xml += "<?xml version=\"1.0\"?>\n";
  xml += fmt::format("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" header_type=\"UInt64\">\n",
                     byte_order);
  xml += "  <UnstructuredGrid>\n    <FieldData>\n";
  add(field, "      ", true);
  xml += "    </FieldData>\n";
  xml += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n_points, n_cells);
  xml += fmt::format("      <PointData Scalars=\"{}\" Vectors=\"{}\">\n", scalars, vectors);
  add(point_data, "        ", false);
  xml += "      </PointData>\n";
  if (!cell_data.empty()) {
    xml += fmt::format("      <CellData Scalars=\"{}\">\n", cell_scalars);
    add(cell_data, "        ", false);
    xml += "      </CellData>\n";
  }
  xml += "      <Points>\n";
  add(points, "        ", false);
  xml += "      </Points>\n      <Cells>\n";
  add(cells, "        ", false);
  xml += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";

  write_atomic(path, [&](CheckedFile& f) {
    f.write(xml);
    for (const VtuArray* a : order) {
      const std::uint64_t bytes = a->bytes;
      f.write(&bytes, sizeof bytes);
      f.write(a->data, a->bytes);
    }
    f.write("\n  </AppendedData>\n</VTKFile>\n");
  });
}

void write_vtu_file(const std::string& path, const VtuPiece& p, double time) {
  std::vector<VtuArray> point_data = {
      vtu_array("displacement", "Float64", 3, p.displacement),
      vtu_array("axial_strain", "Float64", 1, p.axial_strain),
      vtu_array("axial_force", "Float64", 1, p.axial_force),
      vtu_array("g1", "Float64", 3, p.g1),
      vtu_array("g2", "Float64", 3, p.g2),
      vtu_array("fiber", "Int32", 1, p.fiber),
      vtu_array("node", "Int32", 1, p.node),
  };
  std::vector<VtuArray> points = {vtu_array("Points", "Float64", 3, p.points)};
  std::vector<VtuArray> cells = {
      vtu_array("connectivity", "Int64", 1, p.connectivity),
      vtu_array("offsets", "Int64", 1, p.offsets),
      vtu_array("types", "UInt8", 1, p.types),
  };
  write_vtu_arrays(path, time, p.axial_strain.size(), p.types.size(), point_data, points, cells, "axial_force",
                   "displacement");
}


constexpr std::uint8_t kVtkVertex = 1;
constexpr std::uint8_t kVtkLine = 3;
constexpr std::uint8_t kVtkPolyLine = 4;
constexpr std::uint8_t kVtkQuad = 9;

}  // namespace

void OutputWriter::FileCloser::operator()(std::FILE* f) const {
  if (f) std::fclose(f);
}

void prepare_output_dir(const std::string& dir_in, const std::vector<std::string>& subdirs) {
  const fs::path dir = dir_in.empty() ? fs::path(".") : fs::path(dir_in);
  std::vector<fs::path> dirs = {dir};
  for (const std::string& sub : subdirs) dirs.push_back(dir / sub);
  for (const fs::path& d : dirs) {
    std::error_code ec;
    if (fs::exists(d, ec) && !fs::is_directory(d, ec))
      throw InputError(d.string(), "(output directory)",
                       d == dir ? "exists and is not a directory: expected a directory to write the results into "
                                  "(give another --out directory)"
                                : "exists and is not a directory: the run writes into this subfolder of the "
                                  "output directory (remove the file or give another --out directory)");
    // A missing subfolder is made when the run first writes into it (the directory takes it).
    if (d != dir && !fs::exists(d, ec)) continue;
    fs::create_directories(d, ec);
    if (ec || !fs::is_directory(d, ec))
      throw InputError(d.string(), "(output directory)",
                       fmt::format("cannot create the directory: {} (give another --out directory)",
                                   ec ? ec.message() : "not a directory"));
    check_writable(d);
  }
}

namespace {
/// The ParaView series, each in a subfolder of its name.
const std::vector<std::string>& series_names() {
  static const std::vector<std::string> names = {"fibers", "lines", "contacts", "bodies"};
  return names;
}
}  // namespace

OutputWriter::OutputWriter(std::string dir, const Model& model, std::vector<std::string> extra_columns, int tube_sides)
    : m_dir(std::move(dir)), m_model(model), m_extra_columns(std::move(extra_columns)), m_tube_sides(tube_sides) {
  if (m_tube_sides < 3) throw RunError(fmt::format("output: tube_sides must be at least 3, got {}", m_tube_sides));
  if (m_dir.empty()) m_dir = ".";
  prepare_output_dir(m_dir, {"fibers", "lines"});

  // Remove what a previous run in this directory left, so that no stale collection,
  // summary or numbered .vtu can be mistaken for output of this run.
  std::error_code ec;
  fs::remove_all(path("state"), ec);  // the states at step ends, for runs that go on from them
  for (const char* name :
       {"fibers.pvd", "lines.pvd", "contacts.pvd", "bodies.pvd", "nodes.csv", "summary.json"})
    fs::remove(path(name), ec);
  static const std::regex curves(R"(curves_.*\.csv)");
  std::vector<fs::path> folders = {fs::path(m_dir)};
  for (const std::string& series : series_names()) folders.push_back(fs::path(m_dir) / series);
  for (const fs::path& folder : folders) {
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (std::regex_match(name, numbered_file()) || (folder == fs::path(m_dir) && std::regex_match(name, curves))) {
        std::error_code rm;
        fs::remove(it->path(), rm);
      }
    }
    ec.clear();
  }

  const std::string history = path("history.csv");
  errno = 0;
  m_history.reset(std::fopen(history.c_str(), "wb"));
  if (!m_history) io_fail("cannot open for writing", history, errno);
  std::string header = "step,step_index,increment,load_factor,iterations,residual,wall_time";
  for (const std::string& c : m_extra_columns) header += "," + csv_field(c);
  header += "\n";
  errno = 0;
  if (std::fwrite(header.data(), 1, header.size(), m_history.get()) != header.size() ||
      std::fflush(m_history.get()) != 0)
    io_fail("cannot write", history, errno);
}

OutputWriter::OutputWriter(std::string dir, const Model& model, std::vector<std::string> extra_columns, int tube_sides,
                           const nlohmann::json& resume)
    : m_dir(std::move(dir)), m_model(model), m_extra_columns(std::move(extra_columns)), m_tube_sides(tube_sides) {
  if (m_tube_sides < 3) throw RunError(fmt::format("output: tube_sides must be at least 3, got {}", m_tube_sides));
  if (m_dir.empty()) m_dir = ".";
  prepare_output_dir(m_dir, {"fibers", "lines"});
  auto entries = [&resume](const char* key) {
    PvdEntries out;
    for (const nlohmann::json& e : resume.at(key)) out.emplace_back(e.at(0).get<double>(), e.at(1).get<int>());
    return out;
  };
  m_vtu_files = entries("vtu");
  m_contact_files = entries("contacts");
  m_body_files = entries("bodies");
  // history.csv back to its rows at the checkpoint: those a killed run wrote after it are
  // written again.
  const std::string history = path("history.csv");
  const auto bytes = resume.at("history_bytes").get<std::uintmax_t>();
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(history, ec);
  if (ec || size < bytes)
    throw InputError(history, "(file)",
                     fmt::format("{} than at the checkpoint ({} bytes): the output directory was changed since; run "
                                 "the case again without --resume",
                                 ec ? "missing, or not readable: it must be as long as" : "shorter", bytes));
  fs::resize_file(history, bytes, ec);
  if (ec) io_fail("cannot cut back", history, ec.value());
  errno = 0;
  m_history.reset(std::fopen(history.c_str(), "ab"));
  if (!m_history) io_fail("cannot open for writing", history, errno);
  // Numbered files past the checkpoint's: written again, or not at all.
  const int next = vtu_count();
  for (const std::string& series : series_names()) {
    const fs::path folder = fs::path(m_dir) / series;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      std::smatch m;
      if (std::regex_match(name, m, numbered_file()) && std::stoi(m[2].str()) >= next) {
        std::error_code rm;
        fs::remove(it->path(), rm);
      }
    }
    ec.clear();
  }
  write_pvd("fibers.pvd", "fibers", m_vtu_files);
  write_pvd("lines.pvd", "lines", m_vtu_files);
  if (!m_contact_files.empty()) write_pvd("contacts.pvd", "contacts", m_contact_files);
  if (!m_body_files.empty()) write_pvd("bodies.pvd", "bodies", m_body_files);
}

nlohmann::json OutputWriter::resume_point() const {
  auto entries = [](const PvdEntries& files) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& [time, index] : files) out.push_back({time, index});
    return out;
  };
  errno = 0;
  const long bytes = std::ftell(m_history.get());
  if (bytes < 0) io_fail("cannot tell the length of", path("history.csv"), errno);
  return {{"history_bytes", bytes},
          {"vtu", entries(m_vtu_files)},
          {"contacts", entries(m_contact_files)},
          {"bodies", entries(m_body_files)}};
}

OutputWriter::~OutputWriter() = default;

std::string OutputWriter::path(const std::string& name) const { return (fs::path(m_dir) / name).string(); }

std::string OutputWriter::series_file(const std::string& series, int index) {
  return fmt::format("{}/{}_{:06d}.vtu", series, series, index);
}

std::string OutputWriter::series_path(const std::string& series, int index) const {
  const fs::path folder = fs::path(m_dir) / series;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    fs::create_directories(folder, ec);
    if (ec) io_fail("cannot create the directory", folder.string(), ec.value());
  }
  return path(series_file(series, index));
}

void OutputWriter::check_state(const VecX& q) const {
  if (q.size() != m_model.num_dofs())
    throw RunError(fmt::format("output: state has {} values, the model has {} dofs", q.size(), m_model.num_dofs()));
}

void OutputWriter::write_increment(const VecX& q, const HistoryRow& row, double time, bool write_vtu_files,
                                   const std::vector<ContactPoint>* contacts,
                                   const std::vector<BodyPoint>* bodies) {
  check_state(q);
  write_history_row(row);
  if (!write_vtu_files) return;
  const int index = vtu_count();
  const bool with_bodies = bodies && !bodies->empty();
  write_vtu(q, index, time);
  if (contacts) write_contacts(*contacts, index, time);
  if (with_bodies) write_bodies(*bodies, index, time);
  // Each collection lists only the files written for it, so an increment written without
  // contacts or bodies (e.g. the reference state) leaves no dangling DataSet behind.
  m_vtu_files.emplace_back(time, index);
  if (contacts) m_contact_files.emplace_back(time, index);
  if (with_bodies) m_body_files.emplace_back(time, index);
  write_pvd("fibers.pvd", "fibers", m_vtu_files);
  write_pvd("lines.pvd", "lines", m_vtu_files);
  if (contacts) write_pvd("contacts.pvd", "contacts", m_contact_files);
  if (with_bodies) write_pvd("bodies.pvd", "bodies", m_body_files);
}

void OutputWriter::write_contacts(const std::vector<ContactPoint>& contacts, int index, double time) const {
  const size_t n = contacts.size();
  std::vector<double> points, normal, friction, gap, force;
  std::vector<std::int32_t> slip, zone;
  std::vector<std::int64_t> connectivity(n), offsets(n);
  std::vector<std::uint8_t> types(n, 1);  // VTK_VERTEX
  points.reserve(3 * n);
  for (size_t k = 0; k < n; ++k) {
    const ContactPoint& c = contacts[k];
    push3(points, c.position);
    push3(normal, c.normal);
    push3(friction, c.friction);
    gap.push_back(c.gap);
    force.push_back(c.normal_force);
    slip.push_back(c.slip ? 1 : 0);
    zone.push_back(c.zone);
    connectivity[k] = static_cast<std::int64_t>(k);
    offsets[k] = static_cast<std::int64_t>(k + 1);
  }
  std::vector<VtuArray> point_data = {
      vtu_array("gap", "Float64", 1, gap),           vtu_array("normal_force", "Float64", 1, force),
      vtu_array("friction", "Float64", 3, friction), vtu_array("normal", "Float64", 3, normal),
      vtu_array("slip", "Int32", 1, slip),           vtu_array("zone", "Int32", 1, zone),
  };
  std::vector<VtuArray> pts = {vtu_array("Points", "Float64", 3, points)};
  std::vector<VtuArray> cells = {vtu_array("connectivity", "Int64", 1, connectivity),
                                 vtu_array("offsets", "Int64", 1, offsets), vtu_array("types", "UInt8", 1, types)};
  write_vtu_arrays(series_path("contacts", index), time, n, n, point_data, pts, cells, "normal_force",
                   "normal");
}

void OutputWriter::write_bodies(const std::vector<BodyPoint>& bodies, int index, double time) const {
  // Points: the body centres, then the members of body 0, body 1, ...
  // Cells: one vertex per centre, then one line from each centre to each of its members.
  const size_t n_bodies = bodies.size();
  if (n_bodies > static_cast<size_t>(std::numeric_limits<std::int32_t>::max()))
    throw RunError(fmt::format("output: too many bodies ({})", n_bodies));
  size_t n_members = 0;
  for (const BodyPoint& b : bodies) n_members += b.members.size();
  const size_t n_points = n_bodies + n_members;
  const size_t n_cells = n_bodies + n_members;

  std::vector<double> points, d1, d2, d3, displacement, rotation, force, moment;
  for (std::vector<double>* v : {&points, &d1, &d2, &d3, &displacement, &rotation, &force, &moment})
    v->reserve(3 * n_points);
  std::vector<std::int32_t> body;
  body.reserve(n_points);
  std::vector<std::int64_t> connectivity, offsets;
  connectivity.reserve(n_bodies + 2 * n_members);
  offsets.reserve(n_cells);
  std::vector<std::uint8_t> types;
  types.reserve(n_cells);
  std::vector<std::int32_t> kind;
  kind.reserve(n_cells);

  auto add_point = [&](const Vec3& x, const BodyPoint& b, size_t k) {
    push3(points, x);
    push3(d1, b.frame.col(0));
    push3(d2, b.frame.col(1));
    push3(d3, b.frame.col(2));
    push3(displacement, b.displacement);
    push3(rotation, b.rotation);
    push3(force, b.force);
    push3(moment, b.moment);
    body.push_back(static_cast<std::int32_t>(k));
  };
  for (size_t k = 0; k < n_bodies; ++k) {
    add_point(bodies[k].center, bodies[k], k);
    connectivity.push_back(static_cast<std::int64_t>(k));
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    types.push_back(kVtkVertex);
    kind.push_back(0);
  }
  for (size_t k = 0; k < n_bodies; ++k) {
    for (const Vec3& x : bodies[k].members) {
      const auto member = static_cast<std::int64_t>(body.size());
      add_point(x, bodies[k], k);
      connectivity.insert(connectivity.end(), {static_cast<std::int64_t>(k), member});
      offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
      types.push_back(kVtkLine);
      kind.push_back(1);
    }
  }

  std::vector<VtuArray> point_data = {
      vtu_array("body", "Int32", 1, body),
      vtu_array("D1", "Float64", 3, d1),
      vtu_array("D2", "Float64", 3, d2),
      vtu_array("D3", "Float64", 3, d3),
      vtu_array("displacement", "Float64", 3, displacement),
      vtu_array("rotation", "Float64", 3, rotation),
      vtu_array("force", "Float64", 3, force),
      vtu_array("moment", "Float64", 3, moment),
  };
  std::vector<VtuArray> pts = {vtu_array("Points", "Float64", 3, points)};
  std::vector<VtuArray> cells = {vtu_array("connectivity", "Int64", 1, connectivity),
                                 vtu_array("offsets", "Int64", 1, offsets), vtu_array("types", "UInt8", 1, types)};
  std::vector<VtuArray> cell_data = {vtu_array("kind", "Int32", 1, kind)};
  write_vtu_arrays(series_path("bodies", index), time, n_points, n_cells, point_data, pts, cells,
                   "body", "force", cell_data, "kind");
}

void OutputWriter::write_history_row(const HistoryRow& row) {
  if (row.extra.size() != m_extra_columns.size())
    throw RunError(fmt::format("output: history row has {} extra values for {} extra columns", row.extra.size(),
                               m_extra_columns.size()));
  std::string line = fmt::format("{},{},{},{},{},{},{}", csv_field(row.step), row.step_index, row.increment,
                                 row.load_factor, row.iterations, row.residual, row.wall_time);
  for (double v : row.extra) line += fmt::format(",{}", v);
  line += "\n";
  // One write and an immediate flush: a killed run keeps every completed row.
  errno = 0;
  if (std::fwrite(line.data(), 1, line.size(), m_history.get()) != line.size() ||
      std::fflush(m_history.get()) != 0)
    io_fail("cannot write", path("history.csv"), errno);
}

void OutputWriter::write_vtu(const VecX& q, int index, double time) const {
  const Index n_nodes = m_model.num_nodes();
  const VecX& ref = m_model.reference;

  // Nodal states: position, section vectors and the axial state (averaged over the two
  // elements that share an end node).
  std::vector<NodeState> nodes(static_cast<size_t>(n_nodes));
  for (Index k = 0; k < n_nodes; ++k) {
    NodeState& s = nodes[k];
    s.x0 = q.segment<3>(9 * k);
    s.g1 = q.segment<3>(9 * k + 3);
    s.g2 = q.segment<3>(9 * k + 6);
    s.x0_ref = ref.segment<3>(9 * k);
    s.g1_ref = ref.segment<3>(9 * k + 3);
    s.g2_ref = ref.segment<3>(9 * k + 6);
  }
  for (const Fiber& fib : m_model.fibers) {
    std::vector<int> count(static_cast<size_t>(fib.num_nodes), 0);
    for (Index e = 0; e < fib.num_elements; ++e) {
      const BeamElement& el = m_model.elements[fib.first_element + e];
      const Section& sec = m_model.sections[el.section];
      for (int a = 0; a < kElementNodes; ++a) {
        const Index local = 2 * e + a;
        const AxialState st = beam_axial_state(el, sec, q.data() + el.first_dof, static_cast<double>(a - 1));
        NodeState& s = nodes[fib.first_node + local];
        s.strain += st.strain;
        s.force += st.force;
        ++count[local];
      }
    }
    for (Index j = 0; j < fib.num_nodes; ++j) {
      if (count[j] > 1) {
        nodes[fib.first_node + j].strain /= count[j];
        nodes[fib.first_node + j].force /= count[j];
      }
    }
  }

  // Centroid lines: one poly-line per fiber through its nodes.
  VtuPiece lines;
  lines.reserve(static_cast<size_t>(n_nodes));
  for (size_t f = 0; f < m_model.fibers.size(); ++f) {
    const Fiber& fib = m_model.fibers[f];
    for (Index j = 0; j < fib.num_nodes; ++j) {
      const NodeState& s = nodes[fib.first_node + j];
      lines.add_point(s.x0, s.x0 - s.x0_ref, s, f, j);
      lines.connectivity.push_back(fib.first_node + j);
    }
    if (fib.num_nodes >= 2) {
      lines.offsets.push_back(static_cast<std::int64_t>(lines.connectivity.size()));
      lines.types.push_back(kVtkPolyLine);
    } else {
      lines.connectivity.resize(lines.connectivity.size() - static_cast<size_t>(fib.num_nodes));
    }
  }

  // Tube surfaces: a ring of points per node at x0 + a cos(t) g1 + b sin(t) g2, quads
  // between consecutive rings of a fiber (outward normals when g1 x g2 points along the fiber).
  const int n_sides = m_tube_sides;
  std::vector<double> cos_t(n_sides), sin_t(n_sides);
  for (int i = 0; i < n_sides; ++i) {
    const double t = 2.0 * std::numbers::pi * i / n_sides;
    cos_t[i] = std::cos(t);
    sin_t[i] = std::sin(t);
  }
  VtuPiece tubes;
  tubes.reserve(static_cast<size_t>(n_nodes * n_sides));
  for (size_t f = 0; f < m_model.fibers.size(); ++f) {
    const Fiber& fib = m_model.fibers[f];
    const Section& sec = m_model.sections[fib.section];
    const std::int64_t base = static_cast<std::int64_t>(tubes.fiber.size());
    for (Index j = 0; j < fib.num_nodes; ++j) {
      const NodeState& s = nodes[fib.first_node + j];
      for (int i = 0; i < n_sides; ++i) {
        const Vec3 offset = sec.a * cos_t[i] * s.g1 + sec.b * sin_t[i] * s.g2;
        const Vec3 offset_ref = sec.a * cos_t[i] * s.g1_ref + sec.b * sin_t[i] * s.g2_ref;
        tubes.add_point(s.x0 + offset, (s.x0 + offset) - (s.x0_ref + offset_ref), s, f, j);
      }
    }
    for (Index j = 0; j + 1 < fib.num_nodes; ++j) {
      const std::int64_t r0 = base + j * n_sides, r1 = r0 + n_sides;
      for (int i = 0; i < n_sides; ++i) {
        const int i1 = (i + 1) % n_sides;
        tubes.connectivity.insert(tubes.connectivity.end(), {r0 + i, r0 + i1, r1 + i1, r1 + i});
        tubes.offsets.push_back(static_cast<std::int64_t>(tubes.connectivity.size()));
        tubes.types.push_back(kVtkQuad);
      }
    }
  }

  write_vtu_file(series_path("fibers", index), tubes, time);
  write_vtu_file(series_path("lines", index), lines, time);
}

void OutputWriter::write_pvd(const std::string& name, const std::string& prefix, const PvdEntries& entries) const {
  std::string xml = "<?xml version=\"1.0\"?>\n";
  xml += fmt::format("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"{}\">\n",
                     std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian");
  xml += "  <Collection>\n";
  for (const auto& [time, index] : entries)
    xml += fmt::format("    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n", time,
                       xml_attr(series_file(prefix, index)));
  xml += "  </Collection>\n</VTKFile>\n";
  write_atomic(path(name), [&](CheckedFile& f) { f.write(xml); });
}

void OutputWriter::write_nodes(const VecX& q) const {
  check_state(q);
  const std::string text = nodes_csv_text(m_model, q);
  write_atomic(path("nodes.csv"), [&](CheckedFile& f) { f.write(text); });
}

void OutputWriter::write_summary(const nlohmann::json& summary) const {
  const std::string text = summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  write_atomic(path("summary.json"), [&](CheckedFile& f) { f.write(text); });
}

}  // namespace fibra
