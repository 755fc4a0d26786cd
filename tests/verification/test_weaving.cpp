// Weaving (METHOD §6), the weave step alone: a 2 x 2 plain weave of five glass fibers per tow
// (frictionless) starts with all tows straight in one plane, interpenetrating at every
// crossing, and is woven by a weave step (contact normals between crossing tows set by the
// pattern, pseudo-time drag). Read from the geometry at the end of the step:
//  - at every crossing the tow the pattern puts above is above (mean z of its fibers there);
//  - the crossing tows no longer interpenetrate (largest penetration below 0.1 r);
//  - both directions are crimped (the fabric report's crimp, > 0.5 %), and the fabric is
//    thicker than one tow.
// (The relax step that should follow does not converge yet: docs/theory/fabric.md, Status.)
#include <gtest/gtest.h>

#include <cmath>

#include "fibra/model/fabric.hpp"
#include "fibra/model/fabric_report.hpp"
#include "verification/verification_support.hpp"

namespace fibra {
namespace {

const char* kPlain = R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22
[fabric]
pattern = "plain"
warp = { tows = 2, spacing = 1.0e-3 }
weft = { tows = 2, spacing = 1.0e-3 }
margin = 0.5e-3
  [fabric.tow]
  fibers = 5
  width = 0.7e-3
  thickness = 0.25e-3
  [fabric.fiber]
  radius = 5.0e-5
  material = "glass"
  element_length = 1.0e-4
[contact]
friction = 0.0
[[step]]
name = "weave"
kind = "weave"
increments = 10
)";

TEST(Weaving, PlainWeaveStepSeparatesTheTowsInThePatternsOrder) {
  const test::Solved s = test::solve_toml(kPlain, "plain.toml");
  ASSERT_TRUE(s.converged()) << s.result.message;
  const double r = 5e-5;
  // Mean z of a tow's fibers at a position along it (nearest node of each fiber).
  auto tow_z = [&](const TowSpec& tow, double along) {
    double z = 0;
    for (const std::string& name : tow.fibers) {
      const Fiber& f = s.model.fibers[s.model.fiber_index(name)];
      const int axis = tow.direction == TowSpec::Direction::Warp ? 0 : 1;
      Index best = 0;
      for (Index k = 0; k < f.num_nodes; ++k)
        if (std::abs(s.q[9 * (f.first_node + k) + axis] - along) < std::abs(s.q[9 * (f.first_node + best) + axis] - along))
          best = k;
      z += s.q[9 * (f.first_node + best) + 2] / static_cast<double>(tow.fibers.size());
    }
    return z;
  };
  int crossings = 0;
  for (const TowSpec& warp : s.c.tows) {
    if (warp.direction != TowSpec::Direction::Warp) continue;
    for (const TowSpec& weft : s.c.tows) {
      if (weft.direction != TowSpec::Direction::Weft) continue;
      const double x = (weft.index - 0.5) * 1e-3, y = (warp.index - 0.5) * 1e-3;
      const double zw = tow_z(warp, x), zf = tow_z(weft, y);
      const bool above = warp_above(s.c.weave, warp.index, weft.index);
      EXPECT_EQ(zw > zf, above) << warp.name << " x " << weft.name << ": warp z " << zw << ", weft z " << zf;
      EXPECT_GT(std::abs(zw - zf), 2 * r) << warp.name << " x " << weft.name;
      ++crossings;
    }
  }
  EXPECT_EQ(crossings, 4);
  const IncrementInfo& last = s.increments.back();
  const FabricReport rep = fabric_report(s.c, s.model, s.q, nullptr, nullptr);
  std::printf("weaving: warp crimp %.5f, weft crimp %.5f, thickness %.4g m, largest penetration ratio %.4f\n",
              rep.warp_crimp, rep.weft_crimp, rep.thickness, last.contact.max_penetration_ratio);
  EXPECT_LT(last.contact.max_penetration_ratio, 0.1);
  EXPECT_GT(rep.warp_crimp, 0.005);
  EXPECT_GT(rep.weft_crimp, 0.005);
  EXPECT_GT(rep.thickness, 0.25e-3);
}

}  // namespace
}  // namespace fibra
