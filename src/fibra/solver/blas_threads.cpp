#include "fibra/solver/blas_threads.hpp"

#include <dlfcn.h>

#include <atomic>
#include <limits>

namespace fibra {
namespace {

using SetThreads = void (*)(int);
using GetThreads = int (*)();
using GetString = char* (*)();

struct OpenBlas {
  SetThreads set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  GetThreads get = reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  GetString config = reinterpret_cast<GetString>(dlsym(RTLD_DEFAULT, "openblas_get_config"));
  GetString core = reinterpret_cast<GetString>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
};

const OpenBlas& openblas() {
  static const OpenBlas o;
  return o;
}

std::atomic<double> g_min_flops{std::numeric_limits<double>::infinity()};

}  // namespace

bool blas_threads_available() { return openblas().set && openblas().get; }

int blas_threads() { return blas_threads_available() ? openblas().get() : 0; }

std::string blas_info() {
  const OpenBlas& o = openblas();
  if (!o.config || !o.core) return "";
  return std::string(o.config()) + " core=" + o.core();
}

ScopedBlasThreads::ScopedBlasThreads(int threads) {
  if (!blas_threads_available() || threads < 1) return;
  const int previous = openblas().get();
  if (previous == threads) return;
  m_previous = previous;
  openblas().set(threads);
}

ScopedBlasThreads::~ScopedBlasThreads() {
  if (m_previous > 0) openblas().set(m_previous);
}

void set_adaptive_blas_threads(bool on, double min_flops) {
  g_min_flops.store(on ? min_flops : std::numeric_limits<double>::infinity());
}
double adaptive_blas_min_flops() { return g_min_flops.load(); }

}  // namespace fibra
