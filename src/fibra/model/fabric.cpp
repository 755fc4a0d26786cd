#include "fibra/model/fabric.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>
#include <tuple>
#include <utility>

#include "fibra/core/error.hpp"

namespace fibra {
namespace {

std::string lower_trimmed(const std::string& s) {
  std::string out;
  for (char ch : s) out += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  const auto b = out.find_first_not_of(" \t");
  const auto e = out.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : out.substr(b, e - b + 1);
}

/// Parses "A/B" or "A" into integers; false on anything else.
bool parse_pair(const std::string& s, int& a, int& b, bool& has_b) {
  std::istringstream in(s);
  has_b = false;
  if (!(in >> a)) return false;
  char slash = 0;
  if (in >> slash) {
    if (slash != '/' || !(in >> b)) return false;
    has_b = true;
  }
  std::string rest;
  return !(in >> rest);
}

const char* kAccepted =
    "accepted: \"plain\", \"twill A/B\" (e.g. \"twill 2/1\", \"twill 2/2\"), \"basket\" or \"basket N\", "
    "\"satin N\" or \"satin N/M\", or give `matrix` instead";

}  // namespace

std::vector<std::vector<int>> named_weave(const std::string& pattern, std::string& error) {
  error.clear();
  const std::string p = lower_trimmed(pattern);
  const auto space = p.find(' ');
  const std::string word = p.substr(0, space);
  const std::string args = space == std::string::npos ? std::string() : p.substr(space + 1);
  std::vector<std::vector<int>> m;
  int a = 0, b = 0;
  bool has_b = false;
  if (word == "plain" && args.empty()) return {{1, 0}, {0, 1}};
  if (word == "twill") {
    if (!parse_pair(args, a, b, has_b) || !has_b || a < 1 || b < 1) {
      error = fmt::format("\"{}\": a twill is \"twill A/B\" with A, B >= 1 (e.g. \"twill 2/1\"); {}", pattern, kAccepted);
      return {};
    }
    const int n = a + b;
    m.assign(n, std::vector<int>(n, 0));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) m[j][i] = ((i - j) % n + n) % n < a ? 1 : 0;
    return m;
  }
  if (word == "basket") {
    a = 2;
    if (!args.empty() && (!parse_pair(args, a, b, has_b) || has_b || a < 1)) {
      error = fmt::format("\"{}\": a basket is \"basket\" or \"basket N\" with N >= 1; {}", pattern, kAccepted);
      return {};
    }
    const int n = 2 * a;
    m.assign(n, std::vector<int>(n, 0));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) m[j][i] = ((i / a) + (j / a)) % 2 == 0 ? 1 : 0;
    return m;
  }
  if (word == "satin") {
    if (!parse_pair(args, a, b, has_b) || a < 5) {
      error = fmt::format("\"{}\": a satin is \"satin N\" or \"satin N/M\" with N >= 5; {}", pattern, kAccepted);
      return {};
    }
    const int n = a;
    int move = has_b ? b : 0;
    if (!has_b)
      for (int k = 2; k < n - 1 && move == 0; ++k)
        if (std::gcd(k, n) == 1) move = k;
    if (move <= 1 || move >= n - 1 || std::gcd(move, n) != 1) {
      error = fmt::format("\"{}\": the move M of \"satin N/M\" must be coprime with N and 1 < M < N - 1", pattern);
      return {};
    }
    m.assign(n, std::vector<int>(n, 1));
    for (int j = 0; j < n; ++j) m[j][(move * j) % n] = 0;
    return m;
  }
  error = fmt::format("unknown pattern \"{}\"; {}", pattern, kAccepted);
  return {};
}

std::string check_weave(const std::vector<std::vector<int>>& matrix) {
  if (matrix.empty() || matrix[0].empty()) return "the weave matrix is empty";
  const size_t cols = matrix[0].size();
  for (size_t j = 0; j < matrix.size(); ++j) {
    if (matrix[j].size() != cols)
      return fmt::format("the weave matrix is not rectangular: row {} has {} entries, row 0 has {}", j,
                         matrix[j].size(), cols);
    for (int v : matrix[j])
      if (v != 0 && v != 1) return fmt::format("weave matrix entries must be 0 or 1 (row {} has {})", j, v);
  }
  for (size_t j = 0; j < matrix.size(); ++j) {
    const int sum = std::accumulate(matrix[j].begin(), matrix[j].end(), 0);
    if (sum == 0 || sum == static_cast<int>(cols))
      return fmt::format("row {} (a weft) is {} every warp: it never interlaces (every row and column needs both 0 "
                         "and 1)",
                         j, sum == 0 ? "above" : "below");
  }
  for (size_t i = 0; i < cols; ++i) {
    int sum = 0;
    for (const auto& row : matrix) sum += row[i];
    if (sum == 0 || sum == static_cast<int>(matrix.size()))
      return fmt::format("column {} (a warp) is {} every weft: it never interlaces (every row and column needs both "
                         "0 and 1)",
                         i, sum == 0 ? "below" : "above");
  }
  return "";
}

namespace {

/// Hexagonal lattice sites (spacing d, rows along the width; `phase` 0: a row through the
/// centre, 1: the centre between two rows) whose disc of radius r lies in the ellipse.
/// Only the columns |l| <= max_cols when given (those near the centre, in lattice order).
/// `paired`: the lattice has no site at the centre and maps onto itself by the half-turn
/// p -> -p (each site paired with another); else it has a site at x = 0 in every other row
/// (phase 0: at the centre, and the half-turn maps it onto itself; phase 1: the mirror x -> -x
/// does). Rows are shifted by a multiple of d/4 so that a site's image is computed exactly.
std::vector<Eigen::Vector2d> lattice_sites(double d, int phase, double r, double a, double b, bool paired,
                                           int max_cols = INT_MAX) {
  std::vector<Eigen::Vector2d> out;
  const double h = d * std::sqrt(3.0) / 2.0;
  const int rows = static_cast<int>(std::ceil(b / h)) + 1;
  const int cols = std::min(static_cast<int>(std::ceil(a / d)) + 1, max_cols);
  const double rs = r * 1.001;
  for (int k = -rows; k <= rows; ++k) {
    const double y = (k + 0.5 * phase) * h;
    // A row whose top (or bottom) sample, computed as below, is above the ellipse's height has
    // no site: that sample is outside whatever x.
    // (Every test is made on |x| and |y|: the ellipse is symmetric about both axes, and a site
    // and its mirror images are then kept or left alike, whatever the rounding.)
    const double t_top = 2.0 * std::numbers::pi * 24 / 96;
    const double y_top = std::abs(y) + rs * std::sin(t_top);
    if ((y_top / b) * (y_top / b) > 1.0) continue;
    const bool odd = ((k % 2) + 2) % 2 == 1;
    // In columns of d: paired phase 1, +-1/4 (rows k and -1-k are each other's image); paired
    // phase 0, 1/2 in the rows through the centre; else 1/2 in every other row.
    const double shift = paired ? (phase == 1 ? (odd ? -0.25 : 0.25) : (odd ? 0.0 : 0.5)) : (odd ? 0.5 : 0.0);
    for (int l = -cols; l <= cols; ++l) {
      const double x = (l + shift) * d;
      // The disc inside the ellipse: its boundary sampled finely (sag 5.4e-4 r, below the 1e-3 r margin).
      // Decided first without the samples where they cannot differ: a centre outside the ellipse
      // leaves some sample outside (the ellipse is convex); the corner (|x| + r', |y| + r') of the
      // disc's box inside it leaves every sample inside (|x + r' cos t| <= |x| + r', also rounded).
      // A tow thousands of fibers wide has as many sites in a row, each sampled in every step of
      // pack_ellipse's bisection otherwise.
      if ((x / a) * (x / a) + (y / b) * (y / b) > 1.0) continue;
      const double ax = std::abs(x), ay = std::abs(y), cx = ax + rs, cy = ay + rs;
      bool inside = true;
      if ((cx / a) * (cx / a) + (cy / b) * (cy / b) <= 1.0) {
        out.emplace_back(x, y);
        continue;
      }
      for (int s = 0; s < 96 && inside; ++s) {
        const double t = 2.0 * std::numbers::pi * s / 96;
        const double px = ax + rs * std::cos(t), py = ay + rs * std::sin(t);
        inside = (px / a) * (px / a) + (py / b) * (py / b) <= 1.0;
      }
      if (inside) out.emplace_back(x, y);
    }
  }
  return out;
}

bool collinear(const std::vector<Eigen::Vector2d>& p) {
  if (p.size() < 3) return true;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& v : p) mean += v / static_cast<double>(p.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& v : p) cov += (v - mean) * (v - mean).transpose();
  const double det = cov.determinant(), tr = cov.trace();
  return det <= 1e-10 * tr * tr;
}

}  // namespace

std::vector<Eigen::Vector2d> pack_ellipse(int count, double r, double width, double thickness) {
  const double a = 0.5 * width, b = 0.5 * thickness;
  if (count <= 0 || r <= 0 || a < r || b < r) return {};
  // The sites for spacing d (rows offset from the centre first), or none.
  const auto measure = [&](const Eigen::Vector2d& p) { return (p.x() / a) * (p.x() / a) + (p.y() / b) * (p.y() / b); };
  // The packing is as symmetric as the count allows, so that a weave's own symmetries map its
  // tows' fibers onto each other (the plain weave's, warp and weft swapped with z -> -z, needs
  // the half-turn; with it, the relaxed warp and weft crimps of the paper's 12-fiber tows agree
  // to 0.4 %, against 1.1 % with two rows of 6 and 5 + 1 fibers). An even count is taken in
  // pairs from a lattice without a site at the centre that the half-turn maps onto itself; an
  // odd count from a lattice with a site at x = 0, symmetric under the half-turn (phase 0) or
  // the mirror x -> -x (phase 1). Each site's image under that symmetry has the same measure
  // (it is computed exactly), and ties are taken image by image.
  const bool paired = count % 2 == 0;
  // The `count` sites nearest the centre in the ellipse's measure, ties image by image and in
  // lattice order, or none if there are fewer; selected without sorting the whole lattice.
  const auto nearest = [&](const std::vector<Eigen::Vector2d>& s, int phase) -> std::vector<Eigen::Vector2d> {
    if (static_cast<int>(s.size()) < count) return {};
    const bool mirror = !paired && phase == 1;
    // A site and its image share a key: the image's coordinates chosen alike for both.
    const auto key = [&](const Eigen::Vector2d& p) -> std::pair<double, double> {
      if (mirror) return {std::abs(p.x()), p.y()};
      const bool upper = p.y() > 0.0 || (p.y() == 0.0 && p.x() >= 0.0);
      return upper ? std::pair{p.y(), p.x()} : std::pair{-p.y(), -p.x()};
    };
    using Rank = std::tuple<double, std::pair<double, double>, size_t>;
    std::vector<Rank> order(s.size());
    for (size_t i = 0; i < s.size(); ++i) order[i] = {measure(s[i]), key(s[i]), i};
    const size_t take = std::min(order.size(), static_cast<size_t>(count) + 1);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(take), order.end());
    std::vector<Eigen::Vector2d> out(static_cast<size_t>(count));
    for (int i = 0; i < count; ++i) out[i] = s[std::get<2>(order[i])];
    // The mirror's lattice: the last slot would split a site from its image (an even number of
    // sites on the axis x = 0 taken so far); it takes the nearest site on the axis left instead.
    const size_t last = static_cast<size_t>(count) - 1;
    if (mirror && take > last + 1 && std::get<1>(order[last]) == std::get<1>(order[last + 1]) &&
        std::get<0>(order[last]) == std::get<0>(order[last + 1])) {
      const Rank* axis = nullptr;
      for (size_t i = last; i < order.size(); ++i)
        if (s[std::get<2>(order[i])].x() == 0.0 && (!axis || order[i] < *axis)) axis = &order[i];
      if (!axis) return {};
      out[last] = s[std::get<2>(*axis)];
    }
    return out;
  };
  // A tow many fibers wide has a lattice of millions of sites, listed in each step of the
  // bisection: the columns near the centre are listed first, |l| <= count + 2. A site of a
  // column beyond has |x| >= (count + 2.5) d, so a measure of at least that over a squared plus
  // the least (y / b)^2 of the rows; if the count-th nearest site listed is nearer (with a
  // margin for rounding), the whole lattice has the same nearest sites in the same order.
  const auto best_for = [&](double d) -> std::vector<Eigen::Vector2d> {
    const double h = d * std::sqrt(3.0) / 2.0;
    for (int phase : {1, 0}) {
      std::vector<Eigen::Vector2d> s;
      if (std::ceil(a / d) + 1 > count + 2) {
        const double ymin = phase == 1 ? 0.5 * h / b : 0.0;
        const double beyond = std::pow((count + 2.5) * d / a, 2) + ymin * ymin;
        s = nearest(lattice_sites(d, phase, r, a, b, paired, count + 2), phase);
        // The margin covers the few roundings of a measure, no more: a larger one (1e-9) would
        // hide the columns' term, (count + 2.5)^2 (d / a)^2, on a very flat section, and the
        // whole lattice would be listed at every step.
        if (s.empty() || !(measure(s.back()) < beyond * (1.0 - 1e-14)))
          s = nearest(lattice_sites(d, phase, r, a, b, paired), phase);
      } else {
        s = nearest(lattice_sites(d, phase, r, a, b, paired), phase);
      }
      if (s.empty()) continue;
      if (count >= 3 && collinear(s)) continue;
      return s;
    }
    return {};
  };
  // The bisection below starts from a spacing that holds them: 2r (touching) unless that
  // lattice has too many sites to list (a fiber tiny against the section: 1e-9 m fibers in a
  // 0.8 x 0.2 mm tow make 5e10). Then it starts from a spacing whose lattice holds about 4
  // times the count (the area over the area per site), halved while it does not hold them.
  const auto sites_at = [&](double d) { return std::numbers::pi * a * b / (d * d * std::sqrt(3.0) / 2.0); };
  const double most_sites = std::max(1e5, 64.0 * count);
  double lo = 2.0 * r;
  bool holds = false;
  if (sites_at(lo) > most_sites) {
    double d = std::sqrt(std::numbers::pi * a * b / (4.0 * count * std::sqrt(3.0) / 2.0));
    for (int k = 0; k < 3 && d > lo && sites_at(d) <= most_sites && !holds; ++k) {
      holds = !best_for(d).empty();
      if (!holds) d *= 0.5;
    }
    if (holds) lo = d;
  }
  if (!holds && best_for(lo).empty()) return {};
  // Largest spacing that still holds them (bisection; the count falls with the spacing).
  double hi = 2.0 * std::max(a, b) + 2.0 * r;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (best_for(mid).empty())
      hi = mid;
    else
      lo = mid;
  }
  // Their centroid is the centre but for an odd count between two rows (more sites in one row
  // than in the other): the tow-end bodies sit at the actual centroid.
  return best_for(lo);
}

double fabric_fiber_length(const FabricSpec& f, bool warp) {
  // As expand_fabric places the tows: the other direction's outer axes plus the margins.
  const FabricDirectionSpec& other = warp ? f.weft : f.warp;
  const double n = other.tows;
  const double first = (0 - 0.5 * (n - 1)) * other.spacing, last = (n - 1 - 0.5 * (n - 1)) * other.spacing;
  return (last + f.margin) - (first - f.margin);
}

double fabric_fiber_elements(const FabricSpec& f, bool warp) {
  const double element_length = (warp ? f.warp : f.weft).fiber.element_length;
  return std::max(2.0, std::ceil(fabric_fiber_length(f, warp) / element_length - 1e-9));
}

ModelSize fabric_size(const FabricSpec& f) {
  ModelSize size;
  for (const bool warp : {true, false}) {
    const FabricDirectionSpec& d = warp ? f.warp : f.weft;
    const double fibers = static_cast<double>(d.tows) * static_cast<double>(d.tow.fibers);
    size.fibers += fibers;
    size.elements += fibers * fabric_fiber_elements(f, warp);
    size.bodies += 2.0 * d.tows;
  }
  size.bodies += 4;
  return size;
}

void expand_fabric(Case& c) {
  if (!c.fabric) return;
  const FabricSpec& f = *c.fabric;
  const std::string& file = c.file;
  if (const std::string why = check_weave(f.matrix); !why.empty()) throw InputError(file, "fabric.pattern", why);

  struct Direction {
    const char* name;  // "warp" / "weft"
    const FabricDirectionSpec* spec;
    std::vector<Eigen::Vector2d> sites;
  };
  Direction dirs[2] = {{"warp", &f.warp, {}}, {"weft", &f.weft, {}}};
  for (Direction& d : dirs) {
    const FabricDirectionSpec& s = *d.spec;
    const std::string key = fmt::format("fabric.{}", d.name);
    if (s.tows < 1) throw InputError(file, key + ".tows", "a fabric needs at least one tow in each direction");
    if (s.tow.fibers < 3)
      throw InputError(file, key + ".tow.fibers",
                       fmt::format("a tow needs at least 3 fibers (its end bodies follow them in average and need "
                                   "3 not on one line to define a mean rotation), got {}",
                                   s.tow.fibers));
    // A section more than 1e3 times wider than thick is no tow's (the reader holds the
    // thickness within the width); the packing's lattice would have millions of columns.
    if (s.tow.width > 1e3 * s.tow.thickness)
      throw InputError(file, key + ".tow.width",
                       fmt::format("a tow section of {:.6g} m by {:.6g} m (width by thickness) is more than 1000 times "
                                   "wider than thick",
                                   s.tow.width, s.tow.thickness));
    if (s.tows > 1 && s.spacing < s.tow.width)
      throw InputError(file, key + ".spacing",
                       fmt::format("spacing {:.6g} m is smaller than the tow width {:.6g} m: neighbouring {} tows "
                                   "would overlap",
                                   s.spacing, s.tow.width, d.name));
    d.sites = pack_ellipse(s.tow.fibers, s.fiber.radius, s.tow.width, s.tow.thickness);
    if (d.sites.empty()) {
      int fit = 0;
      for (int n = 1; n <= 100000 && !pack_ellipse(n, s.fiber.radius, s.tow.width, s.tow.thickness).empty(); n *= 2)
        fit = n;
      int lo = fit, hi = std::max(1, 2 * fit);
      while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        (pack_ellipse(mid, s.fiber.radius, s.tow.width, s.tow.thickness).empty() ? hi : lo) = mid;
      }
      throw InputError(file, key + ".tow.fibers",
                       fmt::format("{} fibers of radius {:.6g} m do not fit without overlap in the {:.6g} x {:.6g} m "
                                   "elliptical section (at most {} do)",
                                   s.tow.fibers, s.fiber.radius, s.tow.width, s.tow.thickness, lo));
    }
  }
  const int nw = f.warp.tows, nf = f.weft.tows;
  const double sw = f.warp.spacing, sf = f.weft.spacing;
  // Warp i along x at y_i; weft j along y at x_j.
  auto warp_y = [&](int i) { return (i - 0.5 * (nw - 1)) * sw; };
  auto weft_x = [&](int j) { return (j - 0.5 * (nf - 1)) * sf; };
  const double x0 = weft_x(0) - f.margin, x1 = weft_x(nf - 1) + f.margin;
  const double y0 = warp_y(0) - f.margin, y1 = warp_y(nw - 1) + f.margin;

  std::vector<std::string> edge_members[4];  // x-, x+, y-, y+
  for (int dir = 0; dir < 2; ++dir) {
    const Direction& d = dirs[dir];
    const FabricDirectionSpec& s = *d.spec;
    const int tows = dir == 0 ? nw : nf;
    // The count as a real first: read_case refuses a fabric too large with its size; here only
    // a count no int holds is stopped before it is converted.
    const double count = fabric_fiber_elements(f, dir == 0);
    if (!(count <= INT_MAX))
      throw InputError(file, fmt::format("fabric.{}.fiber.element_length", d.name),
                       fmt::format("{:.6g} m cuts the {} fibers ({:.6g} m long) into {:.3g} elements each, more than "
                                   "an int holds ({})",
                                   s.fiber.element_length, d.name, fabric_fiber_length(f, dir == 0), count, INT_MAX));
    const int elements = static_cast<int>(count);
    for (int t = 0; t < tows; ++t) {
      TowSpec tow;
      tow.name = fmt::format("{}{}", d.name, t);
      tow.direction = dir == 0 ? TowSpec::Direction::Warp : TowSpec::Direction::Weft;
      tow.index = t;
      Vec3 start_centroid = Vec3::Zero(), end_centroid = Vec3::Zero();
      BindingSpec start_binding, end_binding;
      start_binding.body = tow.name + ".start";
      end_binding.body = tow.name + ".end";
      // The tow-end bodies' axes are the global ones: across a warp tow are D2 (width, in the
      // plane) and D3 (thickness); across a weft tow D1 and D3.
      if (f.grip != FabricSpec::Grip::Averaged) {
        start_binding.grip = {dir == 0 ? 2 : 1};
        if (f.grip == FabricSpec::Grip::Clamped) start_binding.grip.push_back(3);
        end_binding.grip = start_binding.grip;
        start_binding.spin = end_binding.spin = true;
      }
      for (size_t k = 0; k < d.sites.size(); ++k) {
        const Eigen::Vector2d& p = d.sites[k];
        FiberSpec fib;
        fib.name = fmt::format("{}.f{}", tow.name, k);
        fib.material = s.fiber.material;
        fib.radius = s.fiber.radius;
        fib.semi_axis_1 = fib.semi_axis_2 = s.fiber.radius;
        fib.elements = elements;
        fib.path.kind = PathSpec::Kind::Polyline;
        Vec3 a, b;
        if (dir == 0) {
          a = Vec3(x0, warp_y(t) + p.x(), p.y());
          b = Vec3(x1, warp_y(t) + p.x(), p.y());
          fib.section_direction = Vec3::UnitY();
        } else {
          a = Vec3(weft_x(t) + p.x(), y0, p.y());
          b = Vec3(weft_x(t) + p.x(), y1, p.y());
          fib.section_direction = Vec3::UnitX();
        }
        fib.path.points = {a, b};
        start_centroid += a / static_cast<double>(d.sites.size());
        end_centroid += b / static_cast<double>(d.sites.size());
        NodeRef first{fib.name, NodeRef::Kind::First}, last{fib.name, NodeRef::Kind::Last};
        start_binding.ends.push_back(first);
        end_binding.ends.push_back(last);
        tow.fibers.push_back(fib.name);
        c.fibers.push_back(std::move(fib));
      }
      c.bodies.push_back({tow.name + ".start", start_centroid, Mat3::Identity()});
      c.bodies.push_back({tow.name + ".end", end_centroid, Mat3::Identity()});
      start_binding.line = static_cast<int>(c.bindings.size());
      c.bindings.push_back(std::move(start_binding));
      end_binding.line = static_cast<int>(c.bindings.size());
      c.bindings.push_back(std::move(end_binding));
      edge_members[2 * dir].push_back(tow.name + ".start");
      edge_members[2 * dir + 1].push_back(tow.name + ".end");
      c.tows.push_back(std::move(tow));
    }
  }
  for (int e = 0; e < 4; ++e) {
    Vec3 centre = Vec3::Zero();
    for (const std::string& m : edge_members[e])
      for (const BodySpec& b : c.bodies)
        if (b.name == m) centre += b.center / static_cast<double>(edge_members[e].size());
    c.bodies.push_back({kEdgeBodies[e], centre, Mat3::Identity()});
    BindingSpec bind;
    bind.body = kEdgeBodies[e];
    bind.bodies = edge_members[e];
    bind.line = static_cast<int>(c.bindings.size());
    c.bindings.push_back(std::move(bind));
  }
  c.weave = f.matrix;

  // Edge conditions, in the first step unless the user set them: the x- and y- edges held;
  // the x+ and y+ edges free to draw in along their tows under a small tension, held
  // otherwise (the fabric's mid-plane stays at z = 0, no edge turns).
  if (!c.steps.empty()) {
    auto listed = [&](const std::string& name) {
      for (const StepSpec& st : c.steps)
        for (const BodyStepSpec& b : st.bodies)
          if (b.name == name) return true;
      return false;
    };
    double tension_w = f.tension, tension_f = f.tension;
    for (const MaterialSpec& m : c.materials) {
      const double strain = 1e-4;  // default: the tension that strains a fiber by 1e-4
      if (f.tension <= 0 && m.name == f.warp.fiber.material)
        tension_w = strain * m.young * std::numbers::pi * f.warp.fiber.radius * f.warp.fiber.radius;
      if (f.tension <= 0 && m.name == f.weft.fiber.material)
        tension_f = strain * m.young * std::numbers::pi * f.weft.fiber.radius * f.weft.fiber.radius;
    }
    const double fw = tension_w * nw * static_cast<double>(dirs[0].sites.size());
    const double ff = tension_f * nf * static_cast<double>(dirs[1].sites.size());
    StepSpec& first = c.steps.front();
    for (int e = 0; e < 4; ++e) {
      if (listed(kEdgeBodies[e])) continue;
      BodyStepSpec b;
      b.name = kEdgeBodies[e];
      b.has_displacement = b.has_rotation = true;
      b.displacement = {0.0, 0.0, 0.0};
      b.rotation = {0.0, 0.0, 0.0};
      if (e == 1) {
        b.displacement[0].reset();
        b.force = Vec3(fw, 0, 0);
      } else if (e == 3) {
        b.displacement[1].reset();
        b.force = Vec3(0, ff, 0);
      }
      first.bodies.push_back(b);
    }
    // Tow ends held in rotation and out of the plane, free in the plane: a grip does not let a
    // tow end turn in it or leave it.
    // The averaged rotation of a group of fiber ends is only as well defined as the group is
    // far from a line, and a tow end flattens as the fabric relaxes (12 fibers in a tow 0.8 mm
    // wide fit in one layer): the best-fit rotation about the flattened end's long axis then
    // costs nearly nothing, the edge binding only ties the sum of its tow ends' rotations, and
    // the tow ends of one edge turned in opposite senses without end (1.6 rad after 260 relax
    // increments of a 2 x 2 sample of 12 fibers per tow, which never reached equilibrium; held,
    // it relaxed in 39). docs/theory/fabric.md, "Tow ends".
    for (const TowSpec& tow : c.tows)
      for (const char* end : {".start", ".end"}) {
        const std::string name = tow.name + end;
        if (listed(name)) continue;
        BodyStepSpec b;
        b.name = name;
        b.has_rotation = true;
        b.rotation = {0.0, 0.0, 0.0};
        // Held out of the plane too (a grip holds the tow at its plane): free, each tow end's
        // height was a mode of almost no stiffness (a taut free length swinging about its last
        // crossing), which the relax step's drag let creep by a few um per increment on the
        // 480-fiber sample. docs/theory/fabric.md, "Tow ends".
        b.has_displacement = true;
        b.displacement[2] = 0.0;
        first.bodies.push_back(b);
      }
  }
}

}  // namespace fibra
