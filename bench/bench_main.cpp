// The benchmarks' main: the heap set up as `fibra` sets it (large freed blocks kept, fibra/core/heap.hpp),
// so factorizations and assemblies are measured as the program runs them. Without it, every large
// block freed goes back to the system and its pages are zeroed again at the next request; on the
// reference virtual machine that has made the factorization benchmarks 3-5 times slower than their
// baseline (docs/performance.md, "Memory: freed blocks kept").
#include <benchmark/benchmark.h>

#include "fibra/core/heap.hpp"

int main(int argc, char** argv) {
  fibra::keep_freed_memory();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
