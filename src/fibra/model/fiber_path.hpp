#pragma once
/// Reference geometry of a fiber: nodes placed at equal arc length along its path, with
/// section vectors transported along it without twist.
#include <vector>

#include "fibra/model/case.hpp"

namespace fibra {

/// A sampled reference frame: position, unit tangent, unit section vectors g1, g2.
struct PathFrame {
  Vec3 position;
  Vec3 tangent;
  Vec3 g1;
  Vec3 g2;
};

/// Total arc length of a path [m].
double path_length(const PathSpec& path);

/// Position and unit tangent at arc length s along the path.
void path_point(const PathSpec& path, double s, Vec3& position, Vec3& tangent);

/// `count` frames at equal arc-length spacing from start to end; g1 starts along
/// `section_direction` (projected on the normal plane; a default if absent) and is carried by
/// rotation-minimizing (parallel) transport; g2 = t x g1.
std::vector<PathFrame> sample_path(const PathSpec& path, int count, const std::optional<Vec3>& section_direction);

}  // namespace fibra
