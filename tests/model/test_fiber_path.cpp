// Fiber paths: the helix's start angle turns the helix about its axis without moving it
// along the axis (the strands of a rope start in one plane), and every sample lies on the
// exact helix with the exact tangent.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fibra/model/fiber_path.hpp"

namespace fibra {
namespace {

TEST(FiberPath, HelixStartAngleTurnsAboutTheAxisOnly) {
  const double pi = std::numbers::pi;
  PathSpec p;
  p.kind = PathSpec::Kind::Helix;
  p.radius = 2e-3;
  p.pitch = 10e-3;
  p.turns = 0.75;
  for (double start_deg : {0.0, 120.0, 240.0}) {
    p.start_angle = start_deg * pi / 180.0;
    const int n = 13;
    const std::vector<PathFrame> f = sample_path(p, n, std::nullopt);
    ASSERT_EQ(static_cast<int>(f.size()), n);
    for (int k = 0; k < n; ++k) {
      const double turn = 2 * pi * p.turns * k / (n - 1);
      const double phi = p.start_angle + turn;
      const double c = p.pitch / (2 * pi);
      const Vec3 x(p.radius * std::cos(phi), p.radius * std::sin(phi), c * turn);
      EXPECT_LT((f[k].position - x).norm(), 1e-15) << start_deg << " sample " << k;
      const Vec3 t = Vec3(-p.radius * std::sin(phi), p.radius * std::cos(phi), c).normalized();
      EXPECT_LT((f[k].tangent - t).norm(), 1e-13) << start_deg << " sample " << k;
    }
    EXPECT_NEAR(f.front().position.z(), 0.0, 1e-18);
    EXPECT_NEAR(f.back().position.z(), p.pitch * p.turns, 1e-15);
  }
}

}  // namespace
}  // namespace fibra
