// DenseLU (the implicit schemes' factorisation) against Eigen's PartialPivLU:
// solutions of random systems on both sides of the unblocked/blocked switch,
// pivoting on a zero diagonal, and singular or non-finite matrices refused.
#include <nvib/linalg/dense_lu.hpp>

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
  return nvib_test::finish("test_dense_lu");
}
