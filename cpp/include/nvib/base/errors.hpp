// Errors: a bad argument (ArgumentError, named; NVIB_CHECK), and how a run
// ends (Status) with where and why it stopped early (Failure, and the
// exceptions that carry one). Messages are built only on failure: a check
// that passes costs nothing.
#pragma once

#include <cstdint>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "format.hpp"

namespace nvib {

// A bad argument: `argument` names it ("eta", "effects[3].measure"); the
// message is "<argument>: <what is wrong>".
class ArgumentError : public std::invalid_argument {
 public:
  ArgumentError(std::string argument, const std::string& what)
      : std::invalid_argument(argument + ": " + what), argument_(std::move(argument)), reason_(what) {}
  const std::string& argument() const { return argument_; }
  const std::string& reason() const { return reason_; }  // the message without "<argument>: "

 private:
  std::string argument_, reason_;
};

namespace detail {
[[noreturn]] inline void throw_argument(std::string argument, const std::string& what) {
  throw ArgumentError(std::move(argument), what);
}

}  // namespace detail

// interrupted: an exception (an interrupt, an error raised by the force or the observer) stopped the
// run; it reaches the caller as itself, or as a PartialRun carrying the history (SolveOptions::keep_partial).
// collapsed: the structure collapsed (a law lost its strength, or deformed beyond the collapse
// limit): a result of the model, not a failure of the scheme, so it is returned, never thrown.
enum class Status { success, diverged, newton_failed, singular_matrix, interrupted, collapsed };

inline const char* to_string(Status s) {
  switch (s) {
    case Status::success: return "success";
    case Status::diverged: return "diverged";
    case Status::newton_failed: return "newton_failed";
    case Status::singular_matrix: return "singular_matrix";
    case Status::interrupted: return "interrupted";
    case Status::collapsed: return "collapsed";
  }
  return "unknown";
}

// Where and why a run stopped early.
struct Failure {
  Status status = Status::success;
  std::int64_t step = 0;  // index of the step that failed (1 = the first step)
  double t = 0.0;         // time the failed step was heading for
  Eigen::Index dof = -1;         // offending DOF for divergence, -1 if not applicable
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

}  // namespace nvib

// NVIB_CHECK(condition, argument, what): throws ArgumentError(argument, what)
// when the condition fails; `what` is evaluated only then.
#define NVIB_CHECK(condition, argument, what)                        \
  do {                                                               \
    if (!(condition)) ::nvib::detail::throw_argument((argument), (what)); \
  } while (0)

namespace nvib {

// The one check of a time step and of a start time, wherever one is given (a Stepper, a run's step count).
inline void check_time_step(double dt) {
  NVIB_CHECK(std::isfinite(dt) && dt > 0.0, "dt", "the time step must be finite and > 0, got " + detail::fmt(dt));
}
inline void check_start_time(double t0) { NVIB_CHECK(std::isfinite(t0), "t0", "the initial time must be finite"); }

}  // namespace nvib
