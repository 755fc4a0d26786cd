#pragma once
/// The size of a model estimated from its element counts before anything is built, and the
/// limits a case is held to. Counts are reals, so that one computed from a length (a fabric's
/// element length of a picometre) or written as a huge integer is compared, not overflowed.
/// Every estimate counts the fibers' own elements and the bodies only: contact adds matrix
/// entries and memory, so the estimates are lower bounds (docs/case-file.md, "Model size").
#include <string>

namespace fibra {

/// The counts of a model, or of a part of one.
struct ModelSize {
  double fibers = 0;    ///< fibers
  double elements = 0;  ///< quadratic beam elements, over all fibers
  double bodies = 0;    ///< rigid bodies

  double nodes() const { return fibers + 2 * elements; }  ///< 2 * elements + 1 per fiber
  double dofs() const { return 9 * nodes() + 6 * bodies; }  ///< 9 per node, 6 per body
  /// Entries of the stored (upper) triangle of the stiffness matrix that the elements make:
  /// 45 per node (its 9 x 9 diagonal block), 3 x 81 per element (its three node pairs) and 21
  /// per body (its 6 x 6 diagonal block).
  double matrix_entries() const { return 45 * nodes() + 243 * elements + 21 * bodies; }
  /// The least memory a run of the model takes [bytes]: per matrix entry its value and row
  /// index, and at least one value of the Cholesky factor in double and its single-precision
  /// copy (24 bytes); each element's data; ten vectors of the dofs' size (state, reference,
  /// increment start, gradient, right-hand side, scales, ...).
  double bytes() const;

  ModelSize& operator+=(const ModelSize& other);  ///< the sum of two parts
};

/// One fiber of `elements` elements.
ModelSize fiber_size(double elements);

/// What a model may not exceed.
struct SizeLimits {
  /// The sparse matrix and its factor are addressed by 32-bit integers (the block pattern's
  /// column starts, CHOLMOD's int version): at most 2^31 - 1 entries.
  double matrix_entries = 2147483647.0;
  double memory = 0;  ///< the memory a run may take: the machine's [bytes]
};

/// The limits on this machine: memory is its physical memory, or the memory limit of the
/// control group the process runs in when that is lower.
SizeLimits machine_size_limits();

/// Empty when `size` is within `limits`; otherwise the estimates and the limits they exceed,
/// e.g. "estimated 2e+09 elements, 4e+09 nodes, 3.6e+10 dofs, 6.66e+11 stiffness matrix entries
/// and at least 17.8 TiB of memory; the sparse solver holds at most 2147483647 matrix entries
/// (32-bit indices); this machine has 23.5 GiB of memory".
std::string size_excess(const ModelSize& size, const SizeLimits& limits);

/// A byte count for people, in powers of 1024: "512 B", "3.2 MiB", "16 GiB", "2.1 TiB".
std::string format_bytes(double bytes);

}  // namespace fibra
