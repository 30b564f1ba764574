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

}  // namespace nvib
