/// `fibra export` on a woven 2 x 2 plain weave (the weaving tests' friction sample, woven and
/// relaxed by `fibra run` in about 5 s): the files it writes, the tows' envelopes closed, outward
/// and apart from each other; and every bad input refused with exit code 2 and a message that
/// names the option and what was expected, before anything is written.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "fibra/export/export_state.hpp"
#include "fibra/export/result_state.hpp"
#include "fibra/export/triangle_intersection.hpp"
#include "support/fabric_cases.hpp"
#include "support/scratch_dir.hpp"

namespace fibra {
namespace {

namespace fs = std::filesystem;

/// The woven sample, run once for the suite in a directory of its own.
class ExportCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    s_dir = fs::temp_directory_path() / ("fibra_export_cli_" + std::to_string(static_cast<long>(::getpid())));
    fs::remove_all(s_dir);
    fs::create_directories(s_dir);
    std::ofstream(s_dir / "plain.toml") << test::plain_friction_sample();
    s_run = test::run_fibra(s_dir, "run plain.toml --out woven");
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    if (!::testing::UnitTest::GetInstance()->Failed()) fs::remove_all(s_dir, ec);
  }
  void SetUp() override { ASSERT_EQ(s_run.code, 0) << s_run.err; }
  static fs::path s_dir;
  static test::CliResult s_run;
};

fs::path ExportCli::s_dir;
test::CliResult ExportCli::s_run;

TEST_F(ExportCli, TheWovenSamplesEnvelopesAreClosedOutwardAndApart) {
  const test::CliResult r = test::run_fibra(s_dir, "export woven --out export --voxels 40 40 8");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("exported 4 tows"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("note:"), std::string::npos) << "envelopes still intersect: " << r.out;
  for (const char* f : {"envelopes.vtp", "contours.vtp", "voxels.vti", "voxels.inp", "tows.csv", "envelopes/warp0.stl",
                        "envelopes/warp1.stl", "envelopes/weft0.stl", "envelopes/weft1.stl"})
    EXPECT_TRUE(fs::is_regular_file(s_dir / "export" / f)) << f;
  const std::string vti = test::slurp(s_dir / "export/voxels.vti");
  EXPECT_NE(vti.find("WholeExtent=\"0 40 0 40 0 8\""), std::string::npos);
  // A binary STL: 84 bytes of header and count, then 50 bytes per triangle.
  const std::string stl = test::slurp(s_dir / "export/envelopes/warp0.stl");
  ASSERT_GE(stl.size(), 84u);
  std::uint32_t triangles = 0;
  std::memcpy(&triangles, stl.data() + 80, 4);
  EXPECT_EQ(stl.size(), 84u + 50u * triangles);

  // The same envelopes, computed again from the run's directory.
  const ResultState state = read_result_state((s_dir / "woven").string(), "test");
  const TowFibers tows = tow_fibers(state.model, state.q, state.c.tows);
  Separation separation;
  const std::vector<TowEnvelope> envelopes = tow_envelopes(state.model, state.q, tows, EnvelopeOptions{}, &separation);
  ASSERT_EQ(envelopes.size(), 4u);
  const double r_fiber = 5.0e-5;
  EXPECT_LT(separation.largest_inset, 0.2 * r_fiber) << "the envelopes gave up too much to stay apart";
  for (const TowEnvelope& env : envelopes) {
    EXPECT_EQ(unpaired_edges(env.surface), 0) << "tow " << env.tow;
    EXPECT_GT(signed_volume(env.surface), 0.0) << "tow " << env.tow;
  }
  for (size_t a = 0; a < envelopes.size(); ++a)
    for (size_t b = a + 1; b < envelopes.size(); ++b) {
      EXPECT_TRUE(intersecting_triangles(envelopes[a].surface, envelopes[b].surface).empty())
          << "tows " << a << " and " << b;
      // Apart from the triangle tests: no vertex of one inside the other.
      for (size_t x : {a, b})
        for (const Vec3& p : envelopes[x].surface.points)
          ASSERT_LT(winding_number(envelopes[x == a ? b : a].surface, p), 0.5) << "tows " << a << " and " << b;
    }
  // Warp tows cross weft tows: each pair of crossing tows touches, so the separation had work.
  EXPECT_GT(separation.rounds, 0);
}

TEST_F(ExportCli, EveryBadInputExitsWithTwoNamingTheOption) {
  struct Bad {
    std::string args, message;
  };
  const std::vector<Bad> bad = {
      {"export missing --out x",
       "missing: (directory): no such directory: expected the output directory of `fibra run`"},
      {"export woven", "--out: expected the directory to write the export into"},
      {"export woven --out x --voxels 10 0 10", "--voxels: expected three whole numbers NX NY NZ >= 1"},
      {"export woven --out x --voxels 10 -2 10", "--voxels: expected three whole numbers NX NY NZ >= 1"},
      {"export woven --out x --voxels 10 10", "--voxels: expected three whole numbers NX NY NZ >= 1"},
      {"export woven --out x --voxels 2000 2000 2000", "--voxels: 8e+09 voxels is more than the 8388608"},
      {"export woven --out x --voxel-size 0", "--voxel-size: expected one length H > 0 in metres"},
      {"export woven --out x --voxel-size 1e-8", "--voxel-size: "},
      {"export woven --out x --voxels 4 4 4 --voxel-size 1e-4", "give either --voxels NX NY NZ or --voxel-size H"},
      {"export woven --out x --box 0 0 0 0 1e-3 1e-3", "--box: expected six numbers XMIN YMIN ZMIN XMAX YMAX ZMAX"},
      {"export woven --out x --box 1 1 1 2 2 2", "--box: the box (x from 1 to 2"},
      {"export woven --out x --samples 0", "--samples: expected one whole number K from 1 to 16"},
      {"export notows --out x", "notows/case.toml: tow: the case has no tows"},
  };
  // A run without tows: one straight fiber, clamped, under a small load.
  std::ofstream(s_dir / "notows.toml") << "[[material]]\nname = \"m\"\nyoung = 1e9\npoisson = 0.3\n"
                                          "[[fiber]]\nname = \"f\"\nmaterial = \"m\"\nradius = 1e-3\n"
                                          "points = [[0, 0, 0], [0.1, 0, 0]]\nelements = 2\n"
                                          "[[fix]]\nfiber = \"f\"\nnode = \"first\"\n"
                                          "[[step]]\nname = \"s\"\n[[step.load]]\nfiber = \"f\"\nnode = \"last\"\n"
                                          "force = [0, 0, -1e-3]\n";
  ASSERT_EQ(test::run_fibra(s_dir, "run notows.toml --out notows").code, 0);
  for (const Bad& b : bad) {
    const test::CliResult r = test::run_fibra(s_dir, b.args);
    EXPECT_EQ(r.code, 2) << b.args << "\n" << r.err;
    EXPECT_NE(r.err.find(b.message), std::string::npos) << b.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(s_dir / "x")) << b.args << ": wrote its output directory before refusing";
  }
}

}  // namespace
}  // namespace fibra
