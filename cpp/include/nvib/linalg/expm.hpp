// Matrix exponential by the 2^N algorithm of the precise integration method
// (Zhong & Williams 1994, Proc. IMechE C 208:427):
//   tau = 1/2^N,  Ta = e^{A tau} - I  by its 4th-order Taylor series,
//   N times: Ta <- 2 Ta + Ta^2        (since (I + Ta)^2 = I + 2 Ta + Ta^2),
//   e^{A} = I + Ta.
// Only the increment Ta is squared; adding I early would lose about
// log10(2^N) significant digits to round-off.
#pragma once

#include "../core/types.hpp"

namespace nvib {

// Returns e^{A} - I (the increment), computed with N squarings.
inline Matrix expm_increment(const Matrix& A, int squarings = 20) {
  detail::require(A.rows() == A.cols(), "A: expm needs a square matrix");
  detail::require(squarings >= 0 && squarings <= 60,
                  "squarings: needs 0 <= squarings <= 60, got " + std::to_string(squarings));
  detail::require(A.allFinite(), "A: the matrix has non-finite entries");
  const Index n = A.rows();
  const Matrix At = A / std::ldexp(1.0, squarings);
  const Matrix At2 = At * At;
  // Ta = At + At^2 (I + At/3 + At^2/12) / 2
  Matrix inner = Matrix::Identity(n, n) + At / 3.0 + At2 / 12.0;
  Matrix Ta = At;
  Ta.noalias() += 0.5 * (At2 * inner);
  Matrix tmp(n, n);
  for (int i = 0; i < squarings; ++i) {
    tmp.noalias() = Ta * Ta;
    Ta = 2.0 * Ta + tmp;
  }
  return Ta;
}

inline Matrix expm(const Matrix& A, int squarings = 20) {
  Matrix E = expm_increment(A, squarings);
  E.diagonal().array() += 1.0;
  return E;
}

}  // namespace nvib
