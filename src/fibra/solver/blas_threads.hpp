#pragma once
// OpenBLAS's thread count, reached at run time (CHOLMOD calls OpenBLAS through libblas.so.3,
// which on Debian is the OpenBLAS pthread build when it is installed; fibra has no link
// dependency on OpenBLAS itself). Without OpenBLAS every function here does nothing.
#include <string>

namespace fibra {

/// True if the process's BLAS is OpenBLAS (its thread count can be set).
bool blas_threads_available();

/// OpenBLAS's current thread count (0 without OpenBLAS).
int blas_threads();

/// OpenBLAS build configuration and kernel set ("" without OpenBLAS).
std::string blas_info();

/// Sets the OpenBLAS thread count for a scope and restores the previous one after.
class ScopedBlasThreads {
 public:
  explicit ScopedBlasThreads(int threads);
  ~ScopedBlasThreads();
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

 private:
  int m_previous = 0;  // 0: nothing to restore
};

/// Whether the sparse factorizations and solves of factors of at least `min_flops` flops (per
/// factorization) raise the BLAS thread count to the OpenMP thread count (see CholmodSolver).
/// `fibra` turns it on when it chose the single-threaded BLAS itself (the user did not set
/// OPENBLAS_NUM_THREADS); off by default, so a library user's or a test's own setting is left
/// alone.
void set_adaptive_blas_threads(bool on, double min_flops = 5e10);
/// The smallest factor (flops per factorization) that gets threaded BLAS; infinity when off.
double adaptive_blas_min_flops();

}  // namespace fibra
