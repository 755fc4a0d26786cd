/// Tests of the output layer: history.csv, nodes.csv, .vtu/.pvd and summary.json.
#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fibra/core/error.hpp"
#include "fibra/io/output_writer.hpp"
#include "fibra/model/model.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

/// One steel-like straight fiber "beam" of 2 elements along x, length 1, radius 0.01.
Model make_model() {
  Case c;
  c.file = "test";
  c.name = "test";
  MaterialSpec m;
  m.name = "mat";
  m.model = MaterialSpec::Model::Isotropic;
  m.young = 1e9;
  m.poisson = 0.3;
  c.materials.push_back(m);
  FiberSpec f;
  f.name = "beam";
  f.material = "mat";
  f.radius = 0.01;
  f.semi_axis_1 = 0.01;
  f.semi_axis_2 = 0.01;
  f.path.kind = PathSpec::Kind::Polyline;
  f.path.points = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  f.elements = 2;
  c.fibers.push_back(f);
  return build_model(c);
}

/// A deformed state: uniform 1% stretch along x plus a translation, g1 scaled by 1.05.
VecX deformed_state(const Model& model, double scale = 1.0) {
  VecX q = model.reference;
  for (Index k = 0; k < model.num_nodes(); ++k) {
    const Vec3 x = model.reference.segment<3>(9 * k);
    q.segment<3>(9 * k) = Vec3(x[0] * (1 + 0.01 * scale), 0, 0) + scale * Vec3(0.1, 0.2, 0.3);
    q.segment<3>(9 * k + 3) *= 1 + 0.05 * scale;
  }
  return q;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  EXPECT_TRUE(in.good()) << p;
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> read_lines(const fs::path& p) {
  std::vector<std::string> lines;
  std::istringstream in(read_text(p));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

/// Value of attribute `name` inside the XML tag text `tag`.
std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const size_t p = tag.find(key);
  if (p == std::string::npos) return {};
  const size_t b = p + key.size();
  return tag.substr(b, tag.find('"', b) - b);
}

/// A minimal reader of the .vtu files written by OutputWriter (appended raw, UInt64 headers).
struct Vtu {
  size_t points = 0;
  size_t cells = 0;
  std::map<std::string, std::string> types;    ///< array name -> VTK type
  std::map<std::string, int> components;       ///< array name -> components
  std::map<std::string, std::string> raw;      ///< array name -> bytes

  template <class T>
  std::vector<T> get(const std::string& name) const {
    const std::string& bytes = raw.at(name);
    std::vector<T> v(bytes.size() / sizeof(T));
    std::memcpy(v.data(), bytes.data(), v.size() * sizeof(T));
    return v;
  }
};

Vtu read_vtu(const fs::path& p) {
  const std::string text = read_text(p);
  Vtu vtu;
  EXPECT_NE(text.find("<VTKFile type=\"UnstructuredGrid\""), std::string::npos);
  EXPECT_NE(text.find("header_type=\"UInt64\""), std::string::npos);
  const size_t appended = text.find("<AppendedData encoding=\"raw\">");
  EXPECT_NE(appended, std::string::npos);
  const size_t base = text.find('_', appended) + 1;
  const std::string xml = text.substr(0, appended);
  const size_t piece = xml.find("<Piece ");
  const std::string piece_tag = xml.substr(piece, xml.find('>', piece) - piece);
  vtu.points = std::stoull(attribute(piece_tag, "NumberOfPoints"));
  vtu.cells = std::stoull(attribute(piece_tag, "NumberOfCells"));
  for (size_t pos = xml.find("<DataArray"); pos != std::string::npos; pos = xml.find("<DataArray", pos + 1)) {
    const std::string tag = xml.substr(pos, xml.find('>', pos) - pos);
    const std::string name = attribute(tag, "Name");
    EXPECT_EQ(attribute(tag, "format"), "appended");
    const size_t offset = std::stoull(attribute(tag, "offset"));
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, text.data() + base + offset, sizeof bytes);
    EXPECT_LE(base + offset + 8 + bytes, text.size());
    vtu.raw[name] = text.substr(base + offset + 8, bytes);
    vtu.types[name] = attribute(tag, "type");
    vtu.components[name] = std::stoi(attribute(tag, "NumberOfComponents"));
  }
  EXPECT_NE(text.find("</AppendedData>\n</VTKFile>"), std::string::npos);
  return vtu;
}

/// (timestep, file) entries of a .pvd collection.
std::vector<std::pair<double, std::string>> read_pvd(const fs::path& p) {
  const std::string text = read_text(p);
  EXPECT_NE(text.find("<VTKFile type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.find("</Collection>"), std::string::npos);
  std::vector<std::pair<double, std::string>> out;
  for (size_t pos = text.find("<DataSet"); pos != std::string::npos; pos = text.find("<DataSet", pos + 1)) {
    const std::string tag = text.substr(pos, text.find('>', pos) - pos);
    out.emplace_back(std::stod(attribute(tag, "timestep")), attribute(tag, "file"));
  }
  return out;
}

class OutputWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    m_dir = fs::temp_directory_path() /
            ("fibra_test_output_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(m_dir);
  }
  void TearDown() override { fs::remove_all(m_dir); }
  fs::path m_dir;
};

HistoryRow row(int increment, double load_factor, std::vector<double> extra) {
  HistoryRow r;
  r.step = "pull";
  r.step_index = 0;
  r.increment = increment;
  r.load_factor = load_factor;
  r.iterations = 3 + increment;
  r.residual = 1.5e-10;
  r.wall_time = 0.25 * increment;
  r.extra = std::move(extra);
  return r;
}

TEST_F(OutputWriterTest, HistoryHeaderAndRowsAreFlushedAtOnce) {
  const Model model = make_model();
  // Created with parents.
  OutputWriter out((m_dir / "a" / "b").string(), model, {"reaction:beam:first:x", "displacement:beam:last:x"}, 8);
  EXPECT_EQ(out.dir(), (m_dir / "a" / "b").string());
  const fs::path history = m_dir / "a" / "b" / "history.csv";
  auto lines = read_lines(history);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0],
            "step,step_index,increment,load_factor,iterations,residual,wall_time,reaction:beam:first:x,"
            "displacement:beam:last:x");

  out.write_increment(model.reference, row(1, 0.5, {-12.5, 0.125}), 0.5, false);
  out.write_increment(model.reference, row(2, 1.0, {-25.0, 1.0 / 3.0}), 1.0, false);
  // Read while the writer is still alive: every row must already be on disk.
  lines = read_lines(history);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[1], "pull,0,1,0.5,4,1.5e-10,0.25,-12.5,0.125");
  const auto cols = split(lines[2], ',');
  ASSERT_EQ(cols.size(), 9u);
  EXPECT_EQ(cols[0], "pull");
  EXPECT_EQ(std::stoi(cols[2]), 2);
  EXPECT_EQ(std::stod(cols[3]), 1.0);
  EXPECT_EQ(std::stod(cols[8]), 1.0 / 3.0);  // full precision round trip
  EXPECT_FALSE(fs::exists(m_dir / "a" / "b" / "fibers.pvd"));

  // A row with the wrong number of extra values is refused.
  EXPECT_THROW(out.write_increment(model.reference, row(3, 1.0, {1.0}), 1.0, false), RunError);
}

TEST_F(OutputWriterTest, NodesCsvHoldsEveryNodeAtFullPrecision) {
  const Model model = make_model();
  ASSERT_EQ(model.fibers.size(), 1u);
  ASSERT_EQ(model.num_nodes(), 5);
  OutputWriter out(m_dir.string(), model, {}, 8);
  VecX q = deformed_state(model);
  q[9 * 3 + 1] = 1.0 / 7.0;
  out.write_nodes(q);
  const auto lines = read_lines(m_dir / "nodes.csv");
  ASSERT_EQ(lines.size(), 1u + 5u);
  EXPECT_EQ(lines[0], "fiber,node,x,y,z,g1x,g1y,g1z,g2x,g2y,g2z");
  for (Index j = 0; j < 5; ++j) {
    const auto cols = split(lines[1 + j], ',');
    ASSERT_EQ(cols.size(), 11u);
    EXPECT_EQ(cols[0], "beam");
    EXPECT_EQ(std::stoll(cols[1]), j);
    for (int d = 0; d < 9; ++d) EXPECT_EQ(std::stod(cols[2 + d]), q[9 * j + d]) << "node " << j << " dof " << d;
  }
  EXPECT_FALSE(fs::exists(m_dir / "nodes.csv.tmp"));
  EXPECT_THROW(out.write_nodes(VecX::Zero(7)), RunError);
}

TEST_F(OutputWriterTest, VtuAndPvdRoundTrip) {
  const Model model = make_model();
  const int sides = 8;
  OutputWriter out(m_dir.string(), model, {"f"}, sides);
  const VecX q0 = model.reference;
  const VecX q1 = deformed_state(model, 0.5);
  const VecX q2 = deformed_state(model, 1.0);
  out.write_increment(q0, row(0, 0.0, {0.0}), 0.0, true);
  out.write_increment(q1, row(1, 0.5, {1.0}), 0.5, false);
  out.write_increment(q2, row(2, 1.0, {2.0}), 1.0, true);
  EXPECT_EQ(out.vtu_count(), 2);

  // Collections list every written file, in order, with their time.
  for (const std::string prefix : {"fibers", "lines"}) {
    const auto entries = read_pvd(m_dir / (prefix + ".pvd"));
    ASSERT_EQ(entries.size(), 2u) << prefix;
    EXPECT_EQ(entries[0].first, 0.0);
    EXPECT_EQ(entries[0].second, prefix + "/" + prefix + "_000000.vtu");
    EXPECT_EQ(entries[1].first, 1.0);
    EXPECT_EQ(entries[1].second, prefix + "/" + prefix + "_000001.vtu");
    for (const auto& e : entries) EXPECT_TRUE(fs::exists(m_dir / e.second)) << e.second;
  }
  for (const auto& entry : fs::directory_iterator(m_dir))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();

  const Index n_nodes = model.num_nodes();
  const Section& sec = model.sections[model.fibers[0].section];

  // Tube surface of the deformed state.
  const Vtu tubes = read_vtu(m_dir / "fibers" / "fibers_000001.vtu");
  ASSERT_EQ(tubes.points, static_cast<size_t>(n_nodes * sides));
  ASSERT_EQ(tubes.cells, static_cast<size_t>((n_nodes - 1) * sides));
  EXPECT_EQ(tubes.types.at("displacement"), "Float64");
  EXPECT_EQ(tubes.components.at("displacement"), 3);
  EXPECT_EQ(tubes.types.at("fiber"), "Int32");
  const auto types = tubes.get<std::uint8_t>("types");
  const auto offsets = tubes.get<std::int64_t>("offsets");
  const auto conn = tubes.get<std::int64_t>("connectivity");
  ASSERT_EQ(types.size(), tubes.cells);
  ASSERT_EQ(offsets.size(), tubes.cells);
  ASSERT_EQ(conn.size(), 4 * tubes.cells);
  for (size_t c = 0; c < tubes.cells; ++c) {
    EXPECT_EQ(types[c], 9);  // VTK_QUAD
    EXPECT_EQ(offsets[c], static_cast<std::int64_t>(4 * (c + 1)));
  }
  for (std::int64_t v : conn) {
    EXPECT_GE(v, 0);
    EXPECT_LT(v, static_cast<std::int64_t>(tubes.points));
  }
  const auto pts = tubes.get<double>("Points");
  const auto disp = tubes.get<double>("displacement");
  const auto strain = tubes.get<double>("axial_strain");
  const auto force = tubes.get<double>("axial_force");
  const auto g1 = tubes.get<double>("g1");
  const auto fiber = tubes.get<std::int32_t>("fiber");
  ASSERT_EQ(pts.size(), 3 * tubes.points);
  ASSERT_EQ(disp.size(), 3 * tubes.points);
  ASSERT_EQ(strain.size(), tubes.points);
  ASSERT_EQ(force.size(), tubes.points);
  ASSERT_EQ(fiber.size(), tubes.points);
  for (Index j = 0; j < n_nodes; ++j) {
    for (int i = 0; i < sides; ++i) {
      const size_t p = static_cast<size_t>(j * sides + i);
      const double t = 2.0 * std::numbers::pi * i / sides;
      auto at = [&](const VecX& q) {
        return Vec3(q.segment<3>(9 * j) + sec.a * std::cos(t) * q.segment<3>(9 * j + 3) +
                    sec.b * std::sin(t) * q.segment<3>(9 * j + 6));
      };
      const Vec3 expected_x = at(q2);
      const Vec3 expected_u = at(q2) - at(model.reference);
      for (int d = 0; d < 3; ++d) {
        EXPECT_NEAR(pts[3 * p + d], expected_x[d], 1e-14);
        EXPECT_NEAR(disp[3 * p + d], expected_u[d], 1e-14);
        EXPECT_EQ(g1[3 * p + d], q2[9 * j + 3 + d]);
      }
      EXPECT_NEAR(strain[p], 0.01, 1e-9);
      EXPECT_TRUE(std::isfinite(force[p]));
      EXPECT_EQ(fiber[p], 0);
    }
  }

  // Centroid lines of the deformed state.
  const Vtu lines = read_vtu(m_dir / "lines" / "lines_000001.vtu");
  ASSERT_EQ(lines.points, static_cast<size_t>(n_nodes));
  ASSERT_EQ(lines.cells, 1u);
  EXPECT_EQ(lines.get<std::uint8_t>("types")[0], 4);  // VTK_POLY_LINE
  EXPECT_EQ(lines.get<std::int64_t>("offsets")[0], n_nodes);
  const auto line_conn = lines.get<std::int64_t>("connectivity");
  ASSERT_EQ(line_conn.size(), static_cast<size_t>(n_nodes));
  const auto line_pts = lines.get<double>("Points");
  const auto line_disp = lines.get<double>("displacement");
  const auto line_g2 = lines.get<double>("g2");
  const auto line_strain = lines.get<double>("axial_strain");
  for (Index j = 0; j < n_nodes; ++j) {
    EXPECT_EQ(line_conn[j], j);
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(line_pts[3 * j + d], q2[9 * j + d]);
      EXPECT_EQ(line_disp[3 * j + d], q2[9 * j + d] - model.reference[9 * j + d]);
      EXPECT_EQ(line_g2[3 * j + d], q2[9 * j + 6 + d]);
    }
    EXPECT_NEAR(line_strain[j], 0.01, 1e-9);
  }
  EXPECT_EQ(lines.get<double>("TimeValue").at(0), 1.0);

  // The reference state has zero displacement, strain and force.
  const Vtu ref = read_vtu(m_dir / "fibers" / "fibers_000000.vtu");
  for (double u : ref.get<double>("displacement")) EXPECT_EQ(u, 0.0);
  for (double e : ref.get<double>("axial_strain")) EXPECT_NEAR(e, 0.0, 1e-12);
  for (double n : ref.get<double>("axial_force")) EXPECT_NEAR(n, 0.0, 1e-6);
}

/// Two rigid bodies: "clamp" with 3 members and a rotated frame, "free" without members.
std::vector<BodyPoint> make_bodies(double scale = 1.0) {
  BodyPoint a;
  a.name = "clamp";
  a.center = Vec3(1.0, 2.0, 3.0) * scale;
  a.frame = Mat3::Identity();
  a.displacement = Vec3(0.1, 0.2, 0.3) * scale;
  a.rotation = Vec3(0.0, 0.0, 0.25) * scale;
  a.force = Vec3(-5.0, 6.5, 0.125) * scale;
  a.moment = Vec3(0.5, -0.25, 1.0) * scale;
  a.members = {Vec3(1.5, 2.0, 3.0), Vec3(1.0, 2.5, 3.0), Vec3(1.0, 2.0, 3.5)};
  BodyPoint b;
  b.name = "free";
  b.center = Vec3(-1.0, 0.0, 0.5);
  b.frame.col(0) = Vec3(0.0, 1.0, 0.0);  // rotated by 90 degrees about z
  b.frame.col(1) = Vec3(-1.0, 0.0, 0.0);
  b.frame.col(2) = Vec3(0.0, 0.0, 1.0);
  b.force = Vec3(1.0 / 3.0, 0.0, -2.0);
  b.moment = Vec3(0.0, 7.0, 0.0);
  return {a, b};
}

TEST_F(OutputWriterTest, BodiesVtuAndPvd) {
  const Model model = make_model();
  OutputWriter out(m_dir.string(), model, {}, 6);
  const std::vector<BodyPoint> bodies = make_bodies();
  // The reference state is written without bodies: no bodies files at all.
  out.write_increment(model.reference, row(0, 0.0, {}), 0.0, true);
  EXPECT_FALSE(fs::exists(m_dir / "bodies" / "bodies_000000.vtu"));
  EXPECT_FALSE(fs::exists(m_dir / "bodies.pvd"));
  // An empty list writes nothing either; an increment without vtu neither.
  const std::vector<BodyPoint> none;
  out.write_increment(model.reference, row(1, 0.25, {}), 0.25, false, nullptr, &bodies);
  out.write_increment(model.reference, row(2, 0.5, {}), 0.5, true, nullptr, &none);
  EXPECT_FALSE(fs::exists(m_dir / "bodies" / "bodies_000001.vtu"));
  EXPECT_FALSE(fs::exists(m_dir / "bodies.pvd"));
  EXPECT_EQ(out.vtu_count(), 2);

  // Numbered like the fibers file of the same increment.
  out.write_increment(deformed_state(model), row(3, 1.0, {}), 1.0, true, nullptr, &bodies);
  ASSERT_TRUE(fs::exists(m_dir / "fibers" / "fibers_000002.vtu"));
  ASSERT_TRUE(fs::exists(m_dir / "bodies" / "bodies_000002.vtu"));
  auto entries = read_pvd(m_dir / "bodies.pvd");
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].first, 1.0);
  EXPECT_EQ(entries[0].second, "bodies/bodies_000002.vtu");
  EXPECT_EQ(read_pvd(m_dir / "fibers.pvd").size(), 3u);

  const Vtu vtu = read_vtu(m_dir / "bodies" / "bodies_000002.vtu");
  ASSERT_EQ(vtu.points, 2u + 3u);
  ASSERT_EQ(vtu.cells, 2u + 3u);
  EXPECT_EQ(vtu.get<double>("TimeValue").at(0), 1.0);

  // Cells: vertices at the two centres, then a line from centre 0 to each member.
  EXPECT_EQ(vtu.types.at("types"), "UInt8");
  EXPECT_EQ(vtu.get<std::uint8_t>("types"), (std::vector<std::uint8_t>{1, 1, 3, 3, 3}));
  EXPECT_EQ(vtu.get<std::int64_t>("offsets"), (std::vector<std::int64_t>{1, 2, 4, 6, 8}));
  EXPECT_EQ(vtu.get<std::int64_t>("connectivity"), (std::vector<std::int64_t>{0, 1, 0, 2, 0, 3, 0, 4}));
  EXPECT_EQ(vtu.types.at("kind"), "Int32");
  EXPECT_EQ(vtu.get<std::int32_t>("kind"), (std::vector<std::int32_t>{0, 0, 1, 1, 1}));
  const std::string text = read_text(m_dir / "bodies" / "bodies_000002.vtu");
  const size_t cell_data = text.find("<CellData");
  ASSERT_NE(cell_data, std::string::npos);
  EXPECT_LT(text.find("</PointData>"), cell_data);
  EXPECT_LT(cell_data, text.find("Name=\"kind\""));
  EXPECT_LT(text.find("Name=\"kind\""), text.find("</CellData>"));
  EXPECT_LT(text.find("</CellData>"), text.find("<Points>"));

  // Points: centres, then the members of body 0.
  const auto pts = vtu.get<double>("Points");
  ASSERT_EQ(pts.size(), 3 * vtu.points);
  const std::vector<Vec3> expected_pts = {bodies[0].center, bodies[1].center, bodies[0].members[0],
                                          bodies[0].members[1], bodies[0].members[2]};
  for (size_t p = 0; p < expected_pts.size(); ++p)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(pts[3 * p + d], expected_pts[p][d]) << "point " << p;

  // Point data: every point carries the values of its body.
  EXPECT_EQ(vtu.get<std::int32_t>("body"), (std::vector<std::int32_t>{0, 1, 0, 0, 0}));
  const std::vector<size_t> owner = {0, 1, 0, 0, 0};
  for (const std::string name : {"D1", "D2", "D3", "displacement", "rotation", "force", "moment"}) {
    EXPECT_EQ(vtu.types.at(name), "Float64") << name;
    EXPECT_EQ(vtu.components.at(name), 3) << name;
    EXPECT_EQ(vtu.get<double>(name).size(), 3 * vtu.points) << name;
  }
  const auto d1 = vtu.get<double>("D1");
  const auto d2 = vtu.get<double>("D2");
  const auto force = vtu.get<double>("force");
  const auto moment = vtu.get<double>("moment");
  const auto disp = vtu.get<double>("displacement");
  const auto rot = vtu.get<double>("rotation");
  EXPECT_EQ(d1[3 * 1 + 0], 0.0);  // D1 of body 1
  EXPECT_EQ(d1[3 * 1 + 1], 1.0);
  EXPECT_EQ(d1[3 * 1 + 2], 0.0);
  EXPECT_EQ(d2[3 * 1 + 0], -1.0);
  for (size_t p = 0; p < owner.size(); ++p) {
    const BodyPoint& b = bodies[owner[p]];
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(d1[3 * p + d], b.frame(d, 0)) << "point " << p;
      EXPECT_EQ(force[3 * p + d], b.force[d]) << "point " << p;
      EXPECT_EQ(moment[3 * p + d], b.moment[d]) << "point " << p;
      EXPECT_EQ(disp[3 * p + d], b.displacement[d]) << "point " << p;
      EXPECT_EQ(rot[3 * p + d], b.rotation[d]) << "point " << p;
    }
  }
  EXPECT_EQ(force[3 * 1 + 0], 1.0 / 3.0);  // full precision
  EXPECT_EQ(force[3 * 0 + 1], 6.5);

  // A second increment with bodies adds a second DataSet.
  out.write_increment(deformed_state(model, 2.0), row(4, 1.0, {}), 2.0, true, nullptr, &bodies);
  entries = read_pvd(m_dir / "bodies.pvd");
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[1].first, 2.0);
  EXPECT_EQ(entries[1].second, "bodies/bodies_000003.vtu");
  for (const auto& e : entries) EXPECT_TRUE(fs::exists(m_dir / e.second)) << e.second;
  for (const auto& entry : fs::directory_iterator(m_dir))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();

  // A new writer in the same directory removes the bodies files of this run.
  OutputWriter again(m_dir.string(), model, {}, 6);
  EXPECT_FALSE(fs::exists(m_dir / "bodies.pvd"));
  EXPECT_FALSE(fs::exists(m_dir / "bodies" / "bodies_000002.vtu"));
}

TEST_F(OutputWriterTest, WithoutBodiesNoBodiesFiles) {
  const Model model = make_model();
  OutputWriter out(m_dir.string(), model, {}, 6);
  out.write_increment(model.reference, row(0, 0.0, {}), 0.0, true);
  out.write_increment(deformed_state(model), row(1, 1.0, {}), 1.0, true);
  EXPECT_TRUE(fs::exists(m_dir / "fibers" / "fibers_000001.vtu"));
  for (const auto& entry : fs::directory_iterator(m_dir))
    EXPECT_EQ(entry.path().filename().string().rfind("bodies", 0), std::string::npos) << entry.path();
}

TEST_F(OutputWriterTest, ContactsPvdListsOnlyWrittenFiles) {
  const Model model = make_model();
  OutputWriter out(m_dir.string(), model, {}, 6);
  // The reference state is written without contacts (as the run does).
  out.write_increment(model.reference, row(0, 0.0, {}), 0.0, true);
  std::vector<ContactPoint> contacts(1);
  contacts[0].normal_force = 2.5;
  out.write_increment(deformed_state(model), row(1, 1.0, {}), 1.0, true, &contacts);
  EXPECT_FALSE(fs::exists(m_dir / "contacts" / "contacts_000000.vtu"));
  const auto entries = read_pvd(m_dir / "contacts.pvd");
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].second, "contacts/contacts_000001.vtu");
  const Vtu vtu = read_vtu(m_dir / entries[0].second);
  EXPECT_EQ(vtu.points, 1u);
  EXPECT_EQ(vtu.get<double>("normal_force").at(0), 2.5);
}

TEST_F(OutputWriterTest, SummaryJsonParses) {
  const Model model = make_model();
  OutputWriter out(m_dir.string(), model, {}, 12);
  nlohmann::json s;
  s["status"] = "converged";
  s["message"] = "done";
  s["stopped_at"] = {{"step", "pull"}, {"load_factor", 1.0}, {"residual_history", {1.0, 1e-3, 1e-9}}};
  s["counts"] = {{"fibers", 1}, {"nodes", 5}, {"dofs", 45}, {"elements", 2}};
  s["timings"] = {{"total", 0.5}, {"assembly", 0.1}, {"factorization", 0.1}, {"solve", 0.05}, {"output", 0.01}};
  out.write_summary(s);
  const nlohmann::json back = nlohmann::json::parse(read_text(m_dir / "summary.json"));
  EXPECT_EQ(back, s);
  EXPECT_EQ(back["counts"]["dofs"], 45);
  EXPECT_FALSE(fs::exists(m_dir / "summary.json.tmp"));
  // Rewriting replaces the file.
  s["status"] = "failed";
  out.write_summary(s);
  EXPECT_EQ(nlohmann::json::parse(read_text(m_dir / "summary.json"))["status"], "failed");
}

TEST_F(OutputWriterTest, StaleOutputOfAPreviousRunIsRemoved) {
  const Model model = make_model();
  {
    OutputWriter out(m_dir.string(), model, {}, 6);
    for (int i = 0; i < 3; ++i) out.write_increment(model.reference, row(i, 0.1 * i, {}), i, true);
    out.write_summary(nlohmann::json{{"status", "converged"}});
  }
  ASSERT_TRUE(fs::exists(m_dir / "fibers" / "fibers_000002.vtu"));
  OutputWriter out(m_dir.string(), model, {}, 6);
  EXPECT_FALSE(fs::exists(m_dir / "fibers" / "fibers_000002.vtu"));
  EXPECT_FALSE(fs::exists(m_dir / "lines" / "lines_000000.vtu"));
  EXPECT_FALSE(fs::exists(m_dir / "fibers.pvd"));
  EXPECT_FALSE(fs::exists(m_dir / "summary.json"));
  EXPECT_EQ(read_lines(m_dir / "history.csv").size(), 1u);
}

TEST_F(OutputWriterTest, UnwritableDirectoryIsAnInputErrorNamingThePath) {
  const Model model = make_model();
  fs::create_directories(m_dir);
  std::ofstream(m_dir / "plain_file") << "x";
  try {
    OutputWriter out((m_dir / "plain_file" / "sub").string(), model, {}, 12);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("plain_file"), std::string::npos) << e.what();
    EXPECT_EQ(e.key(), "(output directory)");
  }
  EXPECT_THROW(OutputWriter((m_dir / "plain_file").string(), model, {}, 12), InputError);
  // A file in place of a series' subfolder.
  fs::create_directories(m_dir / "taken");
  std::ofstream(m_dir / "taken" / "lines") << "x";
  try {
    OutputWriter out((m_dir / "taken").string(), model, {}, 12);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (m_dir / "taken" / "lines").string());
  }
  EXPECT_THROW(OutputWriter((m_dir / "ok").string(), model, {}, 2), RunError);  // too few tube sides
}

// A full disk (/dev/full takes no byte: ENOSPC) is reported at the write, naming the file.
TEST_F(OutputWriterTest, FullDiskIsReportedAtTheWrite) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const Model model = make_model();
  OutputWriter out(m_dir.string(), model, {}, 6);
  out.write_increment(model.reference, row(0, 0.0, {}), 0.0, true);
  fs::create_symlink("/dev/full", m_dir / "nodes.csv.tmp");
  try {
    out.write_nodes(model.reference);
    FAIL() << "expected RunError";
  } catch (const RunError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nodes.csv.tmp"), std::string::npos) << what;
    EXPECT_NE(what.find(std::strerror(ENOSPC)), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(m_dir / "nodes.csv"));
  // A series' subfolder replaced by a file during the run: the next .vtu fails.
  fs::remove_all(m_dir / "fibers");
  std::ofstream(m_dir / "fibers") << "x";
  EXPECT_THROW(out.write_increment(model.reference, row(1, 1.0, {}), 1.0, true), RunError);
}

}  // namespace
}  // namespace fibra
