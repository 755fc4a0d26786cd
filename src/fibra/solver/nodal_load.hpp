#pragma once
/// Nodal loads: dead forces on x0, and moments applied as couples on the section vectors.
///
/// A moment M = |M| n is conservative about its fixed axis n: its potential is
/// -|M| sum_a w_a theta_a, theta_a the angle of the projection of g_a on the plane normal to
/// n, with weights w_a = |P G_a|^2 / sum_b |P G_b|^2 from the reference section vectors.
/// For g_a normal to n, g1 x f1 + g2 x f2 = M exactly. See docs/theory/beam.md.
#include <Eigen/Core>

#include "fibra/core/types.hpp"

namespace fibra {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6x6 = Eigen::Matrix<double, 6, 6>;

/// Generalized force (f_g1, f_g2) of moment `moment` at section vectors (g1, g2) with
/// reference (rg1, rg2), and its derivative d f / d(g1, g2) (symmetric) if `dforce` is set.
Vec6 moment_generalized_force(const Vec3& moment, const Vec3& rg1, const Vec3& rg2, const Vec3& g1,
                              const Vec3& g2, Mat6x6* dforce);

/// Work of moment `moment` when the section vectors turn from (h1, h2) to (g1, g2): the
/// weighted angles swept about the moment axis (valid for turns below pi). [J]
double moment_work(const Vec3& moment, const Vec3& rg1, const Vec3& rg2, const Vec3& h1, const Vec3& h2,
                   const Vec3& g1, const Vec3& g2);

}  // namespace fibra
