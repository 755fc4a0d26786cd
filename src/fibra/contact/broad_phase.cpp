#include "fibra/contact/broad_phase.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace fibra {
namespace {

// Cell coordinate of x along one axis (clamped to keep the hash arithmetic bounded).
int cell_coord(double x, double origin, double inv_cell) {
  const double c = std::floor((x - origin) * inv_cell);
  return static_cast<int>(std::clamp(c, -1.0e9, 1.0e9));
}

std::uint64_t cell_hash(int i, int j, int k) {
  std::uint64_t h = static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) * 0x9E3779B97F4A7C15ull;
  h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(j)) * 0xC2B2AE3D27D4EB4Full;
  h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(k)) * 0x165667B19E3779F9ull;
  return h ^ (h >> 29);
}

}  // namespace

CentroidCurve centroid_curve(const double* q_e) {
  const Eigen::Map<const Vec3> x0(q_e), x1(q_e + kNodeDofs), x2(q_e + 2 * kNodeDofs);
  return {0.5 * (x0 - 2.0 * x1 + x2), 0.5 * (x2 - x0), x1};
}

Box element_box(const CentroidCurve& curve, double inflation) {
  const Vec3 start = curve.value(-1.0), end = curve.value(1.0);
  Box box{start.cwiseMin(end), start.cwiseMax(end)};
  for (int d = 0; d < 3; ++d) {
    // Interior extremum of c + b eta + a eta^2 at eta = -b / (2a).
    if (curve.a[d] != 0.0) {
      const double eta = -curve.b[d] / (2.0 * curve.a[d]);
      if (eta > -1.0 && eta < 1.0) {
        const double v = curve.c[d] + eta * (curve.b[d] + eta * curve.a[d]);
        box.lo[d] = std::min(box.lo[d], v);
        box.hi[d] = std::max(box.hi[d], v);
      }
    }
  }
  box.lo.array() -= inflation;
  box.hi.array() += inflation;
  return box;
}

BroadPhase::BroadPhase(const Model& model, BroadPhaseParams params) : m_model(model) {
  const Index n = static_cast<Index>(model.elements.size());
  m_info.resize(n);
  m_self_exclusion.resize(model.fibers.size());
  for (size_t f = 0; f < model.fibers.size(); ++f) {
    const Fiber& fib = model.fibers[f];
    const Section& sec = model.sections[fib.section];
    const double r = std::max(sec.a, sec.b);
    const double margin = params.margin > 0 ? params.margin : 0.5 * r;
    m_self_exclusion[f] = params.self_exclusion > 0 ? params.self_exclusion : 8.0 * r;
    for (Index k = 0; k < fib.num_elements; ++k) {
      ContactBeamInfo& info = m_info[fib.first_element + k];
      info.fiber = static_cast<int>(f);
      info.local = k;
      info.radius = r;
      info.inflation = r + margin;
      info.length = fib.length / static_cast<double>(fib.num_elements);
    }
  }
  m_curves.resize(n);
  m_boxes.resize(n);
  m_cell_range.resize(6 * n);
  m_entry_begin.resize(n + 1);
}

bool BroadPhase::excluded(Index a, Index b) const {
  const ContactBeamInfo& ia = m_info[a];
  const ContactBeamInfo& ib = m_info[b];
  if (ia.fiber != ib.fiber) return false;
  const Index gap_elements = std::max<Index>(std::abs(ia.local - ib.local) - 1, 0);
  const double separation = static_cast<double>(gap_elements) * ia.length;
  return a == b || separation < m_self_exclusion[ia.fiber];
}

const std::vector<ElementPair>& BroadPhase::find_pairs(const VecX& q) {
  const Index n = static_cast<Index>(m_info.size());
  m_pairs.clear();
  if (n == 0) return m_pairs;

  // 1. Curves and boxes; mean box extent along each axis and the scene's bounds.
  double ext_x = 0, ext_y = 0, ext_z = 0;
  double lo_x = 1e300, lo_y = 1e300, lo_z = 1e300, hi_x = -1e300, hi_y = -1e300, hi_z = -1e300;
#pragma omp parallel for schedule(static) reduction(+ : ext_x, ext_y, ext_z) \
    reduction(min : lo_x, lo_y, lo_z) reduction(max : hi_x, hi_y, hi_z)
  for (Index e = 0; e < n; ++e) {
    m_curves[e] = centroid_curve(q.data() + m_model.elements[e].first_dof);
    const Box& box = m_boxes[e] = element_box(m_curves[e], m_info[e].inflation);
    ext_x += box.hi.x() - box.lo.x();
    ext_y += box.hi.y() - box.lo.y();
    ext_z += box.hi.z() - box.lo.z();
    lo_x = std::min(lo_x, box.lo.x());
    lo_y = std::min(lo_y, box.lo.y());
    lo_z = std::min(lo_z, box.lo.z());
    hi_x = std::max(hi_x, box.hi.x());
    hi_y = std::max(hi_y, box.hi.y());
    hi_z = std::max(hi_z, box.hi.z());
  }
  // Cells as large as the mean box along each axis (each box covers about 2 x 2 x 2 cells
  // whatever the boxes' common orientation), and at most 2^20 per axis across the scene.
  m_origin = Vec3(lo_x, lo_y, lo_z);
  const Vec3 scene(hi_x - lo_x, hi_y - lo_y, hi_z - lo_z);
  const Vec3 mean = Vec3(ext_x, ext_y, ext_z) / static_cast<double>(n);
  for (int d = 0; d < 3; ++d) m_cell[d] = std::max({mean[d], scene[d] / 1048576.0, 1e-300});
  const Vec3 inv_cell = m_cell.cwiseInverse();

  // 2. Cell ranges of every box; entry slots by prefix sum.
  m_entry_begin[0] = 0;
  for (Index e = 0; e < n; ++e) {
    int* r = &m_cell_range[6 * e];
    Index count = 1;
    for (int d = 0; d < 3; ++d) {
      r[d] = cell_coord(m_boxes[e].lo[d], m_origin[d], inv_cell[d]);
      r[3 + d] = cell_coord(m_boxes[e].hi[d], m_origin[d], inv_cell[d]);
      count *= r[3 + d] - r[d] + 1;
    }
    m_entry_begin[e + 1] = m_entry_begin[e] + count;
  }
  const Index num_entries = m_entry_begin[n];

  // 3. Counting sort of the (element, cell) entries into hash buckets (stable: element order).
  std::uint64_t buckets = 16;
  while (buckets < 2 * static_cast<std::uint64_t>(num_entries)) buckets <<= 1;
  m_bucket_mask = buckets - 1;
  m_bucket_begin.assign(buckets + 1, 0);
  m_entries.resize(num_entries);
  auto for_cells = [&](Index e, auto&& f) {
    const int* r = &m_cell_range[6 * e];
    for (int i = r[0]; i <= r[3]; ++i)
      for (int j = r[1]; j <= r[4]; ++j)
        for (int k = r[2]; k <= r[5]; ++k) f(i, j, k);
  };
  for (Index e = 0; e < n; ++e)
    for_cells(e, [&](int i, int j, int k) { ++m_bucket_begin[(cell_hash(i, j, k) & m_bucket_mask) + 1]; });
  for (std::uint64_t b = 0; b < buckets; ++b) m_bucket_begin[b + 1] += m_bucket_begin[b];
  // Fill with each bucket's begin as its cursor, then shift the begins back.
  for (Index e = 0; e < n; ++e)
    for_cells(e, [&](int i, int j, int k) {
      const std::uint64_t b = cell_hash(i, j, k) & m_bucket_mask;
      m_entries[m_bucket_begin[b]++] = Entry{e, {i, j, k}};
    });
  for (std::uint64_t b = buckets; b > 0; --b) m_bucket_begin[b] = m_bucket_begin[b - 1];
  m_bucket_begin[0] = 0;

  // 4. Pairs: element a meets the entries b > a of its cells; a pair is reported only in the
  // cell holding the lower corner of the two boxes' intersection, hence exactly once.
  const int threads = omp_get_max_threads();
  if (static_cast<int>(m_thread_pairs.size()) < threads) m_thread_pairs.resize(threads);
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const int nt = omp_get_num_threads();
    std::vector<ElementPair>& out = m_thread_pairs[t];
    out.clear();
    const Index begin = n * t / nt, end = n * (t + 1) / nt;
    for (Index a = begin; a < end; ++a) {
      const Box& box_a = m_boxes[a];
      const size_t first = out.size();
      for_cells(a, [&](int i, int j, int k) {
        const std::uint64_t bucket = cell_hash(i, j, k) & m_bucket_mask;
        for (Index s = m_bucket_begin[bucket]; s < m_bucket_begin[bucket + 1]; ++s) {
          const Entry& entry = m_entries[s];
          const Index b = entry.element;
          if (b <= a || entry.cell[0] != i || entry.cell[1] != j || entry.cell[2] != k) continue;
          const Box& box_b = m_boxes[b];
          if (!box_a.overlaps(box_b)) continue;
          const Vec3 corner = box_a.lo.cwiseMax(box_b.lo);
          if (cell_coord(corner.x(), m_origin.x(), inv_cell.x()) != i ||
              cell_coord(corner.y(), m_origin.y(), inv_cell.y()) != j ||
              cell_coord(corner.z(), m_origin.z(), inv_cell.z()) != k)
            continue;
          if (excluded(a, b)) continue;
          out.push_back({a, b});
        }
      });
      std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(),
                [](const ElementPair& x, const ElementPair& y) { return x.second < y.second; });
    }
  }
  // Deterministic merge: threads own consecutive element ranges.
  for (int t = 0; t < threads; ++t) m_pairs.insert(m_pairs.end(), m_thread_pairs[t].begin(), m_thread_pairs[t].end());
  return m_pairs;
}

}  // namespace fibra
