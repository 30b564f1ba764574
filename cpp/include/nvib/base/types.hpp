// The vocabulary of every part of nvib: vectors and matrices, with the
// counters, errors and loops that every part uses.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "errors.hpp"
#include "loops.hpp"
#include "stats.hpp"

namespace nvib {

using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;
// Saved histories are (n_saved, n_dofs) and C-contiguous, so NumPy takes them without a copy.
using History = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using VecRef = Eigen::Ref<Vector>;
using CVecRef = Eigen::Ref<const Vector>;
using MatRef = Eigen::Ref<Matrix>;
using Index = Eigen::Index;
// Compressed columns, 32-bit indices (a model of up to 2^31 stored entries).
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// One stored entry (row, column) of a sparse tangent.
struct Entry {
  int row, col;
};

// Where the tangent's entries go as they are evaluated (tangent_add()): the values in the list of
// tangent_entries() (K, C, advanced past the group's entries), and each also added into the iteration
// matrix's storage at its position (tk[pk[e]], tc[pc[e]], pk and pc advanced alike).
struct TangentOut {
  double* K;
  double* C;
  const int* pk;
  const int* pc;
  double* tk;
  double* tc;
};
// s[pos[k]] += x[k] for k = 0 .. m - 1, in order; returns the sum of x[k] - x[k] (0 unless some x[k] is
// not finite).
inline double scatter_add(const int* __restrict pos, const double* __restrict x, std::size_t m, double* __restrict s) {
  double nonfinite = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    s[pos[k]] += x[k];
    nonfinite += x[k] - x[k];
  }
  return nonfinite;
}
// The next nk values of out.K and nc of out.C added at their positions, out advanced past them; the sum
// of x - x over them.
inline double add_listed(TangentOut& o, std::size_t nk, std::size_t nc) {
  const double nonfinite = scatter_add(o.pk, o.K, nk, o.tk) + scatter_add(o.pc, o.C, nc, o.tc);
  o.K += nk, o.pk += nk;
  o.C += nc, o.pc += nc;
  return nonfinite;
}

}  // namespace nvib
