#pragma once
/// Helpers of the derivative tests: an assembled upper-triangle matrix as a dense symmetric
/// one, and random unit vectors for random states.
#include <Eigen/Core>
#include <random>
#include <vector>

#include "fibra/assembly/block_pattern.hpp"

namespace fibra::test {

/// Dense symmetric matrix from the upper CSC values of a pattern.
inline Eigen::MatrixXd dense(const BlockPattern& p, const std::vector<double>& values) {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(p.rows(), p.rows());
  for (Index c = 0; c < p.rows(); ++c)
    for (int k = p.col_ptr()[c]; k < p.col_ptr()[c + 1]; ++k) {
      m(p.row_idx()[k], c) = values[k];
      m(c, p.row_idx()[k]) = values[k];
    }
  return m;
}

/// A random unit vector (normal components, normalized).
inline Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

}  // namespace fibra::test
