#include "fibra/solver/rounded_factor.hpp"

#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>

#if defined(__F16C__)
#include <immintrin.h>
#endif

namespace fibra {
namespace {

/// w[i] -= sum_k c_k[i] x_k over n entries, for W columns c_k (one pass over w). The columns'
/// pointers and weights are held in locals: read through `c` inside the loop, GCC vectorized
/// the loads as gathers and kept the sums on the stack.
template <int W>
inline void update(const float* const* c, const double* x, double* w, Index n) {
  const float* __restrict c0 = c[0];
  const float* __restrict c1 = c[W > 1 ? 1 : 0];
  const float* __restrict c2 = c[W > 2 ? 2 : 0];
  const float* __restrict c3 = c[W > 3 ? 3 : 0];
  const double x0 = x[0], x1 = W > 1 ? x[1] : 0.0, x2 = W > 2 ? x[2] : 0.0, x3 = W > 3 ? x[3] : 0.0;
  double* __restrict out = w;
#pragma omp simd
  for (Index i = 0; i < n; ++i) {
    double sum = static_cast<double>(c0[i]) * x0;
    if constexpr (W > 1) sum += static_cast<double>(c1[i]) * x1;
    if constexpr (W > 2) sum += static_cast<double>(c2[i]) * x2;
    if constexpr (W > 3) sum += static_cast<double>(c3[i]) * x3;
    out[i] -= sum;
  }
}

inline void update(int width, const float* const* c, const double* x, double* w, Index n) {
  switch (width) {
    case 4: return update<4>(c, x, w, n);
    case 3: return update<3>(c, x, w, n);
    case 2: return update<2>(c, x, w, n);
    default: return update<1>(c, x, w, n);
  }
}

/// s = sum_i c[i] w[i] over n entries.
inline double dot(const float* __restrict c, const double* __restrict w, Index n) {
  double sum = 0.0;
#pragma omp simd reduction(+ : sum)
  for (Index i = 0; i < n; ++i) sum += static_cast<double>(c[i]) * w[i];
  return sum;
}

/// s_k = sum_i c_k[i] w[i] over n entries for `width` columns c_k: four in one pass over w,
/// fewer one by one.
inline void dots(int width, const float* const* c, const double* w, Index n, double* s) {
  if (width == 4) {
    const float* __restrict c0 = c[0];
    const float* __restrict c1 = c[1];
    const float* __restrict c2 = c[2];
    const float* __restrict c3 = c[3];
    const double* __restrict v = w;
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
#pragma omp simd reduction(+ : s0, s1, s2, s3)
    for (Index i = 0; i < n; ++i) {
      const double wi = v[i];
      s0 += static_cast<double>(c0[i]) * wi;
      s1 += static_cast<double>(c1[i]) * wi;
      s2 += static_cast<double>(c2[i]) * wi;
      s3 += static_cast<double>(c3[i]) * wi;
    }
    s[0] = s0;
    s[1] = s1;
    s[2] = s2;
    s[3] = s3;
    return;
  }
  for (int k = 0; k < width; ++k) s[k] = dot(c[k], w, n);
}

// Columns of a supernode converted (or addressed) together: the substitutions' unit of work.
constexpr Index kColumns = 4;

/// n halves to floats.
inline void halves_to_floats(const std::uint16_t* in, float* out, std::int64_t n) {
  std::int64_t i = 0;
#if defined(__F16C__)
  for (; i + 8 <= n; i += 8)
    _mm256_storeu_ps(out + i, _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i))));
#endif
  for (; i < n; ++i) out[i] = half_to_float(in[i]);
}

}  // namespace

std::uint16_t float_to_half_in_software(float value) {
  const std::uint32_t f = std::bit_cast<std::uint32_t>(value);
  const std::uint32_t sign = (f >> 16) & 0x8000u;
  const std::uint32_t a = f & 0x7fffffffu;
  if (a >= 0x7f800000u) return static_cast<std::uint16_t>(sign | (a > 0x7f800000u ? 0x7e00u : 0x7c00u));
  if (a >= 0x477ff000u) return static_cast<std::uint16_t>(sign | 0x7c00u);  // 65520 and up: infinity
  if (a < 0x38800000u) {
    // Below 2^-14, the smallest normal half: a subnormal m 2^-24, or zero up to 2^-25.
    if (a < 0x33000000u) return static_cast<std::uint16_t>(sign);
    const std::uint32_t e = a >> 23, m = (a & 0x7fffffu) | 0x800000u;
    const std::uint32_t shift = 126 - e;  // 14 .. 24
    std::uint32_t h = m >> shift;
    const std::uint32_t rest = m & ((1u << shift) - 1), halfway = 1u << (shift - 1);
    if (rest > halfway || (rest == halfway && (h & 1u))) ++h;
    return static_cast<std::uint16_t>(sign | h);
  }
  std::uint32_t h = (a >> 13) - (112u << 10);  // the exponent rebiased, the mantissa's top 10 bits
  const std::uint32_t rest = a & 0x1fffu;
  if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // a carry into the exponent is right
  return static_cast<std::uint16_t>(sign | h);
}

float half_to_float_in_software(std::uint16_t bits) {
  const std::uint32_t sign = static_cast<std::uint32_t>(bits & 0x8000u) << 16;
  const std::uint32_t e = (bits >> 10) & 0x1fu, m = bits & 0x3ffu;
  if (e == 0) {
    const float v = static_cast<float>(m) * 0x1p-24f;
    return sign ? -v : v;
  }
  if (e == 31) return std::bit_cast<float>(sign | 0x7f800000u | (m << 13));
  return std::bit_cast<float>(sign | ((e + 112u) << 23) | (m << 13));
}

std::uint16_t float_to_half(float value) {
#if defined(__F16C__)
  return static_cast<std::uint16_t>(_cvtss_sh(value, _MM_FROUND_TO_NEAREST_INT));
#else
  return float_to_half_in_software(value);
#endif
}

float half_to_float(std::uint16_t bits) {
#if defined(__F16C__)
  return _cvtsh_ss(bits);
#else
  return half_to_float_in_software(bits);
#endif
}

bool halves_in_hardware() {
#if defined(__F16C__)
  return true;
#else
  return false;
#endif
}

void RoundedFactor::assign(const SupernodalView& f, FactorStorage storage) {
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
    Index tallest = 1;
    for (Index s = 0; s < ns; ++s) tallest = std::max<Index>(tallest, m_pi[s + 1] - m_pi[s]);
    for (int p = 0; p < 2; ++p) {
      m_block[p].assign(static_cast<std::size_t>(kColumns) * tallest, 0.0f);
      m_scratch[p].assign(tallest, 0.0);
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
  m_storage = storage;
  const std::int64_t count = m_offset[ns];
  const double* in = f.values;
  const std::int64_t* px = m_px.data();
  const std::int64_t* offset = m_offset.data();
  const int* super = m_super.data();
  const int* pi = m_pi.data();
  const int* s_rows = m_s_rows.data();
  m_pivot.resize(m_n);
  double* pivot = m_pivot.data();
  if (storage == FactorStorage::Float) {
    m_halves.clear();
    m_halves.shrink_to_fit();
    m_scale.clear();
    m_values.resize(count);
    float* out = m_values.data();
#pragma omp parallel for schedule(dynamic, 64)
    for (Index s = 0; s < ns; ++s) {
      const Index nscol = super[s + 1] - super[s], nsrow = pi[s + 1] - pi[s];
      for (Index j = 0; j < nscol; ++j) {
        const double* from = in + px[s] + static_cast<std::int64_t>(j) * nsrow + j;
        float* to = out + offset[s] + packed_column(j, nsrow);
        for (Index i = 0; i < nsrow - j; ++i) to[i] = static_cast<float>(from[i]);
        pivot[super[s] + j] = from[0];
      }
    }
    return;
  }
  // Halves: each row scaled by 1 / sqrt((P A P^T)_kk), the row's length in L.
  m_values.clear();
  m_values.shrink_to_fit();
  m_halves.resize(count);
  m_scale.assign(m_n, 0.0);
  double* scale = m_scale.data();
  if (f.diagonal) {
    for (Index k = 0; k < m_n; ++k) scale[k] = f.diagonal[m_perm[k]];
  } else {
    for (Index s = 0; s < ns; ++s) {
      const Index nscol = super[s + 1] - super[s], nsrow = pi[s + 1] - pi[s];
      const int* rows = s_rows + pi[s];
      for (Index j = 0; j < nscol; ++j) {
        const double* from = in + px[s] + static_cast<std::int64_t>(j) * nsrow;
        for (Index i = j; i < nsrow; ++i) scale[rows[i]] += from[i] * from[i];
      }
    }
  }
  for (Index k = 0; k < m_n; ++k) scale[k] = scale[k] > 0.0 ? 1.0 / std::sqrt(scale[k]) : 1.0;
  std::uint16_t* out = m_halves.data();
#pragma omp parallel for schedule(dynamic, 64)
  for (Index s = 0; s < ns; ++s) {
    const Index nscol = super[s + 1] - super[s], nsrow = pi[s + 1] - pi[s];
    const int* rows = s_rows + pi[s];
    for (Index j = 0; j < nscol; ++j) {
      const double* from = in + px[s] + static_cast<std::int64_t>(j) * nsrow;
      std::uint16_t* to = out + offset[s] + packed_column(j, nsrow) - j;
      // Through a float (F16C rounds floats): once in a while a value lands a half's unit away
      // from the half nearest the double, the same way on every run.
      for (Index i = j; i < nsrow; ++i) to[i] = float_to_half(static_cast<float>(from[i] * scale[rows[i]]));
      pivot[super[s] + j] = from[j] * scale[rows[j]];
    }
  }
}

void RoundedFactor::split_tree() {
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

RoundedFactor::Node RoundedFactor::node(Index s) const {
  Node d;
  d.first_column = m_super[s];
  d.nscol = m_super[s + 1] - d.first_column;
  d.nsrow = m_pi[s + 1] - m_pi[s];
  d.below = d.nsrow - d.nscol;
  d.rows = m_s_rows.data() + m_pi[s];
  d.offset = m_offset[s];
  return d;
}

const float* RoundedFactor::columns(const Node& d, Index j0, Index j1, int thread) const {
  const std::int64_t first = d.offset + packed_column(j0, d.nsrow);
  if (m_storage == FactorStorage::Float) return m_values.data() + first;
  float* out = m_block[thread].data();
  halves_to_floats(m_halves.data() + first, out, packed_column(j1, d.nsrow) - packed_column(j0, d.nsrow));
  return out;
}

void RoundedFactor::forward(Index s, Index end_column, double* y, double* delta, double* w, int thread) const {
  const Node d = node(s);
  const Index nscol = d.nscol, nsrow = d.nsrow, below = d.below;
  double* ys = y + d.first_column;
  const double* pivot = m_pivot.data() + d.first_column;
  // w: the supernode's own unknowns, then (negated) what its columns take from the rows below.
  std::copy(ys, ys + nscol, w);
  std::fill(w + nscol, w + nsrow, 0.0);
  // Columns kColumns at a time: the block's own triangle, then every row after the block
  // (the rest of the diagonal block and the rows below, contiguous in each packed column) in
  // one pass.
  for (Index j0 = 0; j0 < nscol; j0 += kColumns) {
    const Index j1 = std::min(j0 + kColumns, nscol);
    const int width = static_cast<int>(j1 - j0);
    const float* block = columns(d, j0, j1, thread);
    const std::int64_t origin = packed_column(j0, nsrow);
    const float* c[kColumns];
    for (Index j = j0; j < j1; ++j) {
      const float* column = block + (packed_column(j, nsrow) - origin);
      const double wj = w[j] / pivot[j];
      w[j] = wj;
      for (Index k = j + 1; k < j1; ++k) w[k] -= static_cast<double>(column[k - j]) * wj;
      c[j - j0] = column + (j1 - j);
    }
    update(width, c, w + j0, w + j1, nsrow - j1);
  }
  std::copy(w, w + nscol, ys);
  // Rows of this part into y, rows of the top (at or beyond end_column) into delta (added up
  // and subtracted from y once both parts are done).
  const double* t = w + nscol;
  for (Index i = 0; i < below; ++i) {
    const int r = d.rows[nscol + i];
    if (r < end_column)
      y[r] += t[i];
    else
      delta[r] -= t[i];
  }
}

void RoundedFactor::backward(Index s, double* y, double* w, int thread) const {
  const Node d = node(s);
  const Index nscol = d.nscol, nsrow = d.nsrow, below = d.below;
  double* ys = y + d.first_column;
  const double* pivot = m_pivot.data() + d.first_column;
  // w: the supernode's own unknowns, then the rows below gathered once.
  std::copy(ys, ys + nscol, w);
  for (Index i = 0; i < below; ++i) w[nscol + i] = y[d.rows[nscol + i]];
  // Blocks of columns, last first: each column's dot product with every row after the block
  // (four columns in one pass), then the block's own triangle, last column first.
  for (Index j1 = nscol, j0 = 0; j1 > 0; j1 = j0) {
    j0 = (j1 - 1) / kColumns * kColumns;
    const int width = static_cast<int>(j1 - j0);
    const float* block = columns(d, j0, j1, thread);
    const std::int64_t origin = packed_column(j0, nsrow);
    const float* c[kColumns];
    const float* own[kColumns];
    for (Index j = j0; j < j1; ++j) {
      own[j - j0] = block + (packed_column(j, nsrow) - origin);
      c[j - j0] = own[j - j0] + (j1 - j);
    }
    double sum[kColumns] = {0.0, 0.0, 0.0, 0.0};
    dots(width, c, w + j1, nsrow - j1, sum);
    for (Index j = j1 - 1; j >= j0; --j) {
      double wj = w[j] - sum[j - j0];
      for (Index k = j + 1; k < j1; ++k) wj -= static_cast<double>(own[j - j0][k - j]) * w[k];
      w[j] = wj / pivot[j];
    }
  }
  std::copy(w, w + nscol, ys);
}

void RoundedFactor::solve(const VecX& b, VecX& x) {
  const Index n = m_n;
  double* y = m_work.data();
  if (m_scale.empty())
    for (Index k = 0; k < n; ++k) y[k] = b[m_perm[k]];
  else
    for (Index k = 0; k < n; ++k) y[k] = b[m_perm[k]] * m_scale[k];
  const int threads = std::min(2, omp_get_max_threads());

  // Forward: the two parts side by side (their updates of the top kept apart), then the top.
#pragma omp parallel for num_threads(threads) schedule(static, 1)
  for (int p = 0; p < 2; ++p)
    for (const Range& r : m_part[p])
      for (Index s = r.first; s <= r.last; ++s) forward(s, r.end_column, y, m_delta[p].data(), m_scratch[p].data(), p);
  for (Index c : m_top_columns) {
    y[c] -= m_delta[0][c] + m_delta[1][c];
    m_delta[0][c] = m_delta[1][c] = 0.0;
  }
  for (Index s : m_top) forward(s, n, y, m_delta[0].data(), m_scratch[0].data(), 0);

  // Back: the top first, then the parts side by side (they read the top, write their own).
  for (auto it = m_top.rbegin(); it != m_top.rend(); ++it) backward(*it, y, m_scratch[0].data(), 0);
#pragma omp parallel for num_threads(threads) schedule(static, 1)
  for (int p = 0; p < 2; ++p)
    for (auto r = m_part[p].rbegin(); r != m_part[p].rend(); ++r)
      for (Index s = r->last; s >= r->first; --s) backward(s, y, m_scratch[p].data(), p);

  x.resize(n);
  if (m_scale.empty())
    for (Index k = 0; k < n; ++k) x[m_perm[k]] = y[k];
  else
    for (Index k = 0; k < n; ++k) x[m_perm[k]] = y[k] * m_scale[k];
}

}  // namespace fibra
