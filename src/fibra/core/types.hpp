#pragma once
/// Basic numeric types shared by all of fibra.
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products everywhere
#include <cstdint>

namespace fibra {

using Index = std::int64_t;  ///< global dof / node / element index
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using VecX = Eigen::VectorXd;

/// Dofs per node: centroid x0 (3), section vectors g1 (3), g2 (3).
inline constexpr int kNodeDofs = 9;
/// Nodes per beam element (quadratic element).
inline constexpr int kElementNodes = 3;
/// Dofs per beam element (contiguous in the global vector).
inline constexpr int kElementDofs = kNodeDofs * kElementNodes;

}  // namespace fibra
