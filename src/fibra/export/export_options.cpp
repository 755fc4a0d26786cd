#include "fibra/export/export_options.hpp"

#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "fibra/core/error.hpp"
#include "fibra/export/fiber_curve.hpp"

namespace fibra {

namespace {

const char* const kWhere = "fibra export";

[[noreturn]] void fail(const std::string& option, const std::string& message) {
  throw InputError(kWhere, option, message);
}

/// The whole word as a finite number, or nothing.
std::optional<double> number(const std::string& word) {
  double v = 0;
  const char* begin = word.data() + (!word.empty() && word[0] == '+' ? 1 : 0);
  const auto [end, ec] = std::from_chars(begin, word.data() + word.size(), v);
  if (word.empty() || ec != std::errc() || end != word.data() + word.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

/// The whole word as an integer, or nothing.
std::optional<long long> integer(const std::string& word) {
  long long v = 0;
  const char* begin = word.data() + (!word.empty() && word[0] == '+' ? 1 : 0);
  const auto [end, ec] = std::from_chars(begin, word.data() + word.size(), v);
  if (word.empty() || ec != std::errc() || end != word.data() + word.size()) return std::nullopt;
  return v;
}

std::string quoted(const std::vector<std::string>& words) { return fmt::format("\"{}\"", fmt::join(words, " ")); }

std::array<Index, 3> parse_voxels(const std::vector<std::string>& words) {
  const std::string expected = "expected three whole numbers NX NY NZ >= 1 (voxels along x, y and z)";
  if (words.size() != 3) fail("--voxels", fmt::format("{}, got {}", expected, quoted(words)));
  std::array<Index, 3> n{};
  for (int k = 0; k < 3; ++k) {
    const std::optional<long long> v = integer(words[k]);
    if (!v || *v < 1) fail("--voxels", fmt::format("{}, got {}", expected, quoted(words)));
    n[k] = static_cast<Index>(*v);
  }
  return n;
}

double parse_voxel_size(const std::vector<std::string>& words) {
  const std::optional<double> h = words.size() == 1 ? number(words[0]) : std::nullopt;
  if (!h || *h <= 0)
    fail("--voxel-size", fmt::format("expected one length H > 0 in metres (the voxels' edge), got {}", quoted(words)));
  return *h;
}

Eigen::AlignedBox3d parse_box(const std::vector<std::string>& words) {
  const std::string expected = "expected six numbers XMIN YMIN ZMIN XMAX YMAX ZMAX in metres with each min < max";
  if (words.size() != 6) fail("--box", fmt::format("{}, got {}", expected, quoted(words)));
  double v[6];
  for (int k = 0; k < 6; ++k) {
    const std::optional<double> x = number(words[k]);
    if (!x) fail("--box", fmt::format("{}, got {}", expected, quoted(words)));
    v[k] = *x;
  }
  static const char* const kAxes[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    if (!(v[k] < v[k + 3]))
      fail("--box", fmt::format("{}: the box is empty along {} ({} >= {})", expected, kAxes[k], v[k], v[k + 3]));
  return {Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5])};
}

int parse_samples(const std::vector<std::string>& words) {
  const std::optional<long long> k = words.size() == 1 ? integer(words[0]) : std::nullopt;
  if (!k || *k < 1 || *k > kMaxSamples)
    fail("--samples", fmt::format("expected one whole number K from 1 to {} (K^3 points per voxel), got {}",
                                  kMaxSamples, quoted(words)));
  return static_cast<int>(*k);
}

}  // namespace

ExportOptions parse_export_options(const std::string& out, const std::vector<std::string>& voxels,
                                   const std::vector<std::string>& voxel_size, const std::vector<std::string>& box,
                                   const std::vector<std::string>& samples) {
  ExportOptions o;
  if (out.empty()) fail("--out", "expected the directory to write the export into");
  o.out = out;
  if (!voxels.empty() && !voxel_size.empty())
    fail("--voxels", "give either --voxels NX NY NZ or --voxel-size H, not both");
  if (!voxels.empty()) o.voxels = parse_voxels(voxels);
  if (!voxel_size.empty()) o.voxel_size = parse_voxel_size(voxel_size);
  if (!box.empty()) o.box = parse_box(box);
  if (!samples.empty()) o.samples = parse_samples(samples);
  return o;
}

Eigen::AlignedBox3d fibers_bounds(const Model& model, const VecX& q) {
  Eigen::AlignedBox3d box;
  for (const BeamElement& el : model.elements) {
    const Section& s = model.sections[el.section];
    for (int k = 0; k < 8; ++k) {
      const SectionPoint p = element_point(q, el, -1.0 + 2.0 * k / 7.0);
      Vec3 reach;
      for (int axis = 0; axis < 3; ++axis) reach[axis] = section_support(p.g1, p.g2, s.a, s.b, Vec3::Unit(axis));
      box.extend(Vec3(p.x - reach));
      box.extend(Vec3(p.x + reach));
    }
  }
  return box;
}

std::string describe_box(const Eigen::AlignedBox3d& b) {
  return fmt::format("x from {:.6g} to {:.6g}, y from {:.6g} to {:.6g}, z from {:.6g} to {:.6g} m", b.min().x(),
                     b.max().x(), b.min().y(), b.max().y(), b.min().z(), b.max().z());
}

VoxelGrid export_grid(const ExportOptions& options, const Eigen::AlignedBox3d& fibers) {
  const Eigen::AlignedBox3d box = options.box ? *options.box : fibers;
  if (options.box && !options.box->intersects(fibers))
    fail("--box", fmt::format("the box ({}) holds no fiber: expected a box that meets the fibers, which span {}",
                              describe_box(box), describe_box(fibers)));
  std::array<Index, 3> count{};
  double total = 1;
  if (options.voxels) {
    count = *options.voxels;
    for (Index n : count) total *= static_cast<double>(n);
  } else {
    const double h = options.voxel_size ? *options.voxel_size
                                        : box.sizes().maxCoeff() / static_cast<double>(kDefaultVoxelsAlongLongestSide);
    for (int k = 0; k < 3; ++k) {
      // A side that is a whole number of H up to rounding is not given one more voxel.
      const double n = std::max(1.0, std::ceil(box.sizes()[k] / h * (1.0 - 1e-12)));
      total *= n;
      count[k] = n < 1e18 ? static_cast<Index>(n) : Index{0};
    }
  }
  if (total > static_cast<double>(kMaxExportVoxels)) {
    const char* option = options.voxels ? "--voxels" : "--voxel-size";
    fail(option, fmt::format("{:.4g} voxels is more than the {} an export holds in memory: expected fewer voxels "
                             "(larger ones with --voxel-size, or a smaller --box)",
                             total, kMaxExportVoxels));
  }
  return VoxelGrid::over(box, count);
}

}  // namespace fibra
