// The fabric report (model/fabric_report.hpp) against geometry built by hand, not simulated:
// straight tows (no crimp, the packed section), a sinusoidal tow (crimp against the elliptic
// integral, computed here by fine quadrature), crimp along each tow's own mean line (straight
// tows turned in the plane, sine waves in any direction and sheared, never negative),
// lenticular and elliptical cuts, a 2 x 2 weave placed by hand (thickness, margins excluded,
// shrinkage), and penetration from given contact responses. Areas of the grown convex hulls are computed here independently, from the
// support function of the fiber centres.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>

#include "fibra/io/case_reader.hpp"
#include "fibra/model/fabric.hpp"
#include "fibra/model/fabric_report.hpp"
#include "fibra/run/run_case.hpp"

namespace fibra {
namespace {

constexpr double kPi = std::numbers::pi;

Case base_case() {
  Case c;
  c.file = "<test>";
  MaterialSpec m;
  m.name = "glass";
  m.young = 72e9;
  m.poisson = 0.22;
  c.materials.push_back(m);
  return c;
}

/// A straight fiber from a to b.
void add_fiber(Case& c, const std::string& name, const Vec3& a, const Vec3& b, double r, int elements) {
  FiberSpec f;
  f.name = name;
  f.material = "glass";
  f.radius = f.semi_axis_1 = f.semi_axis_2 = r;
  f.elements = elements;
  f.path.points = {a, b};
  c.fibers.push_back(f);
}

void add_tow(Case& c, const std::string& name, TowSpec::Direction d, int index, std::vector<std::string> fibers) {
  TowSpec t;
  t.name = name;
  t.direction = d;
  t.index = index;
  t.fibers = std::move(fibers);
  c.tows.push_back(t);
}

/// A tow of straight fibers along x (warp) or y (weft) whose cut centres are `sites`
/// (across, z) about the axis position `at`, from -half to +half along the tow.
void add_straight_tow(Case& c, const std::string& name, TowSpec::Direction d, int index, double at,
                      const std::vector<Eigen::Vector2d>& sites, double r, double half, int elements) {
  std::vector<std::string> names;
  for (size_t k = 0; k < sites.size(); ++k) {
    const std::string fn = name + ".f" + std::to_string(k);
    const Eigen::Vector2d& p = sites[k];
    if (d == TowSpec::Direction::Warp)
      add_fiber(c, fn, Vec3(-half, at + p.x(), p.y()), Vec3(half, at + p.x(), p.y()), r, elements);
    else
      add_fiber(c, fn, Vec3(at + p.x(), -half, p.y()), Vec3(at + p.x(), half, p.y()), r, elements);
    names.push_back(fn);
  }
  add_tow(c, name, d, index, names);
}

/// Moves every node to map(its reference position, its fiber).
void map_nodes(const Model& model, VecX& q, const std::function<Vec3(const Vec3&, const Fiber&)>& map) {
  for (const Fiber& f : model.fibers)
    for (Index k = 0; k < f.num_nodes; ++k) {
      const Index d = 9 * (f.first_node + k);
      q.segment<3>(d) = map(model.reference.segment<3>(d), f);
    }
}

/// Area of the centres' convex hull grown by r, from the support function: the boundary of the
/// grown set at outward direction u is argmax_i (p_i . u) + r u; a fine polygon through those
/// points (independent of the code's hull).
double grown_hull_area(const std::vector<Eigen::Vector2d>& p, double r) {
  const int n = 200000;
  std::vector<Eigen::Vector2d> b(n);
  for (int k = 0; k < n; ++k) {
    const double t = 2 * kPi * k / n;
    const Eigen::Vector2d u(std::cos(t), std::sin(t));
    size_t best = 0;
    for (size_t i = 1; i < p.size(); ++i)
      if (p[i].dot(u) > p[best].dot(u)) best = i;
    b[k] = p[best] + r * u;
  }
  double a = 0;
  for (int k = 0; k < n; ++k) a += 0.5 * (b[k].x() * b[(k + 1) % n].y() - b[(k + 1) % n].x() * b[k].y());
  return a;
}

void expect_section(const TowSectionReport& s, const std::vector<Eigen::Vector2d>& sites, double r, double tol) {
  double lo_u = 1e300, hi_u = -1e300, lo_z = 1e300, hi_z = -1e300;
  for (const auto& p : sites) {
    lo_u = std::min(lo_u, p.x());
    hi_u = std::max(hi_u, p.x());
    lo_z = std::min(lo_z, p.y());
    hi_z = std::max(hi_z, p.y());
  }
  const double area = grown_hull_area(sites, r);
  EXPECT_EQ(s.fibers, static_cast<int>(sites.size()));
  EXPECT_NEAR(s.width, hi_u - lo_u + 2 * r, tol * r);
  EXPECT_NEAR(s.thickness, hi_z - lo_z + 2 * r, tol * r);
  EXPECT_NEAR(s.area, area, 1e-6 * area);
  EXPECT_NEAR(s.volume_fraction, sites.size() * kPi * r * r / area, 1e-6);
}

TEST(FabricReport, StraightTowsHaveNoCrimpAndThePackedSection) {
  const double r = 2e-5, w = 0.8e-3, t = 0.2e-3, s = 1e-3;
  const std::vector<Eigen::Vector2d> sites = pack_ellipse(24, r, w, t);
  ASSERT_EQ(sites.size(), 24u);
  Case c = base_case();
  add_straight_tow(c, "warp0", TowSpec::Direction::Warp, 0, 0.0, sites, r, 1.5 * s, 30);
  add_straight_tow(c, "weft0", TowSpec::Direction::Weft, 0, -0.5 * s, sites, r, 1.0 * s, 20);
  add_straight_tow(c, "weft1", TowSpec::Direction::Weft, 1, 0.5 * s, sites, r, 1.0 * s, 20);
  const Model model = build_model(c);
  const FabricReport rep = fabric_report(c, model, model.reference);
  ASSERT_EQ(rep.tows.size(), 3u);
  // A tow's axis is the mean of its fibers: the packing is centred only approximately.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : sites) mean += p / static_cast<double>(sites.size());
  const TowReport& warp = rep.tows[0];
  EXPECT_NEAR(warp.axis, mean.x(), 1e-15);
  EXPECT_EQ(warp.crossings, 2);
  EXPECT_NEAR(warp.start, -0.5 * s + mean.x(), 1e-15);
  EXPECT_NEAR(warp.end, 0.5 * s + mean.x(), 1e-15);
  EXPECT_NEAR(warp.crimp, 0.0, 1e-13);
  EXPECT_NEAR(warp.z_amplitude, 0.0, 1e-18);
  EXPECT_NEAR(warp.mid.position, mean.x(), 1e-15);
  EXPECT_NEAR(warp.crossing.position, 0.5 * s + mean.x(), 1e-15);
  expect_section(warp.mid, sites, r, 1e-9);
  expect_section(warp.crossing, sites, r, 1e-9);
  // The packing holds the fibers in the nominal ellipse: the section is no larger.
  EXPECT_LE(warp.mid.width, w * (1 + 1e-9));
  EXPECT_LE(warp.mid.thickness, t * (1 + 1e-9));
  // Weft tows: one crossing (the warp axis), so no crimp; the crossing section is there.
  EXPECT_EQ(rep.tows[1].crossings, 1);
  EXPECT_TRUE(std::isnan(rep.tows[1].crimp));
  expect_section(rep.tows[1].crossing, sites, r, 1e-9);
  EXPECT_NEAR(rep.warp_crimp, 0.0, 1e-13);
  EXPECT_TRUE(std::isnan(rep.weft_crimp));
  double zlo = 1e300, zhi = -1e300;
  for (const auto& p : sites) zlo = std::min(zlo, p.y()), zhi = std::max(zhi, p.y());
  EXPECT_NEAR(rep.thickness, zhi - zlo + 2 * r, 1e-12 * r);
  EXPECT_NEAR(rep.section_x, mean.x(), 1e-15);
  EXPECT_NEAR(rep.section_y, mean.x(), 1e-15);
  EXPECT_NEAR(rep.shrinkage_x, 0.0, 1e-15);
  EXPECT_FALSE(rep.has_penetration);
  EXPECT_NEAR(rep.volume_fraction, 24 * kPi * r * r / grown_hull_area(sites, r), 1e-6);
}

/// (1/L) int_0^L sqrt(1 + (2 pi A / L)^2 cos^2(2 pi x / L)) dx - 1 (composite Simpson).
double sinusoid_crimp(double amplitude, double period) {
  const int n = 200000;
  const double k = 2 * kPi * amplitude / period;
  auto f = [&](double x) {
    const double c = std::cos(2 * kPi * x / period);
    return std::sqrt(1 + k * k * c * c);
  };
  double sum = f(0) + f(period);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(period * i / n);
  return sum * (period / n) / 3.0 / period - 1.0;
}

TEST(FabricReport, SinusoidalTowCrimpMatchesTheEllipticIntegral) {
  const double r = 1e-5, period = 2e-3, amp = 0.1e-3, margin = 0.5e-3;
  const double exact = sinusoid_crimp(amp, period);
  ASSERT_GT(exact, 0.02);
  double previous = 1.0;
  for (int per_period : {8, 32, 128}) {
    Case c = base_case();
    // Warp along x from -margin to period + margin; 3 fibers side by side; wefts at 0 and L.
    const int elements = per_period * 3 / 2;
    const std::vector<Eigen::Vector2d> sites = {{-3 * r, 0}, {0, 0}, {3 * r, 0}};
    std::vector<std::string> names;
    for (size_t k = 0; k < sites.size(); ++k) {
      add_fiber(c, "w.f" + std::to_string(k), Vec3(-margin, sites[k].x(), 0), Vec3(period + margin, sites[k].x(), 0),
                r, elements);
      names.push_back("w.f" + std::to_string(k));
    }
    add_tow(c, "w", TowSpec::Direction::Warp, 0, names);
    add_fiber(c, "a.f0", Vec3(0, -1e-3, 0), Vec3(0, 1e-3, 0), r, 4);
    add_fiber(c, "b.f0", Vec3(period, -1e-3, 0), Vec3(period, 1e-3, 0), r, 4);
    add_tow(c, "a", TowSpec::Direction::Weft, 0, {"a.f0"});
    add_tow(c, "b", TowSpec::Direction::Weft, 1, {"b.f0"});
    const Model model = build_model(c);
    VecX q = model.reference;
    map_nodes(model, q, [&](const Vec3& x, const Fiber& f) {
      if (f.name[0] != 'w') return x;
      return Vec3(x.x(), x.y(), amp * std::sin(2 * kPi * x.x() / period));
    });
    const FabricReport rep = fabric_report(c, model, q);
    const TowReport& w = rep.tows[0];
    const double err = std::abs(w.crimp - exact);
    if (per_period == 128) {
      EXPECT_LT(err, 1e-9) << "crimp " << w.crimp << " exact " << exact;
      EXPECT_NEAR(w.z_amplitude, 2 * amp, 1e-5 * amp);
      EXPECT_NEAR(rep.thickness, 2 * amp + 2 * r, 1e-5 * amp);
    }
    EXPECT_LT(err, 0.02 * previous) << per_period << " elements per period";  // O(h^4): 1/256 per 4x
    previous = err;
    EXPECT_NEAR(rep.warp_crimp, w.crimp, 1e-15);
    EXPECT_NEAR(w.mid.position, 0.5 * period, 1e-15);
    // The mid-section cuts the fibers where the sinusoid crosses zero: all at z = 0.
    EXPECT_NEAR(w.mid.center_z, 0.0, 1e-3 * amp);
  }
}

// Crimp is measured along each tow's own mean line: straight tows turned in the fabric plane
// have none, whatever the angle, and report the angle they are turned by; the whole sample
// turned, or only its wefts (as a shear turns them).
TEST(FabricReport, StraightTowsTurnedInThePlaneHaveNoCrimp) {
  const double r = 2e-5, s = 1e-3;
  const std::vector<Eigen::Vector2d> sites = pack_ellipse(7, r, 0.4e-3, 0.1e-3);
  Case c = base_case();
  add_straight_tow(c, "warp0", TowSpec::Direction::Warp, 0, -0.5 * s, sites, r, 1.5 * s, 12);
  add_straight_tow(c, "warp1", TowSpec::Direction::Warp, 1, 0.5 * s, sites, r, 1.5 * s, 12);
  add_straight_tow(c, "weft0", TowSpec::Direction::Weft, 0, -0.5 * s, sites, r, 1.5 * s, 12);
  add_straight_tow(c, "weft1", TowSpec::Direction::Weft, 1, 0.5 * s, sites, r, 1.5 * s, 12);
  const Model model = build_model(c);
  const auto turn = [](double a, const Vec3& x) {
    return Vec3(std::cos(a) * x.x() - std::sin(a) * x.y(), std::sin(a) * x.x() + std::cos(a) * x.y(), x.z());
  };
  for (const double deg : {15.0, 45.0, -30.0}) {
    const double a = deg * kPi / 180;
    for (const bool wefts_only : {false, true}) {
      SCOPED_TRACE(std::to_string(deg) + (wefts_only ? " deg, wefts only" : " deg, the whole sample"));
      VecX q = model.reference;
      map_nodes(model, q, [&](const Vec3& x, const Fiber& f) {
        return wefts_only && f.name[1] == 'a' ? x : turn(a, x);  // "warp...": unturned
      });
      const FabricReport rep = fabric_report(c, model, q);
      ASSERT_EQ(rep.tows.size(), 4u);
      for (const TowReport& t : rep.tows) {
        const bool turned = !wefts_only || t.direction == TowSpec::Direction::Weft;
        EXPECT_NEAR(t.crimp, 0.0, 1e-14) << t.name;
        EXPECT_NEAR(t.angle, turned ? a : 0.0, 1e-14) << t.name;
      }
      EXPECT_NEAR(rep.warp_crimp, 0.0, 1e-14);
      EXPECT_NEAR(rep.weft_crimp, 0.0, 1e-14);
    }
  }
}

/// A sample of 2 warps and 2 wefts, 3 fibers side by side in each, crossing at right angles in
/// the fabric plane; every fiber on z = +-A sin(2 pi u / L) along its tow (u from the first
/// crossing), with 2 periods between the warps' crossings and 1 between the wefts'; margins
/// of 0.25 mm beyond (nodes fall on the crossings). `place` then moves every node (x, y, z) of
/// the flat layout.
struct SineSample {
  static constexpr double r = 1e-5, amp_warp = 0.05e-3, amp_weft = 0.04e-3;
  static constexpr double period_warp = 1.0e-3, period_weft = 0.8e-3, margin = 0.25e-3;
  static constexpr int per_period = 64;
  Case c;
  Model model;
  SineSample() : c(base_case()) {
    const double lw = 2 * period_warp, lf = period_weft;  // crossing ranges: wefts at x = 0, lw; warps at y = 0, lf
    for (int j = 0; j < 2; ++j) {
      std::vector<std::string> warp, weft;
      for (int k = 0; k < 3; ++k) {
        const double offset = (k - 1) * 3 * r;
        const std::string wn = "warp" + std::to_string(j) + ".f" + std::to_string(k);
        const std::string fn = "weft" + std::to_string(j) + ".f" + std::to_string(k);
        add_fiber(c, wn, Vec3(-margin, j * lf + offset, 0), Vec3(lw + margin, j * lf + offset, 0), r,
                  static_cast<int>(std::lround(per_period * (lw + 2 * margin) / period_warp)));
        add_fiber(c, fn, Vec3(j * lw + offset, -margin, 0), Vec3(j * lw + offset, lf + margin, 0), r,
                  static_cast<int>(std::lround(per_period * (lf + 2 * margin) / period_weft)));
        warp.push_back(wn);
        weft.push_back(fn);
      }
      add_tow(c, "warp" + std::to_string(j), TowSpec::Direction::Warp, j, warp);
      add_tow(c, "weft" + std::to_string(j), TowSpec::Direction::Weft, j, weft);
    }
    model = build_model(c);
  }
  /// The waved layout, then `place` applied to each node.
  VecX state(const std::function<Vec3(const Vec3&)>& place) const {
    VecX q = model.reference;
    map_nodes(model, q, [&](const Vec3& x, const Fiber& f) {
      const bool warp = f.name[1] == 'a';
      const double z = warp ? amp_warp * std::sin(2 * kPi * x.x() / period_warp)
                            : -amp_weft * std::sin(2 * kPi * x.y() / period_weft);
      return place(Vec3(x.x(), x.y(), z));
    });
    return q;
  }
};

// A sine wave of known amplitude and period gives the arc length of the sine over its period
// - 1, computed here by quadrature, in any direction of the fabric plane: the sample turned
// about z.
TEST(FabricReport, SineTowsGiveTheirCrimpInAnyDirection) {
  const SineSample sample;
  const double warp_exact = sinusoid_crimp(SineSample::amp_warp, SineSample::period_warp);
  const double weft_exact = sinusoid_crimp(SineSample::amp_weft, SineSample::period_weft);
  ASSERT_GT(warp_exact, 0.02);
  ASSERT_GT(weft_exact, 0.02);
  for (const double deg : {0.0, 15.0, 45.0, 120.0, -75.0}) {
    SCOPED_TRACE(std::to_string(deg) + " deg");
    const double a = deg * kPi / 180;
    const FabricReport rep = fabric_report(sample.c, sample.model, sample.state([&](const Vec3& x) {
      return Vec3(std::cos(a) * x.x() - std::sin(a) * x.y(), std::sin(a) * x.x() + std::cos(a) * x.y(), x.z());
    }));
    ASSERT_EQ(rep.tows.size(), 4u);
    for (const TowReport& t : rep.tows) {
      const bool warp = t.direction == TowSpec::Direction::Warp;
      // 64 quadratic elements per period: the interpolation leaves about 1e-9.
      EXPECT_NEAR(t.crimp, warp ? warp_exact : weft_exact, 1e-8) << t.name;
    }
    EXPECT_NEAR(rep.warp_crimp, warp_exact, 1e-8);
    EXPECT_NEAR(rep.weft_crimp, weft_exact, 1e-8);
  }
}

// The same sine waves sheared as a picture frame shears them: the wefts turned by the angle,
// the warps moved closer (y cos g) without turning, every tow keeping its length and its
// crossings. The crimp of every tow stays, to round-off, and the wefts report the angle; with
// the crimp along the fixed axis (y) a weft would have gained 1/cos(g) - 1 (3.5 % at 15 deg).
TEST(FabricReport, ShearedSineTowsKeepTheirCrimp) {
  const SineSample sample;
  const FabricReport flat = fabric_report(sample.c, sample.model, sample.state([](const Vec3& x) { return x; }));
  for (const double deg : {15.0, 30.0, -25.0}) {
    SCOPED_TRACE(std::to_string(deg) + " deg");
    const double g = deg * kPi / 180;
    const FabricReport sheared = fabric_report(sample.c, sample.model, sample.state([&](const Vec3& x) {
      return Vec3(x.x() - x.y() * std::sin(g), x.y() * std::cos(g), x.z());
    }));
    ASSERT_EQ(sheared.tows.size(), flat.tows.size());
    for (size_t t = 0; t < flat.tows.size(); ++t) {
      const bool weft = flat.tows[t].direction == TowSpec::Direction::Weft;
      EXPECT_GT(flat.tows[t].crimp, 0.02);
      EXPECT_NEAR(sheared.tows[t].crimp, flat.tows[t].crimp, 1e-13) << flat.tows[t].name;
      EXPECT_NEAR(sheared.tows[t].angle, weft ? g : 0.0, 1e-13) << flat.tows[t].name;
    }
    EXPECT_NEAR(sheared.weft_crimp, flat.weft_crimp, 1e-13);
    EXPECT_NEAR(sheared.warp_crimp, flat.warp_crimp, 1e-13);
  }
}

// Crimp is never negative: a fiber that does not span the tow's woven range is measured over
// the projection of what it has there, and fibers bent back and forth in the plane or out of
// it are longer than their projection.
TEST(FabricReport, CrimpIsNeverNegative) {
  const SineSample sample;
  for (const double deg : {0.0, 20.0}) {
    const double g = deg * kPi / 180;
    VecX q = sample.state([&](const Vec3& x) { return Vec3(x.x() - x.y() * std::sin(g), x.y() * std::cos(g), x.z()); });
    // Shorten one warp fiber to half the woven range (its nodes beyond it pulled back onto it)
    // and wave another in the plane.
    for (const Fiber& f : sample.model.fibers)
      for (Index k = 0; k < f.num_nodes; ++k) {
        Vec3 x = q.segment<3>(9 * (f.first_node + k));
        const Vec3 x0 = sample.model.reference.segment<3>(9 * (f.first_node + k));
        if (f.name == "warp0.f0" && x0.x() > SineSample::period_warp) x = q.segment<3>(9 * (f.first_node + k - 1));
        if (f.name == "warp1.f2") x.y() += 0.1e-3 * std::sin(6 * kPi * x0.x() / SineSample::period_warp);
        q.segment<3>(9 * (f.first_node + k)) = x;
      }
    // Without the out-of-plane waves: the in-plane one alone still gives a positive crimp.
    VecX flat = q;
    for (Index k = 0; k < sample.model.num_nodes(); ++k) flat[9 * k + 2] = 0.0;
    for (const VecX* state : {&q, &flat}) {
      const FabricReport rep = fabric_report(sample.c, sample.model, *state);
      for (const TowReport& t : rep.tows) EXPECT_GE(t.crimp, 0.0) << t.name << " at " << deg << " deg";
      ASSERT_EQ(rep.tows[2].name, "warp1");
      EXPECT_GT(rep.tows[2].crimp, 0.1);  // one fiber of three waving in the plane
    }
  }
}

TEST(FabricReport, LenticularAndEllipticalCutsGiveTheirWidthAndThickness) {
  const double r = 1e-5, w = 10 * r, h = 2.5 * r;  // half-spreads of the centres
  // Ellipse: rings of centres on scaled ellipses, the tips included.
  std::vector<Eigen::Vector2d> ellipse, lens;
  for (double scale : {1.0, 0.5})
    for (int k = 0; k < 16; ++k)
      ellipse.emplace_back(scale * w * std::cos(2 * kPi * k / 16), scale * h * std::sin(2 * kPi * k / 16));
  ellipse.emplace_back(0, 0);
  // Lens: two circular arcs through (+-w, 0) and (0, +-h).
  const double R = (w * w + h * h) / (2 * h);
  const double half_angle = std::asin(w / R);
  for (int side : {1, -1})
    for (int k = 0; k <= 12; ++k) {
      const double a = -half_angle + 2 * half_angle * k / 12;
      lens.emplace_back(R * std::sin(a), side * (R * std::cos(a) - (R - h)));
    }
  lens.emplace_back(0, 0);
  lens.emplace_back(0.5 * w, 0);
  lens.emplace_back(-0.5 * w, 0);
  Case c = base_case();
  add_straight_tow(c, "ell", TowSpec::Direction::Warp, 0, 0.0, ellipse, r, 1e-3, 10);
  add_straight_tow(c, "len", TowSpec::Direction::Warp, 1, 0.5e-3, lens, r, 1e-3, 10);
  add_fiber(c, "a.f0", Vec3(-0.2e-3, -1e-3, 0), Vec3(-0.2e-3, 1e-3, 0), r, 4);
  add_fiber(c, "b.f0", Vec3(0.2e-3, -1e-3, 0), Vec3(0.2e-3, 1e-3, 0), r, 4);
  add_tow(c, "a", TowSpec::Direction::Weft, 0, {"a.f0"});
  add_tow(c, "b", TowSpec::Direction::Weft, 1, {"b.f0"});
  const Model model = build_model(c);
  const FabricReport rep = fabric_report(c, model, model.reference);
  const TowSectionReport& se = rep.tows[0].mid;
  const TowSectionReport& sl = rep.tows[1].mid;
  // Same width and thickness ...
  EXPECT_NEAR(se.width, 2 * w + 2 * r, 1e-9 * r);
  EXPECT_NEAR(se.thickness, 2 * h + 2 * r, 1e-9 * r);
  EXPECT_NEAR(sl.width, 2 * w + 2 * r, 1e-9 * r);
  EXPECT_NEAR(sl.thickness, 2 * h + 2 * r, 1e-9 * r);
  expect_section(se, ellipse, r, 1e-9);
  expect_section(sl, lens, r, 1e-9);
  // Both symmetric about the vertical through their centre, wider than thick: level.
  EXPECT_NEAR(se.tilt, 0.0, 1e-12);
  EXPECT_NEAR(sl.tilt, 0.0, 1e-12);
  // ... but the lens is smaller than the ellipse: pi w h vs the two circular segments.
  const double segment = R * R * (half_angle - std::sin(half_angle) * std::cos(half_angle));
  EXPECT_LT(2 * segment, kPi * w * h);
  EXPECT_LT(sl.area, se.area);
  // The exact lens (dense arcs) grown by r bounds the polygonal one from above.
  const double exact_lens = 2 * segment + (4 * R * half_angle) * r + kPi * r * r;
  EXPECT_LT(sl.area, exact_lens);
  EXPECT_GT(sl.area, 0.98 * exact_lens);
}

// The tilt of a section: the lens and ellipse cuts above, turned about the tow axis by a known
// angle (sites rotated in the plane of the cut), in a warp and in a weft tow. The tilt is the
// angle of the centres' principal axis, so a symmetric cloud turned by a gives a, whatever its
// shape; positive when the section rises towards +y (warp) or +x (weft). tow_section cuts any
// plane with the report's measures: at the mid-section's plane it gives the mid-section.
TEST(FabricReport, TurnedCutsGiveTheirTilt) {
  const double r = 1e-5, w = 10 * r, h = 2.5 * r;
  std::vector<Eigen::Vector2d> ellipse, lens;
  for (double scale : {1.0, 0.5})
    for (int k = 0; k < 16; ++k)
      ellipse.emplace_back(scale * w * std::cos(2 * kPi * k / 16), scale * h * std::sin(2 * kPi * k / 16));
  const double R = (w * w + h * h) / (2 * h), half_angle = std::asin(w / R);
  for (int side : {1, -1})
    for (int k = 0; k <= 12; ++k) {
      const double a = -half_angle + 2 * half_angle * k / 12;
      lens.emplace_back(R * std::sin(a), side * (R * std::cos(a) - (R - h)));
    }
  auto turned = [](const std::vector<Eigen::Vector2d>& sites, double a) {
    std::vector<Eigen::Vector2d> out;
    for (const auto& p : sites)
      out.emplace_back(std::cos(a) * p.x() - std::sin(a) * p.y(), std::sin(a) * p.x() + std::cos(a) * p.y());
    return out;
  };
  for (double deg : {3.0, -20.0, 60.0}) {
    const double a = deg * kPi / 180;
    Case c = base_case();
    add_straight_tow(c, "ell", TowSpec::Direction::Warp, 0, 0.0, turned(ellipse, a), r, 1e-3, 10);
    add_straight_tow(c, "len", TowSpec::Direction::Weft, 0, 0.0, turned(lens, a), r, 1e-3, 10);
    add_fiber(c, "a.f0", Vec3(-0.5e-3, -0.5e-3, 0), Vec3(-0.5e-3, 0.5e-3, 0), r, 4);  // a second weft
    add_fiber(c, "b.f0", Vec3(-0.5e-3, 0.4e-3, 0), Vec3(0.5e-3, 0.4e-3, 0), r, 4);    // a second warp
    add_tow(c, "a", TowSpec::Direction::Weft, 1, {"a.f0"});
    add_tow(c, "b", TowSpec::Direction::Warp, 1, {"b.f0"});
    const Model model = build_model(c);
    const FabricReport rep = fabric_report(c, model, model.reference);
    ASSERT_EQ(rep.tows.size(), 4u);
    for (int t : {0, 1}) {
      SCOPED_TRACE(rep.tows[t].name + " turned by " + std::to_string(deg) + " deg");
      EXPECT_NEAR(rep.tows[t].mid.tilt, a, 1e-12);
      EXPECT_NEAR(rep.tows[t].crossing.tilt, a, 1e-12);
      const TowSectionReport at_mid = tow_section(model, model.reference, c.tows[t], rep.tows[t].mid.position);
      EXPECT_EQ(at_mid.fibers, rep.tows[t].mid.fibers);
      EXPECT_NEAR(at_mid.position, rep.tows[t].mid.position, 1e-18);
      EXPECT_NEAR(at_mid.tilt, rep.tows[t].mid.tilt, 1e-15);
      EXPECT_NEAR(at_mid.area, rep.tows[t].mid.area, 1e-12 * at_mid.area);
      EXPECT_NEAR(at_mid.width, rep.tows[t].mid.width, 1e-15);
      EXPECT_NEAR(at_mid.thickness, rep.tows[t].mid.thickness, 1e-15);
      EXPECT_NEAR(at_mid.center_z, rep.tows[t].mid.center_z, 1e-15);
    }
    // One fiber: no axis.
    EXPECT_TRUE(std::isnan(rep.tows[2].crossing.tilt));
    EXPECT_TRUE(std::isnan(tow_section(model, model.reference, c.tows[3], 0.0).tilt));
  }
  // Beyond the fibers' ends: nothing cut.
  Case c = base_case();
  add_straight_tow(c, "ell", TowSpec::Direction::Warp, 0, 0.0, ellipse, r, 1e-3, 10);
  const Model model = build_model(c);
  const TowSectionReport none = tow_section(model, model.reference, c.tows[0], 2e-3);
  EXPECT_EQ(none.fibers, 0);
  EXPECT_TRUE(std::isnan(none.tilt));
  EXPECT_TRUE(std::isnan(none.width));
}

TEST(FabricReport, HandWoven2x2ThicknessShrinkageAndMarginsExcluded) {
  // Warps at y = -+s/2 along x, wefts at x = -+s/2 along y, one fiber each, from -s to s
  // (margins s/2). Warp i: z = h sigma_i sin(pi x / s), sigma = (+1, -1); weft j:
  // z = h s_j sin(pi y / s), s_j = (-1, +1): at every crossing the two tows are at -+h, a
  // plain weave. In the margins the fibers rise to 5h: not part of the woven region.
  const double r = 1e-5, s = 1e-3, h = 0.05e-3;
  Case c = base_case();
  add_fiber(c, "warp0.f0", Vec3(-s, -0.5 * s, 0), Vec3(s, -0.5 * s, 0), r, 40);
  add_fiber(c, "warp1.f0", Vec3(-s, 0.5 * s, 0), Vec3(s, 0.5 * s, 0), r, 40);
  add_fiber(c, "weft0.f0", Vec3(-0.5 * s, -s, 0), Vec3(-0.5 * s, s, 0), r, 40);
  add_fiber(c, "weft1.f0", Vec3(0.5 * s, -s, 0), Vec3(0.5 * s, s, 0), r, 40);
  add_tow(c, "warp0", TowSpec::Direction::Warp, 0, {"warp0.f0"});
  add_tow(c, "warp1", TowSpec::Direction::Warp, 1, {"warp1.f0"});
  add_tow(c, "weft0", TowSpec::Direction::Weft, 0, {"weft0.f0"});
  add_tow(c, "weft1", TowSpec::Direction::Weft, 1, {"weft1.f0"});
  const Model model = build_model(c);
  VecX q = model.reference;
  auto shape = [&](double u, double sign) {
    if (std::abs(u) <= 0.5 * s) return h * sign * std::sin(kPi * u / s);
    return h * sign * (u > 0 ? 1.0 : -1.0) * (1.0 + 8.0 * (std::abs(u) - 0.5 * s) / s);  // up to 5h
  };
  map_nodes(model, q, [&](const Vec3& x, const Fiber& f) {
    if (f.name == "warp0.f0") return Vec3(x.x(), x.y(), shape(x.x(), 1.0));
    if (f.name == "warp1.f0") return Vec3(x.x(), x.y(), shape(x.x(), -1.0));
    if (f.name == "weft0.f0") return Vec3(x.x(), x.y(), shape(x.y(), -1.0));
    return Vec3(x.x(), x.y(), shape(x.y(), 1.0));
  });
  // The crossings: warp above/below weft in turn, separated by 2h.
  const FabricReport rep = fabric_report(c, model, q);
  EXPECT_NEAR(rep.thickness, 2 * h + 2 * r, 1e-4 * h);
  EXPECT_NEAR(rep.x_min, -0.5 * s, 1e-15);
  EXPECT_NEAR(rep.x_max, 0.5 * s, 1e-15);
  EXPECT_NEAR(rep.y_min, -0.5 * s, 1e-15);
  EXPECT_NEAR(rep.y_max, 0.5 * s, 1e-15);
  for (const TowReport& t : rep.tows) {
    EXPECT_NEAR(t.z_amplitude, 2 * h, 1e-4 * h) << t.name;
    EXPECT_GT(t.crimp, 0.0) << t.name;
    // Crossing section at the second crossing (+s/2): z = +-h.
    EXPECT_NEAR(std::abs(t.crossing.center_z), h, 1e-6 * h) << t.name;
  }
  EXPECT_NEAR(rep.warp_crimp, rep.weft_crimp, 1e-12);
  EXPECT_NEAR(rep.shrinkage_x, 0.0, 1e-15);
  EXPECT_NEAR(rep.shrinkage_y, 0.0, 1e-15);

  // Draw the sample in along x by 3 %: the weft axes come closer, the warps do not.
  VecX q2 = q;
  for (Index k = 0; k < model.num_nodes(); ++k) q2[9 * k] *= 0.97;
  const FabricReport shrunk = fabric_report(c, model, q2);
  EXPECT_NEAR(shrunk.shrinkage_x, 0.03, 1e-12);
  EXPECT_NEAR(shrunk.shrinkage_y, 0.0, 1e-12);

  // With edge bodies the shrinkage is that of the bodies.
  c.bodies.push_back({"edge.x-", Vec3(-s, 0, 0), Mat3::Identity()});
  c.bodies.push_back({"edge.x+", Vec3(s, 0, 0), Mat3::Identity()});
  const Model with_bodies = build_model(c);
  VecX q3 = with_bodies.reference;
  q3.head(model.node_dofs) = q;
  q3[with_bodies.bodies[1].first_dof] = 0.9 * s;  // edge.x+ drawn in by 0.1 s
  const FabricReport by_bodies = fabric_report(c, with_bodies, q3);
  EXPECT_NEAR(by_bodies.shrinkage_x, 0.05, 1e-12);
  EXPECT_NEAR(by_bodies.shrinkage_y, 0.0, 1e-12);  // no edge.y bodies: the warp axes
}

TEST(FabricReport, PenetrationFromGivenResponses) {
  Case c = base_case();
  add_fiber(c, "a", Vec3(0, 0, 0), Vec3(1e-3, 0, 0), 1e-5, 4);
  add_fiber(c, "b", Vec3(0, 1e-4, 0), Vec3(1e-3, 1e-4, 0), 2e-5, 4);
  add_fiber(c, "c", Vec3(0, 2e-4, 0), Vec3(1e-3, 2e-4, 0), 3e-5, 4);
  add_tow(c, "t", TowSpec::Direction::Warp, 0, {"a", "b", "c"});
  const Model model = build_model(c);
  std::vector<ContactElement> contacts(3);
  std::vector<ContactResponse> responses(3);
  contacts[0].a.element = 0;  // a-b: smaller radius 1e-5
  contacts[0].b.element = 4;
  responses[0].gap = -2e-6;   // 0.2
  contacts[1].a.element = 5;  // b-c: smaller radius 2e-5
  contacts[1].b.element = 9;
  responses[1].gap = -3e-6;   // 0.15, the deepest in metres
  contacts[2].a.element = 6;  // b-c, separated
  contacts[2].b.element = 10;
  responses[2].gap = 1e-6;
  FabricReport rep = fabric_report(c, model, model.reference, &contacts, &responses);
  EXPECT_TRUE(rep.has_penetration);
  EXPECT_NEAR(rep.max_penetration, 3e-6, 1e-20);
  EXPECT_NEAR(rep.max_penetration_ratio, 0.2, 1e-14);
  // A weave offset hides penetration from the law, not from the report.
  contacts[2].offset = 5e-6;  // geometric gap 1e-6 - 5e-6 = -4e-6: 0.2 of 2e-5, 4e-6 m
  rep = fabric_report(c, model, model.reference, &contacts, &responses);
  EXPECT_NEAR(rep.max_penetration, 4e-6, 1e-20);
  EXPECT_NEAR(rep.max_penetration_ratio, 0.2, 1e-14);
  responses[0].gap = -6e-6;  // 0.6 of 1e-5
  rep = fabric_report(c, model, model.reference, &contacts, &responses);
  EXPECT_NEAR(rep.max_penetration, 6e-6, 1e-20);
  EXPECT_NEAR(rep.max_penetration_ratio, 0.6, 1e-14);
  // No contacts: nothing to say (null in JSON); all separated: zero.
  const FabricReport none = fabric_report(c, model, model.reference);
  EXPECT_FALSE(none.has_penetration);
  EXPECT_TRUE(to_json(none)["max_penetration"].is_null());
  for (auto& rsp : responses) rsp.gap = 1e-6;
  contacts[2].offset = 0;
  rep = fabric_report(c, model, model.reference, &contacts, &responses);
  EXPECT_EQ(rep.max_penetration, 0.0);
  EXPECT_EQ(to_json(rep)["max_penetration_ratio"].get<double>(), 0.0);
}

TEST(FabricReport, JsonHoldsEveryQuantity) {
  const double r = 2e-5, s = 1e-3;
  const std::vector<Eigen::Vector2d> sites = pack_ellipse(6, r, 0.4e-3, 0.1e-3);
  Case c = base_case();
  add_straight_tow(c, "warp0", TowSpec::Direction::Warp, 0, 0.0, sites, r, s, 10);
  add_straight_tow(c, "weft0", TowSpec::Direction::Weft, 0, -0.25 * s, sites, r, s, 10);
  add_straight_tow(c, "weft1", TowSpec::Direction::Weft, 1, 0.25 * s, sites, r, s, 10);
  const Model model = build_model(c);
  const nlohmann::json j = to_json(fabric_report(c, model, model.reference));
  for (const char* key : {"warp_crimp", "weft_crimp", "thickness", "shrinkage_x", "shrinkage_y", "max_penetration",
                          "max_penetration_ratio", "volume_fraction", "woven_region", "section_x", "section_y", "tows"})
    EXPECT_TRUE(j.contains(key)) << key;
  ASSERT_EQ(j["tows"].size(), 3u);
  const nlohmann::json& t = j["tows"][0];
  EXPECT_EQ(t["name"], "warp0");
  EXPECT_EQ(t["direction"], "warp");
  EXPECT_NEAR(t["crimp"].get<double>(), 0.0, 1e-13);
  EXPECT_NEAR(t["angle"].get<double>(), 0.0, 1e-15);
  for (const char* key : {"position", "fibers", "width", "thickness", "area", "volume_fraction", "center_z", "tilt"}) {
    EXPECT_TRUE(t["mid_section"].contains(key)) << key;
    EXPECT_TRUE(t["crossing_section"].contains(key)) << key;
  }
  EXPECT_TRUE(j["tows"][1]["crimp"].is_null());        // a single crossing
  EXPECT_TRUE(j["tows"][1]["mid_section"]["width"].is_null());
  EXPECT_EQ(j["tows"][1]["mid_section"]["fibers"], 0);
}

// run_case with tows: case.toml at the start, the report per increment in history.csv, the last
// step's report and one line per step in summary.json, slices after relax (and weave) steps
// only. Two warps bent by a load over two wefts, no contact (the report is geometry only).
TEST(FabricRun, WritesCaseReportAndSlices) {
  namespace fs = std::filesystem;
  std::string toml = R"(
title = "bent warps"
[[material]]
name = "glass"
young = 72e9
poisson = 0.22
)";
  auto fiber = [&](const std::string& name, double x0, double y0, double x1, double y1, double z) {
    toml += "[[fiber]]\nname = \"" + name + "\"\nmaterial = \"glass\"\nradius = 2e-5\nelements = 8\n";
    toml += "points = [[" + std::to_string(x0) + ", " + std::to_string(y0) + ", " + std::to_string(z) + "], [" +
            std::to_string(x1) + ", " + std::to_string(y1) + ", " + std::to_string(z) + "]]\n";
    toml += "[[fix]]\nfiber = \"" + name + "\"\nnode = \"first\"\n[[fix]]\nfiber = \"" + name +
            "\"\nnode = \"last\"\n";
  };
  fiber("warp0.f0", -0.002, -0.0005, 0.002, -0.0005, 0.0001);
  fiber("warp1.f0", -0.002, 0.0005, 0.002, 0.0005, 0.0001);
  fiber("weft0.f0", -0.0005, -0.002, -0.0005, 0.002, -0.0001);
  fiber("weft1.f0", 0.0005, -0.002, 0.0005, 0.002, -0.0001);
  toml += R"(
[[tow]]
name = "warp0"
direction = "warp"
index = 0
fibers = ["warp0.f0"]
[[tow]]
name = "warp1"
direction = "warp"
index = 1
fibers = ["warp1.f0"]
[[tow]]
name = "weft0"
direction = "weft"
index = 0
fibers = ["weft0.f0"]
[[tow]]
name = "weft1"
direction = "weft"
index = 1
fibers = ["weft1.f0"]
[[step]]
name = "bend"
increments = 2
  [[step.load]]
  fiber = "warp0.f0"
  at = 0.5
  force = [0, 0, -0.01]
[[step]]
name = "settle"
kind = "relax"
)";
  const Case c = parse_case_toml(toml, "bent.toml");
  const fs::path dir = fs::temp_directory_path() / ("fibra_fabric_run_" + std::to_string(static_cast<long>(::getpid())));
  std::error_code ec;
  fs::remove_all(dir, ec);
  RunOptions options;
  options.out_dir = dir.string();
  const RunReport report = run_case(c, options);
  ASSERT_EQ(report.result.status, RunResult::Status::Converged) << report.result.message;

  // The expanded case reads back to the same fibers and tows.
  const Case back = read_case((dir / "case.toml").string());
  EXPECT_EQ(back.fibers.size(), c.fibers.size());
  ASSERT_EQ(back.tows.size(), c.tows.size());
  EXPECT_EQ(back.tows[3].fibers, c.tows[3].fibers);

  ASSERT_TRUE(report.fabric.has_value());
  EXPECT_GT(report.fabric->warp_crimp, 1e-6);  // warp0 bent down between the wefts
  EXPECT_NEAR(report.fabric->weft_crimp, 0.0, 1e-12);

  std::ifstream in(dir / "summary.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("fabric"));
  EXPECT_EQ(j["fabric"]["step"], "settle");
  EXPECT_NEAR(j["fabric"]["warp_crimp"].get<double>(), report.fabric->warp_crimp, 1e-15);
  ASSERT_EQ(j["fabric_steps"].size(), 2u);
  EXPECT_EQ(j["fabric_steps"][0]["step"], "bend");
  EXPECT_EQ(j["fabric_steps"][0]["kind"], "standard");
  EXPECT_EQ(j["fabric_steps"][1]["kind"], "relax");
  EXPECT_TRUE(j["fabric_steps"][1]["max_penetration"].is_null());  // no contact
  EXPECT_GT(j["fabric_steps"][0]["thickness"].get<double>(), 0.2e-3);

  std::ifstream hist(dir / "history.csv");
  std::string header, row, last;
  std::getline(hist, header);
  while (std::getline(hist, row)) last = row;
  EXPECT_NE(header.find(",fabric:warp_crimp,fabric:weft_crimp,fabric:thickness"), std::string::npos) << header;
  const double thickness = std::stod(last.substr(last.rfind(',') + 1));
  EXPECT_NEAR(thickness, report.fabric->thickness, 1e-12 * thickness);

  for (const char* f : {"settle_x.svg", "settle_x.png", "settle_y.svg", "settle_y.png"})
    EXPECT_TRUE(fs::is_regular_file(dir / "slices" / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "slices" / "bend_x.svg"));  // standard steps: no slices
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace fibra
