// Contact on a bundle of 480 parallel glass fibers (radius 10 um, length 10 mm, 100 elements
// each) in hexagonal packing, neighbours overlapping by 0.1 % of the radius, so every touching
// pair forms a contact line:
//
//   BM_Detection/threads:T        ContactDetector::detect (broad phase, zones, contact elements)
//   BM_ContactAssembly/threads:T  Problem::evaluate (gradient + Hessian) with the contact
//                                 elements minus the same without them: reported as contact
//                                 elements per second (target >= 1e6 per core)
//   BM_UpdateNormals              ContactManager::update_normals on the same elements (once
//                                 per normal update, before each Newton solve of the loop)
//
// Run with OMP_WAIT_POLICY=passive.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <chrono>
#include <map>
#include <memory>

#include "bench_common.hpp"
#include "fibra/contact/contact_manager.hpp"
#include "fibra/contact/detection.hpp"
#include "fibra/solver/problem.hpp"

namespace {

using namespace fibra;

constexpr int kFibers = 480;
constexpr int kElements = 100;

struct ContactBundle {
  Model model;
  VecX q;
  Detection detection;
  DetectionParams params;
  explicit ContactBundle(double spacing)
      : model(build_model(bench::bundle_case(kFibers, kElements, 1e-5, 0.01, 1.998))), q(model.reference) {
    params.spacing = spacing;
    ContactDetector detector(model, params);
    detector.detect(q, detection);
    for (ContactElement& c : detection.elements) c.law = PenaltyLaw{1e4, 1e-7};
  }
};

/// spacing_um = 0: the default spacing (one radius, 10 um: 10 contact elements per pair of
/// touching beam elements); 50: half an element (2 per pair).
ContactBundle& bundle(int spacing_um = 0) {
  static std::map<int, std::unique_ptr<ContactBundle>> cache;
  auto& b = cache[spacing_um];
  if (!b) b = std::make_unique<ContactBundle>(spacing_um * 1e-6);
  return *b;
}

void BM_Detection(benchmark::State& state) {
  ContactBundle& b = bundle();
  omp_set_num_threads(static_cast<int>(state.range(0)));
  ContactDetector detector(b.model, b.params);
  Detection out;
  detector.detect(b.q, out);  // warm-up: buffers sized
  for (auto _ : state) {
    detector.detect(b.q, out);
    benchmark::DoNotOptimize(out.elements.data());
  }
  state.counters["contact_elements"] = static_cast<double>(out.elements.size());
  state.counters["zones"] = static_cast<double>(out.zones.size());
  state.counters["candidate_pairs"] = static_cast<double>(detector.broad_phase().pairs().size());
}
BENCHMARK(BM_Detection)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ContactAssembly(benchmark::State& state) {
  ContactBundle& b = bundle(static_cast<int>(state.range(1)));
  omp_set_num_threads(static_cast<int>(state.range(0)));
  Problem with(b.model), without(b.model);
  with.set_contacts(b.detection.elements, FrictionParams{0.2, 1e-8});
  VecX grad;
  std::vector<double> hess_with, hess_without;
  with.evaluate(b.q, &grad, &hess_with);
  without.evaluate(b.q, &grad, &hess_without);
  double contact_seconds = 0.0;
  for (auto _ : state) {
    auto t0 = std::chrono::steady_clock::now();
    with.evaluate(b.q, &grad, &hess_with);
    auto t1 = std::chrono::steady_clock::now();
    without.evaluate(b.q, &grad, &hess_without);
    auto t2 = std::chrono::steady_clock::now();
    contact_seconds += std::chrono::duration<double>((t1 - t0) - (t2 - t1)).count();
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
  }
  const double n = static_cast<double>(b.detection.elements.size());
  state.counters["contact_elements"] = n;
  state.counters["contact_elements_per_second"] =
      n * static_cast<double>(state.iterations()) / std::max(contact_seconds, 1e-12);
}
BENCHMARK(BM_ContactAssembly)
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({1, 50})
    ->Args({2, 50})
    ->ArgNames({"threads", "spacing_um"})
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();

void BM_UpdateNormals(benchmark::State& state) {
  ContactBundle& b = bundle();
  ContactSpec spec;
  spec.enabled = true;
  ContactManager manager(b.model, spec);
  std::vector<ContactElement> contacts = b.detection.elements;
  double turn = 0.0;
  for (auto _ : state) {
    turn = manager.update_normals(contacts, b.q);
    benchmark::DoNotOptimize(turn);
  }
  state.counters["contact_elements"] = static_cast<double>(contacts.size());
  state.counters["elements_per_second"] =
      benchmark::Counter(static_cast<double>(contacts.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_UpdateNormals)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
