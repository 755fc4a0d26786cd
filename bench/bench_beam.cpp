// Beam element kernel throughput: evaluations of beam_element_energy per second on one core,
// (a) energy + gradient + Hessian (what the Newton assembly calls), (b) energy + gradient,
// (c) energy only (line search). The elements come from a curved (arc) glass fiber meshed by
// build_model, evaluated at a smoothly bent, stretched and twisted state.
#include <benchmark/benchmark.h>

#include "bench_common.hpp"
#include "fibra/beam/beam_element.hpp"

namespace {

using namespace fibra;

struct BeamSetup {
  Model model;
  VecX q;
  BeamSetup() {
    Case c;
    c.materials.push_back(bench::glass());
    FiberSpec s;
    s.name = "arc";
    s.material = "glass";
    s.radius = 1e-5;
    s.path.kind = PathSpec::Kind::Arc;
    s.path.axis = Vec3::UnitY();
    s.path.radius = 0.01;
    s.path.angle = 1.0;
    s.elements = 16;
    c.fibers.push_back(s);
    model = build_model(c);
    q = bench::deformed_state(model, {.bending = 1e-2, .stretch = 2e-3, .twist = 1e-2});
  }
};

const BeamSetup& setup() {
  static const BeamSetup s;
  return s;
}

template <bool Gradient, bool Hessian>
void BM_BeamElement(benchmark::State& state) {
  const BeamSetup& s = setup();
  const Index n = static_cast<Index>(s.model.elements.size());
  ElemVec g;
  ElemMat h;
  Index k = 0;
  for (auto _ : state) {
    const BeamElement& e = s.model.elements[k];
    double energy = beam_element_energy(e, s.model.sections[e.section], s.q.data() + e.first_dof,
                                        Gradient ? &g : nullptr, Hessian ? &h : nullptr);
    benchmark::DoNotOptimize(energy);
    benchmark::DoNotOptimize(g.data());
    benchmark::DoNotOptimize(h.data());
    benchmark::ClobberMemory();
    if (++k == n) k = 0;
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel("elements/s on 1 core");
}

void BM_BeamEnergyGradHess(benchmark::State& state) { BM_BeamElement<true, true>(state); }
void BM_BeamEnergyGrad(benchmark::State& state) { BM_BeamElement<true, false>(state); }
void BM_BeamEnergy(benchmark::State& state) { BM_BeamElement<false, false>(state); }

}  // namespace

BENCHMARK(BM_BeamEnergyGradHess);
BENCHMARK(BM_BeamEnergyGrad);
BENCHMARK(BM_BeamEnergy);
