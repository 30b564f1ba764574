// Counters of a solve.
#pragma once

#include <cstdint>

namespace nvib {

// Counters summed over a whole solve (never reset per step), declared once in counters(): the
// binding, the files and the sums read that list.
struct Stats {
  std::int64_t num_steps = 0;
  std::int64_t num_force_evals = 0;
  std::int64_t num_fd_force_evals = 0;
  std::int64_t num_tangent_evals = 0;
  std::int64_t num_newton_iters = 0;
  std::int64_t num_factorizations = 0;
  std::int64_t num_reused_factorizations = 0;
  std::int64_t num_linear_solves = 0;
  std::int64_t num_expm = 0;
  std::int64_t num_rejected_steps = 0;
  std::int64_t num_events = 0;
  std::int64_t num_check_steps = 0;
  std::int64_t num_restarts = 0;
  double wall_time = 0.0;  // seconds
  const char* linear_solver = "";  // of the implicit schemes' Newton iteration: "dense LU", "sparse LDLT", ...

  // v(name, counter, meaning) for every counter, in order.
  template <class Self, class V>
  static void counters(Self& s, V&& v) {
    v("num_steps", s.num_steps, "accepted steps");
    v("num_force_evals", s.num_force_evals, "evaluations of F(u, v, t) asked for by the scheme");
    v("num_fd_force_evals", s.num_fd_force_evals, "extra evaluations spent on finite-difference tangents");
    v("num_tangent_evals", s.num_tangent_evals, "tangent (K_t, C_t) evaluations, analytic or finite-difference");
    v("num_newton_iters", s.num_newton_iters, "Newton iterations");
    v("num_factorizations", s.num_factorizations, "factorisations of an iteration matrix");
    v("num_reused_factorizations", s.num_reused_factorizations,
      "iteration matrices identical to the one factorised last, whose factors were kept");
    v("num_linear_solves", s.num_linear_solves, "solves with a factorised iteration matrix");
    v("num_expm", s.num_expm, "matrix exponentials (PIM)");
    v("num_rejected_steps", s.num_rejected_steps, "steps retaken (adaptive runs: too inaccurate, failed, or landing on an event)");
    v("num_events", s.num_events, "steps landed on a declared event (adaptive runs)");
    v("num_check_steps", s.num_check_steps, "steps of the companion run on double steps that measures an adaptive run's error");
    v("num_restarts", s.num_restarts, "adaptive runs redone from the start with a tighter control (their error exceeded tol)");
  }

  Stats& operator+=(const Stats& o) { return combine(o, 1); }
  Stats& operator-=(const Stats& o) { return combine(o, -1); }

 private:
  Stats& combine(const Stats& o, int sign) {
    std::int64_t* mine[16];
    int k = 0;
    counters(*this, [&](const char*, std::int64_t& c, const char*) { mine[k++] = &c; });
    k = 0;
    counters(o, [&](const char*, const std::int64_t& c, const char*) { *mine[k++] += sign * c; });
    wall_time += sign * o.wall_time;
    if (sign > 0 && *o.linear_solver) linear_solver = o.linear_solver;
    return *this;
  }
};

}  // namespace nvib
