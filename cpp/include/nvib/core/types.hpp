// Basic types shared by every part of nvib: vectors, counters, status, errors.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "format.hpp"

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

// Counters summed over a whole solve (never reset per step).
struct Stats {
  std::int64_t num_steps = 0;
  std::int64_t num_force_evals = 0;     // evaluations of F(u, v, t) asked for by the scheme
  std::int64_t num_fd_force_evals = 0;  // extra evaluations spent on finite-difference tangents
  std::int64_t num_tangent_evals = 0;   // tangent (K_t, C_t) evaluations, analytic or finite-difference
  std::int64_t num_newton_iters = 0;
  std::int64_t num_factorizations = 0;
  std::int64_t num_linear_solves = 0;
  std::int64_t num_expm = 0;
  double wall_time = 0.0;  // seconds
  const char* linear_solver = "";  // of the implicit schemes' Newton iteration: "dense LU", "sparse LDLT", ...

  Stats& operator+=(const Stats& o) { return combine(o, 1); }
  Stats& operator-=(const Stats& o) { return combine(o, -1); }

 private:
  Stats& combine(const Stats& o, int sign) {
    num_steps += sign * o.num_steps;
    num_force_evals += sign * o.num_force_evals;
    num_fd_force_evals += sign * o.num_fd_force_evals;
    num_tangent_evals += sign * o.num_tangent_evals;
    num_newton_iters += sign * o.num_newton_iters;
    num_factorizations += sign * o.num_factorizations;
    num_linear_solves += sign * o.num_linear_solves;
    num_expm += sign * o.num_expm;
    wall_time += sign * o.wall_time;
    if (sign > 0 && *o.linear_solver) linear_solver = o.linear_solver;
    return *this;
  }
};

// interrupted: an exception (an interrupt, an error raised by the force or the observer) stopped the
// run; it reaches the caller as itself, or as a PartialRun carrying the history (SolveOptions::keep_partial).
enum class Status { success, diverged, newton_failed, singular_matrix, interrupted };

inline const char* to_string(Status s) {
  switch (s) {
    case Status::success: return "success";
    case Status::diverged: return "diverged";
    case Status::newton_failed: return "newton_failed";
    case Status::singular_matrix: return "singular_matrix";
    case Status::interrupted: return "interrupted";
  }
  return "unknown";
}

// Where and why a run stopped early.
struct Failure {
  Status status = Status::success;
  std::int64_t step = 0;  // index of the step that failed (1 = the first step)
  double t = 0.0;         // time the failed step was heading for
  Index dof = -1;         // offending DOF for divergence, -1 if not applicable
  std::vector<double> residuals;  // Newton residual norms of the failed step
  std::string message;
};

class Error : public std::runtime_error {
 public:
  explicit Error(const Failure& f) : std::runtime_error(f.message), failure(f) {}
  Failure failure;
};
class DivergenceError : public Error { using Error::Error; };
class ConvergenceError : public Error { using Error::Error; };
class SingularMatrixError : public Error { using Error::Error; };

[[noreturn]] inline void throw_failure(const Failure& f) {
  switch (f.status) {
    case Status::diverged: throw DivergenceError(f);
    case Status::newton_failed: throw ConvergenceError(f);
    case Status::singular_matrix: throw SingularMatrixError(f);
    default: throw Error(f);
  }
}

namespace detail {
inline bool finite(double x) { return std::isfinite(x); }

// body(i) for i = 0 .. n-1. Up to 8 entries the count is a compile-time constant, so the loop is
// unrolled into straight-line (and paired SIMD) code without the trip-count tests, alias checks
// and remainder of a general loop, which on a model of a few DOFs cost more than the arithmetic.
// Same operations in the same order either way.
// flatten: the body is inlined into each loop (left to itself, the inliner gives up on a body used
// in nine loops and calls it entry by entry).
#if defined(__GNUC__)
#define NVIB_FLATTEN __attribute__((flatten))
#else
#define NVIB_FLATTEN
#endif
template <int N, class F>
NVIB_FLATTEN inline void unrolled(F& body) {
  for (Index i = 0; i < N; ++i) body(i);
}
template <class F>
NVIB_FLATTEN inline void looped(Index n, F& body) {
  for (Index i = 0; i < n; ++i) body(i);
}
template <class F>
inline void for_each_index(Index n, F&& body) {
  switch (n) {
    case 1: return unrolled<1>(body);
    case 2: return unrolled<2>(body);
    case 3: return unrolled<3>(body);
    case 4: return unrolled<4>(body);
    case 5: return unrolled<5>(body);
    case 6: return unrolled<6>(body);
    case 7: return unrolled<7>(body);
    case 8: return unrolled<8>(body);
    default: return looped(n, body);
  }
}
}  // namespace detail

}  // namespace nvib
