#pragma once
/// Projection of a term's local Hessian onto the positive semi-definite matrices, for projected
/// Newton (docs/theory/solver.md, "Indefinite tangents").
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace fibra {

/// Replaces a symmetric matrix (the expression `hessian`, written through) that is indefinite
/// by its projection onto the positive semi-definite ones: its negative eigenvalues set to zero,
/// its eigenvectors kept. True when it did. A matrix whose negative eigenvalues are within
/// round-off (1e-10) of its largest diagonal entry is left as it is: a beam element's Hessian
/// is singular along its six rigid motions, and those are no indefiniteness. The usual case,
/// a positive (semi-)definite matrix, costs one Cholesky factorization.
template <class Derived>
bool project_psd(const Eigen::MatrixBase<Derived>& hessian) {
  using Plain = typename Derived::PlainObject;
  auto& h = const_cast<Eigen::MatrixBase<Derived>&>(hessian);
  if (h.size() == 0) return false;
  const double scale = h.diagonal().cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return false;
  const double roundoff = 1e-10 * scale;
  Plain shifted = h;
  shifted.diagonal().array() += roundoff;
  if (Eigen::LLT<Plain>(shifted).info() == Eigen::Success) return false;
  const Eigen::SelfAdjointEigenSolver<Plain> eig(h.eval());
  if (eig.info() != Eigen::Success) return false;
  if (eig.eigenvalues().minCoeff() >= -roundoff) return false;
  h = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  return true;
}

}  // namespace fibra
