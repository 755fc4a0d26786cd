/// Tests of the voxel model (export/voxel_model, mesh_voxelizer, fiber_locator,
/// export_options): a straight tow's voxels carry its axis as their fiber direction; the fiber
/// volume summed over the voxels converges to the fibers' analytic volume in the box, within
/// the sub-sampling's bound, as the voxels shrink; the voxels given to a tow are those whose
/// centres its envelope holds; the options and the grid they give, and their errors.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "export/export_cases.hpp"
#include "fibra/core/error.hpp"
#include "fibra/export/export_options.hpp"
#include "fibra/export/export_state.hpp"
#include "fibra/export/fiber_locator.hpp"
#include "fibra/export/mesh_voxelizer.hpp"
#include "fibra/export/voxel_model.hpp"

namespace fibra {
namespace {

TEST(ExportVoxels, AStraightTowsVoxelsCarryItsAxis) {
  const test::BuiltCase b = test::build_case(test::straight_tow_case());
  // One point per voxel: a voxel whose centre falls between fibers holds none, and takes its
  // direction from the tow's stations.
  ExportOptions options;
  options.voxels = std::array<Index, 3>{48, 28, 20};
  options.samples = 1;
  const ExportedState s =
      export_state(b.model, b.q, b.c.tows, export_grid(options, fibers_bounds(b.model, b.q)), options.samples);
  const VoxelModel& vm = s.voxels;
  int tow = 0, fibers = 0, tow_without_fibers = 0;
  for (Index v = 0; v < vm.grid.size(); ++v) {
    if (vm.tow[v] < 0 && vm.fraction[v] == 0) {
      EXPECT_EQ(vm.direction[v], Vec3::Zero()) << "voxel " << v;
      continue;
    }
    tow += vm.tow[v] == 0;
    fibers += vm.fraction[v] > 0;
    tow_without_fibers += vm.tow[v] == 0 && vm.fraction[v] == 0;
    EXPECT_NEAR((vm.direction[v] - test::straight_axis()).norm(), 0.0, 1e-6) << "voxel " << v;
  }
  EXPECT_GT(tow, 100);
  EXPECT_GT(fibers, 100);
  EXPECT_GT(tow_without_fibers, 0) << "no voxel of the tow between its fibers: the station directions are not tested";
}

/// Three fibers in the box [0, 1 mm]^3 apart from each other: one along x and one along y
/// through the whole box (their flat ends outside it), one oblique with both ends inside.
struct VolumeCase {
  test::BuiltCase built;
  double volume = 0;   ///< of the fibers inside the box [m^3]
  double surface = 0;  ///< of their lateral surfaces inside the box [m^2]
};

VolumeCase volume_case() {
  const double mm = 1e-3, r1 = 0.1 * mm, a2 = 0.12 * mm, b2 = 0.07 * mm, r3 = 0.06 * mm;
  const Vec3 p3(0.2 * mm, 0.8 * mm, 0.15 * mm), q3(0.8 * mm, 0.75 * mm, 0.55 * mm);
  std::string text = test::kMaterial;
  text += test::straight_fiber("x", Vec3(-0.5 * mm, 0.3 * mm, 0.31 * mm), Vec3(1.5 * mm, 0.3 * mm, 0.31 * mm), r1, 7);
  text += test::straight_fiber("y", Vec3(0.62 * mm, -0.5 * mm, 0.71 * mm), Vec3(0.62 * mm, 1.5 * mm, 0.71 * mm), a2, 6,
                               b2, Vec3(1, 0, 0.3));
  text += test::straight_fiber("o", p3, q3, r3, 3);
  VolumeCase c;
  c.built = test::build_case(text + test::kStep);
  const double l3 = (q3 - p3).norm();
  c.volume = std::numbers::pi * (r1 * r1 * mm + a2 * b2 * mm + r3 * r3 * l3);
  // The ellipse's perimeter (Ramanujan's approximation, within 1e-5 here).
  const double h = std::pow((a2 - b2) / (a2 + b2), 2);
  const double ellipse = std::numbers::pi * (a2 + b2) * (1 + 3 * h / (10 + std::sqrt(4 - 3 * h)));
  c.surface = 2 * std::numbers::pi * r1 * mm + ellipse * mm + 2 * std::numbers::pi * r3 * l3;
  return c;
}

TEST(ExportVoxels, TheFiberVolumeConvergesToTheAnalyticVolumeAsVoxelsShrink) {
  const VolumeCase c = volume_case();
  const TowFibers tows = tow_fibers(c.built.model, c.built.q, {});
  const Eigen::AlignedBox3d box(Vec3::Zero(), Vec3::Constant(1e-3));
  const int k = 2;
  std::vector<double> errors;
  for (Index n : {10, 20, 40}) {
    const VoxelGrid grid = VoxelGrid::over(box, {n, n, n});
    const VoxelModel vm = voxel_model(c.built.model, c.built.q, tows, {}, grid, k);
    double volume = 0;
    for (double f : vm.fraction) volume += f * grid.spacing.prod();
    const double error = std::abs(volume - c.volume);
    // A sub-sample counted wrongly has its cell (edge h / k) across the fibers' surface, so
    // within its diagonal of it: the error is at most the shell of that half-thickness.
    const double bound = 2.0 * std::sqrt(3.0) * (1e-3 / static_cast<double>(n) / k) * c.surface;
    EXPECT_LT(error, bound) << n << " voxels per side";
    errors.push_back(error / c.volume);
  }
  EXPECT_LT(errors[1], errors[0]);
  EXPECT_LT(errors[2], errors[1]);
  EXPECT_LT(errors[2], 1e-2) << "relative error with 40^3 voxels of 2^3 points";
}

TEST(ExportVoxels, TheLocatorFindsExactlyThePointsOfTheSections) {
  // Across the oblique fiber of the volume case: in at 0.999 r, out at 1.001 r, in every
  // direction of its section and along it.
  const VolumeCase c = volume_case();
  const Model& model = c.built.model;
  const FiberLocator locator(model, c.built.q);
  const Fiber& f = model.fibers[2];
  const double r = model.sections[f.section].a;
  std::vector<Index> candidates;
  for (Index node = f.first_node; node < f.first_node + f.num_nodes; ++node) {
    const Vec3 x = c.built.q.segment<3>(kNodeDofs * node), g1 = c.built.q.segment<3>(kNodeDofs * node + 3),
               g2 = c.built.q.segment<3>(kNodeDofs * node + 6);
    for (int j = 0; j < 12; ++j) {
      const double t = 2 * std::numbers::pi * j / 12;
      const Vec3 radial = std::cos(t) * g1 + std::sin(t) * g2;
      for (double scale : {0.999, 1.001}) {
        const Vec3 p = x + scale * r * radial;
        locator.candidates(Eigen::AlignedBox3d(p, p), candidates);
        const std::optional<FiberHit> hit = locator.find(p, candidates);
        const bool at_an_end = node == f.first_node || node == f.first_node + f.num_nodes - 1;
        if (scale < 1) {
          ASSERT_TRUE(hit.has_value()) << "node " << node << " angle " << j;
          EXPECT_EQ(hit->fiber, 2);
          EXPECT_NEAR((hit->tangent - (model.reference.segment<3>(kNodeDofs * (f.first_node + f.num_nodes - 1)) -
                                       model.reference.segment<3>(kNodeDofs * f.first_node))
                                          .normalized())
                          .norm(),
                      0.0, 1e-12);
        } else if (!at_an_end) {
          EXPECT_FALSE(hit.has_value()) << "node " << node << " angle " << j;
        }
      }
    }
  }
}

TEST(ExportVoxels, ATowsVoxelsAreThoseWhoseCentresItsEnvelopeHolds) {
  const test::BuiltCase b = test::build_case(test::curved_tow_case());
  const TowFibers tows = tow_fibers(b.model, b.q, b.c.tows);
  const TowEnvelope env = tow_envelope(b.model, b.q, tows, 0, EnvelopeOptions{});
  const Eigen::AlignedBox3d bounds = mesh_bounds(env.surface);
  const VoxelGrid grid = VoxelGrid::over(bounds, {31, 27, 9});
  std::vector<char> voxelized(grid.size(), 0);
  for_each_voxel_inside(env.surface, grid, [&](Index v) { ++voxelized[v]; });
  int inside = 0;
  for (Index k = 0; k < grid.count[2]; ++k)
    for (Index j = 0; j < grid.count[1]; ++j)
      for (Index i = 0; i < grid.count[0]; ++i) {
        const Index v = grid.index(i, j, k);
        ASSERT_LE(voxelized[v], 1) << "voxel " << v << " visited twice";
        const bool wound = winding_number(env.surface, grid.center(i, j, k)) > 0.5;
        EXPECT_EQ(voxelized[v] == 1, wound) << "voxel " << i << ", " << j << ", " << k;
        inside += wound;
      }
  EXPECT_GT(inside, 100);
}

TEST(ExportOptions, TheGridFollowsTheOptions) {
  const Eigen::AlignedBox3d fibers(Vec3(0, 0, 0), Vec3(2e-3, 1e-3, 0.25e-3));
  ExportOptions o;
  VoxelGrid g = export_grid(o, fibers);  // 100 along the longest side
  EXPECT_EQ(g.count, (std::array<Index, 3>{100, 50, 13}));
  EXPECT_NEAR(g.box().max().z(), 0.25e-3, 1e-18);
  EXPECT_LE(g.spacing.z(), 2e-5);
  o.voxel_size = 0.1e-3;
  g = export_grid(o, fibers);
  EXPECT_EQ(g.count, (std::array<Index, 3>{20, 10, 3}));
  o = parse_export_options("out", {"3", "4", "5"}, {}, {"-1e-3", "0", "0", "1e-3", "0.5e-3", "1e-4"}, {"2"});
  g = export_grid(o, fibers);
  EXPECT_EQ(g.count, (std::array<Index, 3>{3, 4, 5}));
  EXPECT_EQ(g.origin, Vec3(-1e-3, 0, 0));
  EXPECT_NEAR(g.spacing.x(), 2e-3 / 3, 1e-18);
  EXPECT_EQ(o.samples, 2);
}

/// The message of the InputError that `fn` throws ("" if none).
template <class Fn>
std::string input_error(Fn fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ExportOptions, EveryBadValueNamesItsOption) {
  using V = std::vector<std::string>;
  auto parse = [](V voxels, V size, V box, V samples, std::string out = "out") {
    return input_error([&] { parse_export_options(out, voxels, size, box, samples); });
  };
  EXPECT_NE(parse({}, {}, {}, {}, "").find("--out"), std::string::npos);
  for (const V& voxels : {V{"10", "0", "10"}, V{"10", "-3", "10"}, V{"10", "10"}, V{"1.5", "2", "3"}, V{"a", "b", "c"}})
    EXPECT_NE(parse(voxels, {}, {}, {}).find("--voxels: expected three whole numbers"), std::string::npos);
  for (const V& size : {V{"0"}, V{"-1e-5"}, V{"x"}, V{"nan"}})
    EXPECT_NE(parse({}, size, {}, {}).find("--voxel-size: expected one length"), std::string::npos);
  EXPECT_NE(parse({"1", "1", "1"}, {"1e-5"}, {}, {}).find("not both"), std::string::npos);
  EXPECT_NE(parse({}, {}, {"0", "0", "0", "0", "1", "1"}, {}).find("--box"), std::string::npos);
  EXPECT_NE(parse({}, {}, {"0", "0", "0", "0", "1", "1"}, {}).find("empty along x"), std::string::npos);
  EXPECT_NE(parse({}, {}, {"0", "0", "1", "1", "1", "0.5"}, {}).find("empty along z"), std::string::npos);
  EXPECT_NE(parse({}, {}, {"0", "0", "0", "1", "1"}, {}).find("--box: expected six numbers"), std::string::npos);
  for (const V& samples : {V{"0"}, V{"17"}, V{"2.5"}})
    EXPECT_NE(parse({}, {}, {}, samples).find("--samples"), std::string::npos);

  const Eigen::AlignedBox3d fibers(Vec3(0, 0, 0), Vec3(2e-3, 1e-3, 0.25e-3));
  ExportOptions o;
  o.voxels = std::array<Index, 3>{1000, 1000, 1000};
  EXPECT_NE(input_error([&] { export_grid(o, fibers); }).find("--voxels: 1e+09 voxels is more than"),
            std::string::npos);
  o.voxels.reset();
  o.voxel_size = 1e-7;
  EXPECT_NE(input_error([&] { export_grid(o, fibers); }).find("--voxel-size"), std::string::npos);
  o.voxel_size.reset();
  o.box = Eigen::AlignedBox3d(Vec3(1, 1, 1), Vec3(2, 2, 2));
  EXPECT_NE(input_error([&] { export_grid(o, fibers); }).find("holds no fiber"), std::string::npos);
}

}  // namespace
}  // namespace fibra
