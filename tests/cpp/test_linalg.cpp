// Linear algebra of the schemes.
// DenseLU (the implicit schemes' factorisation) against Eigen's PartialPivLU:
// solutions of random systems on both sides of the unblocked/blocked switch,
// pivoting on a zero diagonal, and singular or non-finite matrices refused.
// BandedLDLT: random symmetric band matrices of every half-width against a dense
// solve, and pivots it cannot take without an exchange (zero, non-finite) refused.
// expm_increment_with_moments (PIM's propagators) against the 2^N exponential
// of the whole block matrix it avoids forming.
#include <nvib/linalg/banded_ldlt.hpp>
#include <nvib/linalg/dense_lu.hpp>
#include <nvib/linalg/expm.hpp>

#include <random>

#include "check.hpp"

using nvib::Index;
using nvib::Matrix;
using nvib::Vector;

int main() {
  std::mt19937 gen(12345);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto random_matrix = [&](Index n) {
    Matrix A(n, n);
    for (Index j = 0; j < n; ++j)
      for (Index i = 0; i < n; ++i) A(i, j) = normal(gen);
    return A;
  };
  for (Index n : {1, 2, 3, 6, 12, 31, 64, 65, 70}) {
    const Matrix A = random_matrix(n);
    Vector b(n);
    for (Index i = 0; i < n; ++i) b[i] = normal(gen);
    nvib::DenseLU lu(n);
    CHECK(lu.compute(A) && lu.ok());
    Vector x = b;
    lu.solve_in_place(x);
    const Vector ref = A.partialPivLu().solve(b);
    CHECK((x - ref).cwiseAbs().maxCoeff() <= 1e-10 * std::max(1.0, ref.cwiseAbs().maxCoeff()));
    CHECK((A * x - b).cwiseAbs().maxCoeff() <= 1e-10 * std::max(1.0, b.cwiseAbs().maxCoeff()));
    // the same object factorises another matrix of its size
    const Matrix B = random_matrix(n) + 10.0 * Matrix::Identity(n, n);
    CHECK(lu.compute(B));
    x = b;
    lu.solve_in_place(x);
    CHECK((B * x - b).cwiseAbs().maxCoeff() <= 1e-10 * std::max(1.0, b.cwiseAbs().maxCoeff()));
  }
  {  // a zero on the diagonal needs a row exchange
    Matrix A(3, 3);
    A << 0, 2, 1, 1, 1, 0, 3, 0, 1;
    Vector b(3), x(3);
    b << 3, 2, 4;
    nvib::DenseLU lu(3);
    CHECK(lu.compute(A));
    x = b;
    lu.solve_in_place(x);
    CHECK((A * x - b).cwiseAbs().maxCoeff() <= 1e-14);
  }
  {  // singular to working precision, exactly singular, and non-finite: refused
    Matrix A(3, 3);
    A << 1, 2, 3, 4, 5, 6, 7, 8, 9;  // rank 2
    nvib::DenseLU lu(3);
    CHECK(!lu.compute(A) && !lu.ok());
    CHECK(!lu.compute(Matrix::Zero(3, 3)));
    Matrix B = Matrix::Identity(3, 3);
    B(1, 2) = std::numeric_limits<double>::infinity();
    CHECK(!lu.compute(B));
    B(1, 2) = std::numeric_limits<double>::quiet_NaN();
    CHECK(!lu.compute(B));
    for (Index n : {65, 70}) {  // the blocked path too
      nvib::DenseLU big(n);
      Matrix S = random_matrix(n);
      S.col(3) = S.col(1);
      CHECK(!big.compute(S));
    }
  }
  // BandedLDLT: symmetric band matrices, diagonally dominant (as c_M M + c_K K) or merely positive definite
  auto band = [&](Index n, Index b, double dominance) {
    Matrix A = Matrix::Zero(n, n);
    for (Index i = 0; i < n; ++i)
      for (Index j = std::max<Index>(0, i - b); j < i; ++j) A(i, j) = A(j, i) = normal(gen);
    for (Index i = 0; i < n; ++i) A(i, i) = dominance * (1.0 + std::abs(normal(gen))) + A.row(i).cwiseAbs().sum();
    return A;
  };
  auto factorise = [](nvib::BandedLDLT& ldlt, const Matrix& A) {
    const nvib::SparseMatrix S = A.sparseView(1.0, 0.0);
    ldlt.analyze(S);
    std::vector<double> values(static_cast<size_t>(ldlt.size()) + 1, 0.0);  // + 1: where the upper triangle goes
    const std::vector<int> to = ldlt.layout(S);
    for (Index k = 0; k < S.nonZeros(); ++k) values[to[k] >= 0 ? to[k] : ldlt.size()] += S.valuePtr()[k];
    return ldlt.factorize(values.data());
  };
  for (Index n : {1, 2, 3, 7, 40}) {
    for (Index b : {0, 1, 2, 3, 4, 7}) {
      if (b >= n && b > 0) continue;
      for (double dominance : {1e3, 0.01}) {
        const Matrix A = band(n, b, dominance);
        nvib::BandedLDLT ldlt;
        CHECK(factorise(ldlt, A));
        CHECK(ldlt.half_bandwidth() == b || (b == 0 && ldlt.half_bandwidth() == 0));
        Vector rhs(n), x(n);
        for (Index i = 0; i < n; ++i) rhs[i] = normal(gen);
        x = rhs;
        ldlt.solve_in_place(x.data());
        CHECK((A * x - rhs).cwiseAbs().maxCoeff() <= 1e-12 * A.cwiseAbs().maxCoeff() * std::max(1.0, x.cwiseAbs().maxCoeff()));
      }
    }
  }
  {  // pivots without an exchange: a zero one (A(0, 0) = 0 of a regular matrix), a non-finite one, a tiny one
    Matrix A(2, 2);
    A << 0, 1, 1, 2;
    nvib::BandedLDLT ldlt;
    CHECK(!factorise(ldlt, A));
    A << 1, 1, 1, std::numeric_limits<double>::infinity();
    CHECK(!factorise(ldlt, A));
    A << 1, 1, 1, 1 + 1e-15;  // the second pivot 1e-15 of the first (the dense LU's 1e-14 test)
    CHECK(!factorise(ldlt, A));
    for (Index b : {1, 5}) {  // NaN in the general path too
      Matrix B = band(8, b, 10.0);
      B(3, 3) = std::numeric_limits<double>::quiet_NaN();
      CHECK(!factorise(ldlt, B));
    }
  }
  // PIM's moments: the structured first block row equals the full block exponential
  for (int q : {1, 2, 3, 4}) {
    const Index n = 3, N = 2 * n;
    Matrix H = Matrix::Zero(N, N);  // a damped chain's state matrix
    H.topRightCorner(n, n).setIdentity();
    Matrix K(n, n);
    K << 2, -1, 0, -1, 2, -1, 0, -1, 1;
    H.bottomLeftCorner(n, n) = -400.0 * K;
    H.bottomRightCorner(n, n) = -0.3 * K;
    for (double h : {1e-3, 0.02, 0.1}) {
      const Index B = q + 1;
      Matrix Z = Matrix::Zero(B * N, B * N);
      Z.topLeftCorner(N, N) = h * H;
      for (Index k = 0; k + 1 < B; ++k) Z.block(k * N, (k + 1) * N, N, N) = h * Matrix::Identity(N, N);
      const Matrix E = nvib::expm_increment(Z, 20);
      std::vector<Matrix> F;
      const Matrix Ta = nvib::expm_increment_with_moments(h * H, h, q, F, 20);
      CHECK(static_cast<int>(F.size()) == q);
      CHECK((Ta - E.topLeftCorner(N, N)).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, Ta.cwiseAbs().maxCoeff()));
      for (int j = 1; j <= q; ++j) {
        const Matrix Ej = E.block(0, j * N, N, N);
        const double scale = Ej.cwiseAbs().maxCoeff();
        CHECK((F[static_cast<size_t>(j) - 1] - Ej).cwiseAbs().maxCoeff() <= 1e-12 * scale);
      }
    }
  }
  return nvib_test::finish("test_linalg");
}
