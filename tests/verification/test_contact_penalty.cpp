// The penalty adapts per proximity zone in both directions (docs/theory/contact.md, "Penalty"):
// a zone that penetrates beyond the allowed depth is stiffened towards 70 % of it
// (adapt_penalty); a zone whose deepest penetration is below 35 % of it is softened towards
// 70 % by at most 4 per call and never below the floor (soften_penalty). Two crossed fibers in
// contact make one zone; the responses' gaps are set by hand, as only they are read.
#include <gtest/gtest.h>

#include <memory>

#include "fibra/contact/contact_manager.hpp"
#include "verification/verification_support.hpp"

namespace fibra::test {
namespace {

struct CrossedPair {
  Case c;
  Model model;
  std::unique_ptr<ContactManager> manager;
  std::vector<ContactElement> elements;
  double allowed = 0;  // allowed penetration [m]
};

CrossedPair crossed_pair() {
  const double r = 20e-6;
  CrossedPair p;
  p.c = parse_case_toml(fmt::format(R"(
[[material]]
name = "glass"
young = 72e9
poisson = 0.22
[[fiber]]
name = "a"
material = "glass"
radius = {0}
points = [[-0.5e-3, 0, 0], [0.5e-3, 0, 0]]
elements = 4
[[fiber]]
name = "b"
material = "glass"
radius = {0}
points = [[0, -0.5e-3, {1}], [0, 0.5e-3, {1}]]
elements = 4
[contact]
max_penetration = 0.05
[[step]]
)",
                                    r, 1.98 * r),
                        "crossed.toml");
  p.model = build_model(p.c);
  p.manager = std::make_unique<ContactManager>(p.model, p.c.contact);
  p.elements = p.manager->detect(p.model.reference, p.model.reference, {});
  p.allowed = 0.05 * r;
  return p;
}

// Responses whose deepest penetration is `ratio` times the allowed one (the others half of it).
std::vector<ContactResponse> at_ratio(const CrossedPair& p, double ratio) {
  std::vector<ContactResponse> out(p.elements.size());
  for (size_t k = 0; k < out.size(); ++k) out[k].gap = -(k == 0 ? ratio : 0.5 * ratio) * p.allowed;
  return out;
}

TEST(ContactPenalty, OneZoneAtTheCrossing) {
  const CrossedPair p = crossed_pair();
  ASSERT_FALSE(p.elements.empty());
  for (const ContactElement& e : p.elements) {
    EXPECT_EQ(e.zone, p.elements.front().zone);
    EXPECT_DOUBLE_EQ(e.law.stiffness, p.manager->initial_stiffness());
  }
}

TEST(ContactPenalty, TooDeepZoneIsStiffenedTowardsSeventyPercent) {
  CrossedPair p = crossed_pair();
  const double k0 = p.manager->initial_stiffness();
  EXPECT_EQ(p.manager->adapt_penalty(p.elements, at_ratio(p, 0.9)), 0);  // within the allowed depth
  EXPECT_DOUBLE_EQ(p.elements.front().law.stiffness, k0);
  EXPECT_EQ(p.manager->adapt_penalty(p.elements, at_ratio(p, 2.1)), 1);
  for (const ContactElement& e : p.elements) EXPECT_NEAR(e.law.stiffness, 3.0 * k0, 1e-9 * k0);
  EXPECT_EQ(p.manager->adapt_penalty(p.elements, at_ratio(p, 1e4)), 1);  // at most 100 per call
  EXPECT_NEAR(p.elements.front().law.stiffness, 300.0 * k0, 1e-9 * k0);
}

TEST(ContactPenalty, ShallowZoneIsSoftenedBoundedAndFloored) {
  CrossedPair p = crossed_pair();
  const double k0 = p.manager->initial_stiffness();
  for (ContactElement& e : p.elements) e.law.stiffness = 100.0 * k0;
  // Between 35 % and 100 % of the allowed depth: left as it is.
  EXPECT_EQ(p.manager->soften_penalty(p.elements, at_ratio(p, 0.4), k0), 0);
  EXPECT_DOUBLE_EQ(p.elements.front().law.stiffness, 100.0 * k0);
  // At 28 %: towards 70 %, a factor 0.4.
  EXPECT_EQ(p.manager->soften_penalty(p.elements, at_ratio(p, 0.28), k0), 1);
  for (const ContactElement& e : p.elements) EXPECT_NEAR(e.law.stiffness, 40.0 * k0, 1e-9 * k0);
  // Far below (or open): by 4 at most.
  EXPECT_EQ(p.manager->soften_penalty(p.elements, at_ratio(p, 0.0), k0), 1);
  EXPECT_NEAR(p.elements.front().law.stiffness, 10.0 * k0, 1e-9 * k0);
  EXPECT_EQ(p.manager->soften_penalty(p.elements, at_ratio(p, 0.01), k0), 1);
  EXPECT_NEAR(p.elements.front().law.stiffness, 2.5 * k0, 1e-9 * k0);
  // Never below the floor, and a zone at the floor is not counted.
  EXPECT_EQ(p.manager->soften_penalty(p.elements, at_ratio(p, 0.01), k0), 1);
  for (const ContactElement& e : p.elements) EXPECT_DOUBLE_EQ(e.law.stiffness, k0);
  EXPECT_EQ(p.manager->soften_penalty(p.elements, at_ratio(p, 0.01), k0), 0);
  EXPECT_DOUBLE_EQ(p.elements.front().law.stiffness, k0);
}

// Softened to where the penetration (about 1/k at a given force) lands between the two
// thresholds, a zone is then left alone by both: no cycle of raises and softenings.
TEST(ContactPenalty, SofteningAndStiffeningDoNotCycle) {
  CrossedPair p = crossed_pair();
  const double k0 = p.manager->initial_stiffness();
  for (ContactElement& e : p.elements) e.law.stiffness = 50.0 * k0;
  double ratio = 0.05;  // at 50 k0
  for (int call = 0; call < 10; ++call) {
    const double before = p.elements.front().law.stiffness;
    p.manager->soften_penalty(p.elements, at_ratio(p, ratio), k0);
    EXPECT_EQ(p.manager->adapt_penalty(p.elements, at_ratio(p, ratio * before / p.elements.front().law.stiffness)), 0);
    ratio *= before / p.elements.front().law.stiffness;
  }
  EXPECT_GE(ratio, 0.35);
  EXPECT_LE(ratio, 1.0);
  EXPECT_GT(p.elements.front().law.stiffness, k0);
}

}  // namespace
}  // namespace fibra::test
