// Counters of a solve.
#pragma once

#include <cstdint>

namespace nvib {

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

}  // namespace nvib
