#pragma once
/// The rotation exponential R(phi) = exp([phi]x) with its exact first and second derivatives
/// with respect to the rotation vector phi (Rodrigues' formula differentiated; series near 0
/// so the derivatives are smooth through phi = 0). Used for the incremental rotation of rigid
/// bodies: a body's frame is D = R(theta) D_ref, theta reset to 0 after each increment, so
/// |theta| stays small and the map is never near its singularity at |theta| = 2 pi.
#include "fibra/core/types.hpp"

namespace fibra {

/// [v]x: the matrix of the cross product v x .
inline Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

/// vee(M - M^T) = (M32 - M23, M13 - M31, M21 - M12): twice the axial vector of M's skew part.
inline Vec3 vee_antisymmetric(const Mat3& m) {
  return {m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)};
}

/// R(phi) and, when the pointers are given, dR[j] = dR/dphi_j (3 matrices) and
/// d2R[3 j + k] = d2R/dphi_j dphi_k (9 matrices, symmetric in j, k).
Mat3 rotation_exp(const Vec3& phi, Mat3* dR = nullptr, Mat3* d2R = nullptr);

/// The rotation vector of a rotation matrix (angle in [0, pi]).
Vec3 rotation_log(const Mat3& r);

/// T(phi) with dR/dphi_j (R^T) = [T e_j]x: the spatial angular velocity is T(phi) dphi/dt.
/// A moment m does the work m . T dphi, so the generalized force conjugate to phi is T^T m.
Mat3 rotation_tangent(const Vec3& phi);

}  // namespace fibra
