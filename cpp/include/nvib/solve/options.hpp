// What a run is asked to do (SolveOptions) and what it gives back (Result), with the limits and
// defaults the loop applies.
#pragma once

#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <string>
#include <vector>

#include "../base/types.hpp"

namespace nvib {

struct SolveOptions {
  double t0 = 0.0;
  std::int64_t save_every = 1;  // save steps 0, k, 2k, ... and always the last one
  std::vector<Index> dofs;      // DOFs to save; empty means all
  // |u_i| beyond this bound counts as divergence (non-finite states always do).
  // NaN (the default) means default_max_displacement() of the initial state;
  // infinity means no bound.
  double max_displacement = std::numeric_limits<double>::quiet_NaN();
  bool throw_on_failure = true;
  // Seconds of work between observer calls and interrupt polls (on a clock, not a count of steps).
  double observe_period = 0.05;
  // Record kinetic and potential energy, work of the loads, dissipated energy
  // and the balance error at every saved state (powers integrated every step
  // by the trapezoidal rule).
  bool energy = false;
  // With energy: a run whose energy balance error exceeds this fraction of the
  // energy scale (the largest |kinetic| + |potential| + |work in| + |dissipated|
  // so far) stops as diverged. Catches an instability that stays finite (a
  // vehicle launched off its rails) which no displacement bound sees.
  // Checked every step from the 10th on; infinity means no check; NaN (the
  // default) means kDefaultMaxEnergyError with energy, no check without.
  double max_energy_error = std::numeric_limits<double>::quiet_NaN();
  // An exception out of the step loop (an interrupt hook, a throwing force or observer) leaves as a
  // PartialRun carrying the history saved so far and the exception, instead of the exception alone.
  bool keep_partial = false;
  // The saved history may take at most this many bytes; NaN (the default): half the memory
  // available when the run starts; infinity: no limit. Checked before anything is allocated.
  double max_history_bytes = std::numeric_limits<double>::quiet_NaN();
  // Named effects to record at every saved state (measure, rate, force, internal variables).
  std::vector<std::string> record;
  // Collapse (status collapsed, the run stops): a law with memory that lost its strength, or, if
  // this is a number, an effect with memory whose |measure| exceeds it. stop_at_collapse = false
  // runs on (a failed law then carries no force).
  double collapse_deformation = std::numeric_limits<double>::quiet_NaN();
  bool stop_at_collapse = true;
  // Track the peaks over every accepted step, whatever save_every: max |u_i| of every DOF and, for each
  // row of peak_measures (an m x n matrix, m >= 0), max |row . u| (a named effect's measure, a storey's
  // drift), into Result::peak_u and Result::peak_measures; with energy, the relative balance error over
  // every step too (Result::peak_energy_error).
  bool peaks = false;
  SparseMatrix peak_measures;
  // Estimate every DOF's error relative to its peak from the accepted steps (error_estimate.hpp) into
  // Result::error_estimate.
  bool error_estimate = true;
  // Adaptive steps (adaptive.hpp): NaN (the default) runs at the fixed step dt; a number in (0, 1) asks
  // for a run whose error relative to each DOF's peak stays within it: the steps are chosen as the run
  // goes, and a companion run on double steps measures the error (a run that misses tol is redone with
  // a tighter control). dt is the first step. max_dt: the longest step of the companion run (NaN: dt for
  // the explicit schemes, 10 dt for the others); min_dt: its shortest, below which the run stops with a
  // message (NaN: 1e-6 dt).
  double tol = std::numeric_limits<double>::quiet_NaN();
  double max_dt = std::numeric_limits<double>::quiet_NaN();
  double min_dt = std::numeric_limits<double>::quiet_NaN();
  // For testing the rejection: every k-th companion step is first tried at twice its length and rejected whatever
  // its error (a retaken step must equal one taken once). 0: never.
  std::int64_t reject_every = 0;
};

// Columns of Result::energy: dissipated by the viscous laws (dampers), hysteretic by the laws with
// memory; potential includes the energy the laws with memory store.
enum EnergyColumn { kinetic = 0, potential = 1, work_in = 2, dissipated = 3, hysteretic = 4, balance_error = 5 };
constexpr Index kEnergyColumns = 6;

// Bytes of the history a run saves: nsave states of t and (u, v, a) on m DOFs, plus the energy columns.
inline double history_bytes(std::int64_t nsave, Index m, bool energy) {
  return 8.0 * static_cast<double>(nsave) *
         (1.0 + 3.0 * static_cast<double>(m) + (energy ? static_cast<double>(kEnergyColumns) : 0.0));
}

// A recorded effect (SolveOptions::record): per saved state, the measure d, its rate d', the force
// and the internal variables of each of its `count` effects (state: count x state_names columns).
struct EffectRecord {
  std::string name, type;
  std::vector<std::string> state_names;
  Index count = 0;
  History measure, rate, force, state;
};

struct Result {
  Vector t;
  History u, v, a;  // (n_saved, n_saved_dofs), row-major
  History energy;   // (n_saved, kEnergyColumns) if requested: see EnergyColumn
  std::vector<EffectRecord> effects;  // the recorded effects, in the order asked
  std::vector<Index> dofs;
  Stats stats;
  Status status = Status::success;
  Failure failure;
  std::int64_t num_steps_requested = 0;
  // Largest equilibrium residual of an accepted step relative to its force
  // scale (implicit schemes; NaN for the others and for linear models, whose
  // single solve is exact up to round-off). Newton keeps it below about rtol;
  // iteration = none reports here what it leaves unbalanced.
  double max_residual = std::numeric_limits<double>::quiet_NaN();
  // With SolveOptions::peaks: the peaks over every accepted step (the saved ones or not), from t0; empty
  // otherwise.
  Vector peak_u, peak_measures;
  // With SolveOptions::peaks and energy: the relative energy balance error over every step (NaN otherwise).
  double peak_energy_error = std::numeric_limits<double>::quiet_NaN();
  // With SolveOptions::error_estimate: every DOF's estimated max |u_i - u_i,exact| / max |u_i| (see
  // error_estimate.hpp); empty when not asked for or the stepper neither names its scheme nor follows
  // its own error.
  Vector error_estimate;
};

// The energy check's default limit: half the energy scale. A sound run's
// balance error is orders of magnitude below it; an unstable one reaches it.
constexpr double kDefaultMaxEnergyError = 0.5;

// First step at which SolveOptions::max_energy_error is checked.
constexpr std::int64_t kEnergyCheckFrom = 10;

// Scale factor of the default divergence bound.
constexpr double kBoundFactor = 1e10;

// The default bound on |u_i|: 1e10 x max(1, max|u|, max|v| T, L) for a run of
// duration T from (u, v), where L is the displacement the model's loads may cause
// (load_displacement_scale() in solve.hpp; 0 where it is not known). Far beyond
// any physical response of a model started there and so loaded, in whatever
// units, yet reached long before a diverging state overflows, so such a run
// stops naming the DOF instead of running on with inf or NaN.
inline double default_max_displacement(const Vector& u, const Vector& v, double duration, double load_scale = 0.0) {
  double scale = 1.0;
  if (u.size() > 0) scale = std::max(scale, u.cwiseAbs().maxCoeff());
  if (v.size() > 0) scale = std::max(scale, v.cwiseAbs().maxCoeff() * std::abs(duration));
  if (std::isfinite(load_scale)) scale = std::max(scale, load_scale);
  return kBoundFactor * scale;
}

// Number of steps to reach t_end: t_end/dt rounded when it is an integer up
// to round-off, else rounded up (the run then ends at the first multiple of dt past t_end).
inline std::int64_t steps_to_reach(double t0, double t_end, double dt) {
  check_start_time(t0);
  NVIB_CHECK(std::isfinite(t_end), "t_end", "must be finite");
  check_time_step(dt);
  NVIB_CHECK(t_end > t0, "t_end", "must be > t0 (" + detail::fmt(t0) + "), got " + detail::fmt(t_end));
  const double r = (t_end - t0) / dt;
  NVIB_CHECK(r < 9.0e15, "dt", "too many steps (t_end - t0)/dt = " + detail::fmt(r));
  const double nearest = std::round(r);
  if (std::abs(r - nearest) <= 1e-9 * std::max(1.0, r)) return std::max<std::int64_t>(1, static_cast<std::int64_t>(nearest));
  return static_cast<std::int64_t>(std::ceil(r));
}

// The steps of a run from t0 to t_end (solve): steps_to_reach's, and a step longer than the run is
// refused: the run would end at t0 + dt, past t_end, without a word.
inline std::int64_t run_steps(double t0, double t_end, double dt) {
  const std::int64_t n = steps_to_reach(t0, t_end, dt);
  NVIB_CHECK(n > 1 || (t_end - t0) / dt >= 1.0 - 1e-9, "dt",
             "the step " + detail::fmt(dt) + " is longer than the run (t_end - t0 = " + detail::fmt(t_end - t0) +
                 "), which would end at t = " + detail::fmt(t0 + dt) + ", past t_end; give dt <= t_end - t0");
  return n;
}

// What leaves integrate() and solve() with SolveOptions::keep_partial when the step loop throws: the
// history saved before the exception (counters of the steps taken) and the exception itself.
struct PartialRun {
  Result partial;
  std::exception_ptr cause;
};

}  // namespace nvib
