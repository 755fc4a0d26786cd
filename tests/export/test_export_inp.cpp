/// The Abaqus input file of the voxel model (export/abaqus_inp) read back with meshio
/// (python3-meshio, a declared dependency: scripts/deps.sh) by tests/export/check_inp.py: node
/// and element counts, the element set of each tow and of the matrix, the six face node sets,
/// one orientation per element along its fiber direction; and the set names Abaqus accepts.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "export/export_cases.hpp"
#include "fibra/export/abaqus_inp.hpp"
#include "fibra/export/export_options.hpp"
#include "fibra/export/export_state.hpp"
#include "support/scratch_dir.hpp"

namespace fibra {
namespace {

class ExportInp : public test::ScratchDirTest {
 protected:
  ExportInp() : ScratchDirTest("fibra_export_inp_") {}
};

/// Two straight tows crossing at right angles, apart in z, with a loose fiber in no tow.
std::string crossing_case() {
  const double r = 0.05e-3;
  std::string text = test::kMaterial;
  for (int k = 0; k < 2; ++k) {
    const double o = (k - 0.5) * 2.2 * r;
    text += test::straight_fiber(fmt::format("a{}", k), Vec3(-0.6e-3, o, 0), Vec3(0.6e-3, o, 0), r, 6);
    text += test::straight_fiber(fmt::format("b{}", k), Vec3(o, -0.6e-3, 2.5 * r), Vec3(o, 0.6e-3, 2.5 * r), r, 6);
  }
  text += test::straight_fiber("loose", Vec3(-0.6e-3, 0.4e-3, 0), Vec3(0.6e-3, 0.45e-3, 0.1e-3), r, 4);
  return text + test::tow("warp A", "warp", 0, {"a0", "a1"}) + test::tow("weft-B", "weft", 0, {"b0", "b1"}) +
         test::kStep;
}

std::string python() {
  const char* env = std::getenv("FIBRA_PYTHON");
  return env && *env ? env : "/usr/bin/python3";
}

TEST_F(ExportInp, MeshioReadsTheExpectedCountsSetsAndOrientations) {
  ASSERT_EQ(std::system((python() + " -c 'import meshio' 2> /dev/null").c_str()), 0)
      << python() << " has no meshio: it is a declared dependency (scripts/deps.sh installs python3-meshio)";
  const test::BuiltCase b = test::build_case(crossing_case());
  ExportOptions options;
  options.voxels = std::array<Index, 3>{9, 8, 5};
  const ExportedState s =
      export_state(b.model, b.q, b.c.tows, export_grid(options, fibers_bounds(b.model, b.q)), options.samples);
  const VoxelModel& vm = s.voxels;
  const std::string inp = abaqus_inp(vm, {"warp A", "weft-B"}, "test");
  std::ofstream(m_dir / "voxels.inp") << inp;

  nlohmann::json expected;
  expected["nodes"] = 10 * 9 * 6;
  expected["elements"] = vm.grid.size();
  std::map<std::string, Index> elsets;
  for (int t : vm.tow) ++elsets[t == 0 ? "TOW_warp_A" : t == 1 ? "TOW_weft_B" : "MATRIX"];
  ASSERT_EQ(elsets.size(), 3u) << "the case should fill both tows and the matrix";
  expected["elsets"] = elsets;
  expected["nsets"] = {{"XMIN", 9 * 6},  {"XMAX", 9 * 6},  {"YMIN", 10 * 6},
                       {"YMAX", 10 * 6}, {"ZMIN", 10 * 9}, {"ZMAX", 10 * 9}};
  for (size_t v = 0; v < vm.direction.size(); ++v) {
    const Vec3& d = vm.direction[v];
    expected["directions"][std::to_string(v + 1)] = {d.x(), d.y(), d.z()};
  }
  std::ofstream(m_dir / "expected.json") << expected.dump();

  const std::string script = std::string(FIBRA_SOURCE_DIR) + "/tests/export/check_inp.py";
  const std::string command =
      fmt::format("{} '{}' '{}' '{}' > '{}' 2>&1", python(), script, (m_dir / "voxels.inp").string(),
                  (m_dir / "expected.json").string(), (m_dir / "check.txt").string());
  EXPECT_EQ(std::system(command.c_str()), 0) << test::slurp(m_dir / "check.txt");
}

TEST(ExportInpNames, TowSetsAreAbaqusLabelsUniqueButForCase) {
  EXPECT_EQ(abaqus_tow_sets({"warp0", "weft 1", "a.b", "A_B", "a-b"}),
            (std::vector<std::string>{"TOW_warp0", "TOW_weft_1", "TOW_a_b", "TOW_A_B_2", "TOW_a_b_3"}));
}

TEST(ExportInpNames, LocalAxesFollowTheFiberWithAxisThreeUp) {
  for (const Vec3& a : {Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(1, 2, 0.3).normalized(), Vec3(0, 0, 1)}) {
    const auto [one, two] = local_axes(a);
    EXPECT_NEAR((one - a).norm(), 0.0, 1e-15);
    EXPECT_NEAR(two.norm(), 1.0, 1e-15);
    EXPECT_NEAR(one.dot(two), 0.0, 1e-15);
    if (std::abs(a.z()) < 0.5) {
      EXPECT_NEAR(two.z(), 0.0, 1e-15) << "axis 2 leaves the fabric's plane";
    }
  }
  const auto [one, two] = local_axes(Vec3::Zero());
  EXPECT_EQ(one, Vec3::UnitX());
  EXPECT_EQ(two, Vec3::UnitY());
}

}  // namespace
}  // namespace fibra
