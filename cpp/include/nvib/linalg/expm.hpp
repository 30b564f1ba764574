// Matrix exponential by the 2^N algorithm of the precise integration method
// (Zhong & Williams 1994, Proc. IMechE C 208:427):
//   tau = 1/2^N,  Ta = e^{A tau} - I  by its 4th-order Taylor series,
//   N times: Ta <- 2 Ta + Ta^2        (since (I + Ta)^2 = I + 2 Ta + Ta^2),
//   e^{A} = I + Ta.
// Only the increment Ta is squared; adding I early would lose about
// log10(2^N) significant digits to round-off.
#pragma once

#include "../base/interrupt.hpp"
#include "../base/types.hpp"

namespace nvib {

// Returns e^{A} - I (the increment), computed with N squarings.
inline Matrix expm_increment(const Matrix& A, int squarings = 20) {
  NVIB_CHECK(A.rows() == A.cols(), "A", "expm needs a square matrix");
  NVIB_CHECK(squarings >= 0 && squarings <= 60, "squarings",
                  "needs 0 <= squarings <= 60, got " + std::to_string(squarings));
  NVIB_CHECK(A.allFinite(), "A", "the matrix has non-finite entries");
  const Index n = A.rows();
  const Matrix At = A / std::ldexp(1.0, squarings);
  const Matrix At2 = At * At;
  // Ta = At + At^2 (I + At/3 + At^2/12) / 2
  Matrix inner = Matrix::Identity(n, n) + At / 3.0 + At2 / 12.0;
  Matrix Ta = At;
  Ta.noalias() += 0.5 * (At2 * inner);
  Matrix tmp(n, n);
  for (int i = 0; i < squarings; ++i) {
    poll_interrupt();  // O(n^3) each: large models take seconds
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

namespace nvib {

// e^{A} - I and the first block row of the exponential of Van Loan's block
// matrix Z = [[A, hI, 0, ..], [0, 0, hI, ..], .., [0, .., 0]] (q + 1 blocks):
//   e^{Z} = [[e^{A}, F_1, F_2, .., F_q], [0, I, hI, h^2/2 I, ..], ..],
//   F_j = h^j sum_k A^k / (k + j)!     (= h^j phi_j(A); with A = hH these are
//   the moment integrals int_0^h e^{H(h-s)} s^{j-1} ds / (j-1)!).
// The same 2^N algorithm as expm_increment, squaring only the first block
// row: the rows below it are the shift's exponential, (h s)^{j-i}/(j-i)! I
// at scale s. One doubling is q + 1 products of A's size instead of one of
// (q + 1) times its size, ~ (q + 1)^2 / 1 times fewer operations.
// F is resized to q matrices (F[j - 1] = F_j).
inline Matrix expm_increment_with_moments(const Matrix& A, double h, int q, std::vector<Matrix>& F,
                                          int squarings = 20) {
  NVIB_CHECK(A.rows() == A.cols(), "A", "expm needs a square matrix");
  NVIB_CHECK(squarings >= 0 && squarings <= 60, "squarings",
                  "needs 0 <= squarings <= 60, got " + std::to_string(squarings));
  NVIB_CHECK(q >= 0 && q <= 8, "q", "needs 0 <= q <= 8 moments, got " + std::to_string(q));
  NVIB_CHECK(A.allFinite() && std::isfinite(h), "A, h", "non-finite entries");
  const Index n = A.rows();
  const double s = std::ldexp(1.0, -squarings);
  const Matrix As = A * s;
  const double hs = h * s;
  // Taylor terms (As)^k / k! for k = 0..K: the increment uses k = 1..4, F_j uses 1/(k+j)!
  constexpr int K = 5;
  std::vector<Matrix> P(K + 1);
  P[0] = Matrix::Identity(n, n);
  for (int k = 1; k <= K; ++k) P[static_cast<size_t>(k)].noalias() = P[static_cast<size_t>(k) - 1] * As;
  auto fact = [](int m) {
    double f = 1.0;
    for (int i = 2; i <= m; ++i) f *= i;
    return f;
  };
  Matrix Ta = Matrix::Zero(n, n);
  for (int k = 1; k <= 4; ++k) Ta += P[static_cast<size_t>(k)] / fact(k);
  F.assign(static_cast<size_t>(q), Matrix::Zero(n, n));
  for (int j = 1; j <= q; ++j) {
    Matrix& Fj = F[static_cast<size_t>(j) - 1];
    for (int k = 0; k <= K; ++k) Fj += P[static_cast<size_t>(k)] / fact(k + j);
    Fj *= std::pow(hs, j);
  }
  std::vector<Matrix> G(static_cast<size_t>(q), Matrix(n, n));
  Matrix tmp(n, n);
  double sigma = hs;  // h times the current scale
  for (int it = 0; it < squarings; ++it) {
    poll_interrupt();
    // F_j <- 2 F_j + Ta F_j + sum_{i<j} F_i sigma^{j-i}/(j-i)!   (old values on the right)
    for (int j = 1; j <= q; ++j) {
      Matrix& g = G[static_cast<size_t>(j) - 1];
      const Matrix& Fj = F[static_cast<size_t>(j) - 1];
      g.noalias() = Ta * Fj;
      poll_interrupt();  // after each O(n^3) product
      g += 2.0 * Fj;
      for (int i = 1; i < j; ++i) g += (std::pow(sigma, j - i) / fact(j - i)) * F[static_cast<size_t>(i) - 1];
    }
    F.swap(G);
    tmp.noalias() = Ta * Ta;
    Ta = 2.0 * Ta + tmp;
    sigma *= 2.0;
  }
  return Ta;
}

}  // namespace nvib
