#include "fibra/solver/single_factor.hpp"

#include <omp.h>

#include <algorithm>
#include <numeric>

namespace fibra {
namespace {

// Below this length a loop runs scalar: the vector loop's set-up and horizontal sums cost more
// than they save.
constexpr Index kShort = 16;
// Rows below a supernode's diagonal block from which four columns are taken at a time.
constexpr Index kBlock = 32;

/// sum_i a[i] * b[i] over n entries.
inline double dot(const float* a, const double* b, Index n) {
  double sum = 0.0;
  if (n < kShort) {
    for (Index i = 0; i < n; ++i) sum += static_cast<double>(a[i]) * b[i];
    return sum;
  }
#pragma omp simd reduction(+ : sum)
  for (Index i = 0; i < n; ++i) sum += static_cast<double>(a[i]) * b[i];
  return sum;
}

/// y[i] += a[i] * x over n entries.
inline void axpy(const float* a, double x, double* y, Index n) {
  if (n < kShort) {
    for (Index i = 0; i < n; ++i) y[i] += static_cast<double>(a[i]) * x;
    return;
  }
#pragma omp simd
  for (Index i = 0; i < n; ++i) y[i] += static_cast<double>(a[i]) * x;
}

}  // namespace

void SingleFactor::assign(const SupernodalView& f) {
  const Index ns = f.nsuper;
  // The structure (and the tree's cut) only changes with a new analysis.
  const bool same = m_n == f.n && static_cast<Index>(m_super.size()) == ns + 1 &&
                    std::equal(m_super.begin(), m_super.end(), f.super) && std::equal(m_pi.begin(), m_pi.end(), f.pi) &&
                    std::equal(m_perm.begin(), m_perm.end(), f.perm) &&
                    static_cast<Index>(m_s_rows.size()) == f.pi[ns] &&
                    std::equal(m_s_rows.begin(), m_s_rows.end(), f.s_rows);
  if (!same) {
    m_n = f.n;
    m_super.assign(f.super, f.super + ns + 1);
    m_pi.assign(f.pi, f.pi + ns + 1);
    m_px.resize(ns + 1);
    for (Index s = 0; s <= ns; ++s) m_px[s] = f.px[s];
    m_s_rows.assign(f.s_rows, f.s_rows + f.pi[ns]);
    m_perm.assign(f.perm, f.perm + f.n);
    Index widest = 1;
    for (Index s = 0; s < ns; ++s)
      widest = std::max<Index>(widest, (m_pi[s + 1] - m_pi[s]) - (m_super[s + 1] - m_super[s]));
    for (int p = 0; p < 2; ++p) {
      m_scratch[p].assign(widest, 0.0);
      m_delta[p].assign(m_n, 0.0);
    }
    m_work.assign(m_n, 0.0);
    // Packed: column j of a supernode keeps its rows j .. nsrow-1 (CHOLMOD stores the diagonal
    // block whole, its upper triangle unused: 14 % of the values on the 480-fiber twill). A
    // supernode's size is where its column nscol would start.
    m_offset.assign(ns + 1, 0);
    for (Index s = 0; s < ns; ++s)
      m_offset[s + 1] = m_offset[s] + packed_column(m_super[s + 1] - m_super[s], m_pi[s + 1] - m_pi[s]);
    split_tree();
  }
  m_values.resize(m_offset[ns]);
  float* out = m_values.data();
  const double* in = f.values;
  const std::int64_t* px = m_px.data();
  const std::int64_t* offset = m_offset.data();
#pragma omp parallel for schedule(dynamic, 64)
  for (Index s = 0; s < ns; ++s) {
    const Index nscol = m_super[s + 1] - m_super[s], nsrow = m_pi[s + 1] - m_pi[s];
    for (Index j = 0; j < nscol; ++j) {
      const double* from = in + px[s] + static_cast<std::int64_t>(j) * nsrow + j;
      float* to = out + offset[s] + packed_column(j, nsrow);
      for (Index i = 0; i < nsrow - j; ++i) to[i] = static_cast<float>(from[i]);
    }
  }
}

void SingleFactor::split_tree() {
  const Index ns = static_cast<Index>(m_super.size()) - 1;
  for (auto& p : m_part) p.clear();
  m_top.clear();
  m_top_columns.clear();
  // Supernodal tree: a supernode's parent holds its first row below the diagonal block.
  std::vector<Index> super_of(m_n);
  for (Index s = 0; s < ns; ++s)
    for (Index c = m_super[s]; c < m_super[s + 1]; ++c) super_of[c] = s;
  std::vector<Index> parent(ns, -1), first(ns), work(ns), count(ns, 1);
  std::iota(first.begin(), first.end(), Index{0});
  std::vector<std::vector<Index>> children(ns);
  std::vector<Index> roots;
  for (Index s = 0; s < ns; ++s) {
    const Index nscol = m_super[s + 1] - m_super[s], nsrow = m_pi[s + 1] - m_pi[s];
    work[s] += nscol * nsrow;
    if (nsrow > nscol) {
      parent[s] = super_of[m_s_rows[m_pi[s] + nscol]];
      children[parent[s]].push_back(s);
    } else {
      roots.push_back(s);
    }
  }
  bool postordered = true;
  for (Index s = 0; s < ns; ++s) {
    const Index p = parent[s];
    if (p < 0) continue;
    if (p <= s) postordered = false;
    work[p] += work[s];
    count[p] += count[s];
    first[p] = std::min(first[p], first[s]);
  }
  // Subtrees must be contiguous ranges (CHOLMOD postorders its supernodes); else one part
  // holding every supernode, on one thread.
  for (Index s = 0; s < ns && postordered; ++s) postordered = s - first[s] + 1 == count[s];
  if (!postordered) {
    m_part[0] = {{0, ns - 1, m_n}};
    m_top_share = 0.0;
    return;
  }
  const double total = std::accumulate(roots.begin(), roots.end(), 0.0, [&](double a, Index r) { return a + work[r]; });
  std::vector<Index> open = roots, top;
  std::vector<Index> bins[2];
  double top_work = 0.0;
  for (int round = 0; round < 256; ++round) {
    // Largest first into the lighter bin.
    std::sort(open.begin(), open.end(), [&](Index a, Index b) { return work[a] > work[b] || (work[a] == work[b] && a < b); });
    double load[2] = {0.0, 0.0};
    bins[0].clear();
    bins[1].clear();
    for (Index s : open) {
      const int b = load[1] < load[0] ? 1 : 0;
      bins[b].push_back(s);
      load[b] += work[s];
    }
    if (std::max(load[0], load[1]) <= 1.05 * std::min(load[0], load[1]) || open.empty()) break;
    // Too uneven: the largest subtree's root goes to the top, its children are shared out.
    const Index s = open.front();
    double own = work[s];
    for (Index c : children[s]) own -= work[c];
    if (top_work + own > 0.4 * total) break;
    open.erase(open.begin());
    open.insert(open.end(), children[s].begin(), children[s].end());
    top_work += own;
    top.push_back(s);
  }
  if (bins[0].empty() || bins[1].empty()) {
    // One part holding the whole tree (no top): still correct, on one thread.
    bins[0] = roots;
    bins[1].clear();
    top.clear();
    top_work = 0.0;
  }
  for (int b = 0; b < 2; ++b) {
    std::sort(bins[b].begin(), bins[b].end());
    for (Index r : bins[b]) m_part[b].push_back({first[r], r, m_super[r + 1]});
  }
  std::sort(top.begin(), top.end());
  m_top = top;
  for (Index s : m_top)
    for (Index c = m_super[s]; c < m_super[s + 1]; ++c) m_top_columns.push_back(c);
  m_top_share = total > 0.0 ? top_work / total : 0.0;
}

SingleFactor::Node SingleFactor::node(Index s) const {
  Node d;
  d.first_column = m_super[s];
  d.nscol = m_super[s + 1] - d.first_column;
  d.nsrow = m_pi[s + 1] - m_pi[s];
  d.below = d.nsrow - d.nscol;
  d.rows = m_s_rows.data() + m_pi[s];
  d.l = m_values.data() + m_offset[s];
  return d;
}

void SingleFactor::forward(Index s, Index end_column, double* y, double* delta, double* t) const {
  const auto [k1, nscol, nsrow, node_below, rows, l] = node(s);
  const Index below = node_below;  // a variable, not a binding: Clang 14 has none in OpenMP loops
  double* ys = y + k1;
  // The diagonal block's triangle by columns (column j packed from its diagonal down).
  for (Index j = 0; j < nscol; ++j) {
    const float* col = l + packed_column(j, nsrow);
    const double yj = ys[j] / static_cast<double>(col[0]);
    ys[j] = yj;
    axpy(col + 1, -yj, ys + j + 1, nscol - j - 1);
  }
  if (below == 0) return;
  // t = (rows below) * y_s, four columns at a time (one pass over t per four columns).
  std::fill(t, t + below, 0.0);
  Index j = 0;
  for (; below >= kBlock && j + 4 <= nscol; j += 4) {
    const float* c0 = below_part(l, j, nscol, nsrow);
    const float* c1 = below_part(l, j + 1, nscol, nsrow);
    const float* c2 = below_part(l, j + 2, nscol, nsrow);
    const float* c3 = below_part(l, j + 3, nscol, nsrow);
    const double y0 = ys[j], y1 = ys[j + 1], y2 = ys[j + 2], y3 = ys[j + 3];
#pragma omp simd
    for (Index i = 0; i < below; ++i)
      t[i] += static_cast<double>(c0[i]) * y0 + static_cast<double>(c1[i]) * y1 + static_cast<double>(c2[i]) * y2 +
              static_cast<double>(c3[i]) * y3;
  }
  for (; j < nscol; ++j) axpy(below_part(l, j, nscol, nsrow), ys[j], t, below);
  // Rows of this part into y, rows of the top (at or beyond end_column) into delta (added up
  // and subtracted from y once both parts are done).
  for (Index i = 0; i < below; ++i) {
    const int r = rows[nscol + i];
    if (r < end_column)
      y[r] -= t[i];
    else
      delta[r] += t[i];
  }
}

void SingleFactor::backward(Index s, double* y, double* t) const {
  const auto [k1, nscol, nsrow, node_below, rows, l] = node(s);
  const Index below = node_below;  // a variable, not a binding: Clang 14 has none in OpenMP loops
  double* ys = y + k1;
  if (below > 0) {
    // The rows below gathered once; their dot products with the columns four at a time.
    for (Index i = 0; i < below; ++i) t[i] = y[rows[nscol + i]];
    Index j = 0;
    for (; below >= kBlock && j + 4 <= nscol; j += 4) {
      const float* c0 = below_part(l, j, nscol, nsrow);
      const float* c1 = below_part(l, j + 1, nscol, nsrow);
      const float* c2 = below_part(l, j + 2, nscol, nsrow);
      const float* c3 = below_part(l, j + 3, nscol, nsrow);
      double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
#pragma omp simd reduction(+ : s0, s1, s2, s3)
      for (Index i = 0; i < below; ++i) {
        s0 += static_cast<double>(c0[i]) * t[i];
        s1 += static_cast<double>(c1[i]) * t[i];
        s2 += static_cast<double>(c2[i]) * t[i];
        s3 += static_cast<double>(c3[i]) * t[i];
      }
      ys[j] -= s0;
      ys[j + 1] -= s1;
      ys[j + 2] -= s2;
      ys[j + 3] -= s3;
    }
    for (; j < nscol; ++j) ys[j] -= dot(below_part(l, j, nscol, nsrow), t, below);
  }
  // The diagonal block's triangle, last column first.
  for (Index j = nscol - 1; j >= 0; --j) {
    const float* col = l + packed_column(j, nsrow);
    ys[j] = (ys[j] - dot(col + 1, ys + j + 1, nscol - j - 1)) / static_cast<double>(col[0]);
  }
}

void SingleFactor::solve(const VecX& b, VecX& x) {
  const Index n = m_n;
  double* y = m_work.data();
  for (Index k = 0; k < n; ++k) y[k] = b[m_perm[k]];
  const int threads = std::min(2, omp_get_max_threads());

  // Forward: the two parts side by side (their updates of the top kept apart), then the top.
#pragma omp parallel for num_threads(threads) schedule(static, 1)
  for (int p = 0; p < 2; ++p)
    for (const Range& r : m_part[p])
      for (Index s = r.first; s <= r.last; ++s) forward(s, r.end_column, y, m_delta[p].data(), m_scratch[p].data());
  for (Index c : m_top_columns) {
    y[c] -= m_delta[0][c] + m_delta[1][c];
    m_delta[0][c] = m_delta[1][c] = 0.0;
  }
  for (Index s : m_top) forward(s, n, y, m_delta[0].data(), m_scratch[0].data());

  // Back: the top first, then the parts side by side (they read the top, write their own).
  for (auto it = m_top.rbegin(); it != m_top.rend(); ++it) backward(*it, y, m_scratch[0].data());
#pragma omp parallel for num_threads(threads) schedule(static, 1)
  for (int p = 0; p < 2; ++p)
    for (auto r = m_part[p].rbegin(); r != m_part[p].rend(); ++r)
      for (Index s = r->last; s >= r->first; --s) backward(s, y, m_scratch[p].data());

  x.resize(n);
  for (Index k = 0; k < n; ++k) x[m_perm[k]] = y[k];
}

}  // namespace fibra
