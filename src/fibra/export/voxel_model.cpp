#include "fibra/export/voxel_model.hpp"

#include <algorithm>
#include <limits>
#include <unordered_map>

#include "fibra/export/fiber_locator.hpp"
#include "fibra/export/mesh_voxelizer.hpp"

namespace fibra {

namespace {

/// The tows whose envelopes hold each voxel's centre: the first in `tow`, the voxels held by
/// several in `shared` (with all their tows).
struct EnvelopeClaims {
  std::vector<int> tow;
  std::unordered_map<Index, std::vector<int>> shared;
};

EnvelopeClaims envelope_claims(const std::vector<TowEnvelope>& envelopes, const VoxelGrid& grid) {
  EnvelopeClaims claims;
  claims.tow.assign(grid.size(), -1);
  for (const TowEnvelope& env : envelopes)
    for_each_voxel_inside(env.surface, grid, [&](Index v) {
      int& owner = claims.tow[v];
      if (owner < 0) {
        owner = env.tow;
        return;
      }
      std::vector<int>& all = claims.shared[v];
      if (all.empty()) all.push_back(owner);
      all.push_back(env.tow);
    });
  return claims;
}

/// What the k^3 points of one voxel found: per tow (and one slot for fibers in no tow) the
/// points in its fibers and the sum of their oriented tangents.
struct VoxelSamples {
  std::vector<int> count;
  std::vector<Vec3> tangent_sum;
  int hits = 0;  ///< points in any fiber
  void reset(size_t slots) {
    count.assign(slots, 0);
    tangent_sum.assign(slots, Vec3::Zero());
    hits = 0;
  }
};

void sample_voxel(const FiberLocator& locator, const TowFibers& tows, const VoxelGrid& grid, Index i, Index j, Index k,
                  int n, std::vector<Index>& candidates, VoxelSamples& out) {
  const Eigen::AlignedBox3d box = grid.voxel_box(i, j, k);
  locator.candidates(box, candidates);
  const int no_tow = static_cast<int>(tows.fibers.size());
  out.reset(tows.fibers.size() + 1);
  if (candidates.empty()) return;
  for (int c = 0; c < n; ++c)
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) {
        const Vec3 fraction((a + 0.5) / n, (b + 0.5) / n, (c + 0.5) / n);
        const Vec3 p = box.min() + grid.spacing.cwiseProduct(fraction);
        const std::optional<FiberHit> hit = locator.find(p, candidates);
        if (!hit) continue;
        const int tow = tows.tow_of_fiber[hit->fiber];
        const int slot = tow >= 0 ? tow : no_tow;
        ++out.count[slot];
        out.tangent_sum[slot] += tows.sign[hit->fiber] * hit->tangent;
        ++out.hits;
      }
}

/// Among the tows whose envelopes hold the voxel, the one with the most points in its fibers.
int resolve_shared(const std::vector<int>& claimants, const VoxelSamples& s) {
  int best = claimants.front();
  for (int t : claimants)
    if (s.count[t] > s.count[best] || (s.count[t] == s.count[best] && t < best)) best = t;
  return best;
}

/// The direction of the station of `env` nearest to p.
Vec3 nearest_station_direction(const TowEnvelope& env, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  Vec3 direction = Vec3::Zero();
  for (const TowStation& st : env.stations) {
    const double d = (st.center - p).squaredNorm();
    if (d < best) best = d, direction = st.direction;
  }
  return direction;
}

Vec3 voxel_direction(int tow, const VoxelSamples& s, const TowEnvelope* env, const Vec3& centre) {
  Vec3 sum = Vec3::Zero();
  if (tow >= 0 && s.count[tow] > 0)
    sum = s.tangent_sum[tow];
  else if (s.hits > 0)
    for (const Vec3& t : s.tangent_sum) sum += t;
  else if (env)
    sum = nearest_station_direction(*env, centre);
  const double norm = sum.norm();
  return norm > 0 ? Vec3(sum / norm) : Vec3::Zero();
}

}  // namespace

VoxelModel voxel_model(const Model& model, const VecX& q, const TowFibers& tows,
                       const std::vector<TowEnvelope>& envelopes, const VoxelGrid& grid, int k) {
  VoxelModel vm;
  vm.grid = grid;
  EnvelopeClaims claims = envelope_claims(envelopes, grid);
  vm.tow = std::move(claims.tow);
  vm.direction.assign(grid.size(), Vec3::Zero());
  vm.fraction.assign(grid.size(), 0.0);
  std::vector<const TowEnvelope*> envelope_of(tows.fibers.size(), nullptr);
  for (const TowEnvelope& env : envelopes) envelope_of[env.tow] = &env;
  const FiberLocator locator(model, q);
  const double points = static_cast<double>(k) * k * k;
  const Index rows = grid.count[1] * grid.count[2];
#pragma omp parallel
  {
    std::vector<Index> candidates;
    VoxelSamples samples;
#pragma omp for schedule(dynamic, 1)
    for (Index row = 0; row < rows; ++row) {
      const Index j = row % grid.count[1], kz = row / grid.count[1];
      for (Index i = 0; i < grid.count[0]; ++i) {
        const Index v = grid.index(i, j, kz);
        sample_voxel(locator, tows, grid, i, j, kz, k, candidates, samples);
        if (const auto shared = claims.shared.find(v); shared != claims.shared.end())
          vm.tow[v] = resolve_shared(shared->second, samples);
        vm.fraction[v] = samples.hits / points;
        const TowEnvelope* env = vm.tow[v] >= 0 ? envelope_of[vm.tow[v]] : nullptr;
        vm.direction[v] = voxel_direction(vm.tow[v], samples, env, grid.center(i, j, kz));
      }
    }
  }
  return vm;
}

}  // namespace fibra
