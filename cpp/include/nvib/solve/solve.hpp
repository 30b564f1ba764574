// The one loop shared by every scheme: step, detect divergence, hand each accepted step to the
// observers (saving, energy, recorded effects, collapse: observers.hpp), sum the counters, report
// progress and poll for an interrupt about every 50 ms of work. It knows no scheme: a scheme names
// its stepper (Scheme::stepper<Model>).
#pragma once

#include <chrono>
#include <cstring>
#include <exception>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>
#if defined(__GLIBCXX__)
#include <cxxabi.h>  // abi::__forced_unwind
#endif

#include "../base/interrupt.hpp"
#include "../base/memory.hpp"
#include "../schemes/stepper.hpp"
#include "error_estimate.hpp"
#include "observers.hpp"
#include "options.hpp"

namespace nvib {

// Names the first offending quantity: u beyond the bound or non-finite, then v, then a; `why` says
// where the bound comes from.
template <class Stepper>
Failure divergence(const Stepper& st, std::int64_t step, double bound, const std::string& why = std::string()) {
  Failure f;
  f.status = Status::diverged;
  f.step = step;
  f.t = st.time();
  const char* what = "u";
  double value = 0.0;
  const Vector* vecs[3] = {&st.u(), &st.v(), &st.a()};
  const char* names[3] = {"u", "v", "a"};
  for (int q = 0; q < 3 && f.dof < 0; ++q)
    for (Index d = 0; d < vecs[q]->size(); ++d) {
      const double x = (*vecs[q])[d];
      if (!std::isfinite(x) || (q == 0 && !(std::abs(x) <= bound))) {
        f.dof = d;
        what = names[q];
        value = x;
        break;
      }
    }
  const bool beyond = std::isfinite(value);
  f.message = "diverged at t = " + detail::fmt(f.t) + " (step " + std::to_string(step) + "): " + what + "[" +
              std::to_string(f.dof) + "] = " + detail::fmt(value) +
              (beyond ? " beyond the bound " + detail::fmt(bound) + why : std::string(", not finite"));
  return f;
}

// The displacement the model's declared loads may cause over a run from t0 to t1: max over the DOFs of
// max_t |P_i(t)| / (max(K_ii, 0) + M_ii / T^2), T = t1 - t0. P is the force of the declared effects at
// rest (u = v = 0: the loads, the ground motions, any preload), at t0 alone if none depends on time,
// else at 65 times spread over [t0, t1]; K_ii is the diagonal of the linear K plus the effects' tangent
// at rest. It is the static displacement of DOF i under that load held by its own stiffness, and,
// where there is little, the displacement the load gives its mass over the run (P T^2 / M, a free
// body): so a model in mm or um, or loaded hard in its own units, has a bound as far
// above its response as one in m. 0 for a model without declared effects (a Python callable force is
// not evaluated here: it may count or cost its calls). The effects are evaluated on a copy: the run's
// own trial states and counters are left as they are.
template <class ModelT>
double load_displacement_scale(const ModelT& model, double t0, double t1) {
  const effects::EffectSet* set = effect_set_of(model.nonlinear_force());
  const double T = std::abs(t1 - t0);
  if (set == nullptr || !(T > 0.0) || !std::isfinite(T)) return 0.0;
  const Index n = model.size();
  const Vector peak = set->rest_force_peak(t0, t1, set->uses_time() ? 64 : 0);
  const Vector zero = Vector::Zero(n);
  Vector kd = Vector::Zero(n);
  if (model.has_K()) kd = model.K().diagonal();
  Vector effects_kd = Vector::Zero(n);
  set->add_tangent_diagonal(zero.data(), zero.data(), t0, effects_kd.data());
  for (Index i = 0; i < n; ++i)
    if (std::isfinite(effects_kd[i])) kd[i] += effects_kd[i];
  const Vector hold = kd.cwiseMax(0.0) + model.mass().diagonal_entries().cwiseAbs() / (T * T);
  double scale = 0.0;
  for (Index i = 0; i < n; ++i)
    if (peak[i] > 0.0 && hold[i] > 0.0) scale = std::max(scale, peak[i] / hold[i]);
  return std::isfinite(scale) ? scale : 0.0;
}

namespace detail {
// Bit 63 set when some entry is not finite (nonfinite_bits in base/loops.hpp).
inline std::uint64_t nonfinite_bits(const Vector& x) { return nonfinite_bits(x.size(), x.data()); }
}  // namespace detail

// Every |u_i| <= bound and finite. A comparison with NaN is false and |inf| exceeds every finite bound
// (an infinite bound is taken as the largest finite double). Up to 8 entries, a conjunction of
// comparisons in straight-line code; above, block by block, the bits' test and the largest |u_i| (loops
// the compiler vectorises, and the block still in cache for the second: the conjunction on bools is
// compiled entry by entry).
inline bool displacement_ok(const Vector& u, double bound) {
  const double* p = u.data();
  const Index n = u.size();
  const double finite_bound = std::min(bound, std::numeric_limits<double>::max());
  if (n <= 8) {
    bool ok = true;
    detail::for_each_index(n, [&ok, p, finite_bound](Index i) { ok &= std::abs(p[i]) <= finite_bound; });
    return ok;
  }
  constexpr Index kBlock = 1024;
  for (Index b = 0; b < n; b += kBlock) {
    double m = 0.0;
    bool finite = true;
    detail::largest(std::min(kBlock, n - b), p + b, m, finite);
    if (!finite || !(m <= finite_bound)) return false;
  }
  return true;
}
// The same test after a step, on the largest |u_i| the step measured where it did (measured_max_u()).
template <class Stepper>
bool stepped_displacement_ok(const Stepper& st, double bound) {
  const double m = st.measured_max_u();
  if (m >= 0.0) return m <= std::min(bound, std::numeric_limits<double>::max());
  return displacement_ok(st.u(), bound);  // (not measured, or not finite: the whole test)
}
// Every entry of v and a finite.
inline bool rates_ok(const Vector& v, const Vector& a) {
  return !((detail::nonfinite_bits(v) | detail::nonfinite_bits(a)) >> 63);
}

// Steppers that measure the equilibrium residual of each accepted step (the implicit ones).
template <class S, class = void>
struct has_accepted_residual : std::false_type {};
template <class S>
struct has_accepted_residual<S, std::void_t<decltype(std::declval<const S&>().accepted_residual())>>
    : std::true_type {};


// One step with the loop's divergence test (every entry of u, v and a
// finite), for stepping by hand: the failure, if any, in `failure`.
template <class Stepper>
Status checked_step(Stepper& st, Failure& failure) {
  const Status s = st.step();
  if (s != Status::success) {
    failure = st.failure();
    return s;
  }
  if (!displacement_ok(st.u(), std::numeric_limits<double>::infinity()) || !rates_ok(st.v(), st.a())) {
    failure = divergence(st, st.step_index(), std::numeric_limits<double>::infinity());
    return Status::diverged;
  }
  return s;
}

// Steppers that name their scheme (every stepper of the registry): the error estimate needs its constants.
template <class S, class = void>
struct has_scheme : std::false_type {};
template <class S>
struct has_scheme<S, std::void_t<decltype(std::declval<const S&>().scheme())>> : std::true_type {};

struct NoObserver {
  void operator()(std::int64_t, std::int64_t) const {}
};

namespace detail {
// The checks of a run's options that both loops (fixed steps, adaptive.hpp) make, naming the option;
// returns the energy check's limit (SolveOptions::max_energy_error with its default applied).
template <class ModelT>
double checked_run_options(const SolveOptions& opt, const ModelT& model, Index n) {
  NVIB_CHECK(opt.save_every >= 1, "save_every", "must be >= 1, got " + std::to_string(opt.save_every));
  NVIB_CHECK(opt.observe_period > 0.0, "observe_period", "must be > 0");
  NVIB_CHECK(std::isnan(opt.max_displacement) || opt.max_displacement > 0.0, "max_displacement",
             "must be > 0 (infinity for no bound, NaN for the default)");
  NVIB_CHECK(std::isnan(opt.collapse_deformation) || opt.collapse_deformation > 0.0, "collapse_deformation",
             "must be > 0 (NaN for none)");
  for (Index d : opt.dofs)
    NVIB_CHECK(d >= 0 && d < n, "dofs", "index " + std::to_string(d) + " is out of range for " + std::to_string(n) +
                                            " degrees of freedom");
  const effects::EffectSet* set = effect_set_of(model.nonlinear_force());
  NVIB_CHECK(opt.record.empty() || set != nullptr, "record", "the model has no declared effects to record");
  const double energy_limit = std::isnan(opt.max_energy_error)
                                  ? (opt.energy ? kDefaultMaxEnergyError : std::numeric_limits<double>::infinity())
                                  : opt.max_energy_error;
  NVIB_CHECK(energy_limit > 0.0, "max_energy_error", "must be > 0 (infinity for no check)");
  NVIB_CHECK(energy_limit == std::numeric_limits<double>::infinity() || opt.energy, "max_energy_error",
             "needs the energy accounting (energy = true)");
  NVIB_CHECK(!opt.energy || model.accounts_energy(), "energy",
             "the model has a force whose energy is unknown (a user callable or a compiled law); energy accounting "
             "needs built-in effects");
  NVIB_CHECK(std::isnan(opt.collapse_deformation) || (set != nullptr && set->has_state()), "collapse_deformation",
             "applies to effects with memory, and this model has none");
  return energy_limit;
}

// The divergence bound on |u_i| of a run of `duration` from the stepper's state (max_displacement, or its
// default), and in `why` what a divergence message says of it.
template <class Stepper>
double divergence_bound(const SolveOptions& opt, const Stepper& st, double duration, double load_scale, std::string& why) {
  if (!std::isnan(opt.max_displacement)) {
    why.clear();
    return opt.max_displacement;
  }
  why = " (the default: 1e10 x the run's displacement scale, the largest of 1, max|u0|, max|v0| x its duration "
        "and the static displacement of its loads)";
  return default_max_displacement(st.u(), st.v(), duration, load_scale);
}
// The observers of a run's accepted steps that the fixed-step and the adaptive loops share: the saved
// history, the energy account, the recorded effects, the collapse watch, the peaks and the largest
// accepted residual. `row` counts the saved states.
template <class Model>
struct RunObservers {
  RunObservers(Result& res, Model& model, const effects::EffectSet* set, const SolveOptions& opt, Index n,
               std::int64_t rows, double energy_limit, double dt)
      : history(res, opt, n, rows) {
    if (opt.energy) energy.emplace(res, model, rows, energy_limit, dt, opt.peaks);
    if (!opt.record.empty()) recorder.emplace(res, *set, opt.record, rows);
    if (set != nullptr && opt.stop_at_collapse) {
      collapse.emplace(*set, opt.collapse_deformation);
      if (!collapse->active()) collapse.reset();
    }
    if (opt.peaks) peaks.emplace(res, opt, n);
  }
  // The limit on the saved history's bytes, and the bytes of one saved state.
  static double memory_limit(const SolveOptions& opt) {
    return std::isnan(opt.max_history_bytes) ? 0.5 * available_memory_bytes() : opt.max_history_bytes;
  }
  static double row_bytes(const SolveOptions& opt, const effects::EffectSet* set, Index m) {
    return history_bytes(1, m, opt.energy) +
           (opt.record.empty() || set == nullptr ? 0.0 : observe::EffectRecorder::bytes_per_state(*set, opt.record));
  }

  template <class Stepper>
  void start(const Stepper& st) {
    if (energy) energy->start(st);
    save(st);
    if (peaks) peaks->update(st);
  }
  template <class Stepper>
  void save(const Stepper& st) {
    history.save(st, row);
    if (energy) energy->save(st, row);
    if (recorder) recorder->save(st, row);
    ++row;
  }
  void resize(std::int64_t rows) {
    history.resize(rows);
    if (energy) energy->resize(rows);
    if (recorder) recorder->resize(rows);
  }
  // After accepted step i: its residual, and the energy balance and collapse checks; false (with failure
  // set) when one of them stops the run.
  template <class Stepper>
  bool accepted(const Stepper& st, std::int64_t i, Failure& failure) {
    if constexpr (has_accepted_residual<Stepper>::value) {
      const double r = st.accepted_residual();
      if (r > max_residual || (std::isnan(max_residual) && !std::isnan(r))) max_residual = r;
    }
    return !((energy && !energy->step(st, i, failure)) || (collapse && !collapse->step(st, i, failure)));
  }
  // The run stopped at a collapse: the state it collapsed in.
  template <class Stepper>
  void collapsed(const Stepper& st) {
    save(st);
    if (peaks) peaks->update(st);
  }

  observe::SavedHistory history;
  std::optional<observe::EnergyAccount<Model>> energy;
  std::optional<observe::EffectRecorder> recorder;
  std::optional<observe::CollapseWatch> collapse;
  std::optional<observe::PeakTracker> peaks;
  Index row = 0;
  double max_residual = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace detail

template <class Stepper, class Observer>
Result integrate_adaptive(Stepper& st, double t_end, const SolveOptions& opt, Observer&& observe);

template <class Stepper, class Observer = NoObserver>
Result integrate(Stepper& st, double t_end, const SolveOptions& opt, Observer&& observe = Observer{}) {
  if (!std::isnan(opt.tol)) {
    if constexpr (has_scheme<Stepper>::value) {
      return integrate_adaptive(st, t_end, opt, std::forward<Observer>(observe));
    } else {
      detail::throw_argument("tol", "adaptive steps need a stepper of the scheme registry");
    }
  }
  using clock = std::chrono::steady_clock;
  // The default divergence bound, before the clock starts: it is set-up, not stepping.
  const double load_scale = std::isnan(opt.max_displacement) && std::isfinite(t_end)
                                ? load_displacement_scale(st.model(), st.time(), t_end)
                                : 0.0;
  const auto start = clock::now();
  const Index n = st.size();
  auto& model = st.model();
  const effects::EffectSet* set = effect_set_of(model.nonlinear_force());
  const double energy_limit = detail::checked_run_options(opt, model, n);
  const std::int64_t nsteps = steps_to_reach(st.time(), t_end, st.dt());
  const std::int64_t k = opt.save_every;
  const std::int64_t nsave = nsteps / k + 1 + (nsteps % k != 0 ? 1 : 0);
  {
    const Index m = opt.dofs.empty() ? n : static_cast<Index>(opt.dofs.size());
    using Observers = detail::RunObservers<std::decay_t<decltype(model)>>;
    const double bytes = static_cast<double>(nsave) * Observers::row_bytes(opt, set, m);
    const double limit = Observers::memory_limit(opt);
    NVIB_CHECK(limit <= 0.0 || bytes <= limit, "save_every, dofs",
               "the saved history would need " + detail::fmt(bytes / 1e9) + " GB (" + std::to_string(nsave) +
                   " states of " + std::to_string(m) + " DOFs: t, u, v, a" + (opt.energy ? ", energy" : "") +
                   (opt.record.empty() ? "" : ", recorded effects") + "), more than the limit of " +
                   detail::fmt(limit / 1e9) + " GB" +
                   (std::isnan(opt.max_history_bytes) ? " (half the memory available)" : "") +
                   "; save fewer states (a larger save_every) or fewer DOFs (dofs)");
    NVIB_CHECK(static_cast<double>(nsave) * static_cast<double>(std::max<Index>(m, 1)) <= 9.0e15, "save_every",
               "the run would save " + std::to_string(nsave) + " states; raise save_every");
  }

  Result res;
  res.num_steps_requested = nsteps;
  // The observers of the accepted steps.
  using Model = std::decay_t<decltype(model)>;
  detail::RunObservers<Model> obs(res, model, set, opt, n, nsave, energy_limit, st.dt());
  std::optional<observe::ErrorEstimate<Model>> estimate;
  std::optional<observe::OwnErrorEstimate> own_estimate;
  if constexpr (observe::tracks_own_error<Stepper>::value) {
    if (opt.error_estimate) own_estimate.emplace(res, n);
  } else if constexpr (has_scheme<Stepper>::value) {
    if (opt.error_estimate) {
      const ErrorConstants& c = cached_error_constants(st.scheme());
      if (c.available) {
        estimate.emplace(res, model, c, error_blend(st.scheme()), st.dt(), n);
      } else {
        res.error_estimate = Vector::Constant(n, std::numeric_limits<double>::quiet_NaN());
      }
    }
  }
  obs.start(st);
  if (estimate) estimate->start(st);
  if (own_estimate) own_estimate->start(st);

  const Stats before = st.stats();
  std::string why;
  const double bound = detail::divergence_bound(opt, st, t_end - st.time(), load_scale, why);
  // Countdowns instead of i % k: an integer division per step costs as much as a small model's force.
  std::int64_t to_save = k, done = 0;
  ClockPoll poll(opt.observe_period);
  // The history up to the last saved state, the counters of this call and the wall time.
  auto finish = [&] {
    if (obs.row < nsave) obs.resize(obs.row);
    res.max_residual = obs.max_residual;
    if (estimate) estimate->finish();
    if (own_estimate) own_estimate->finish(st);
    res.stats = st.stats();
    res.stats -= before;  // counters of this call only (the stepper's own are cumulative)
    res.stats.wall_time = std::chrono::duration<double>(clock::now() - start).count();
  };
  try {
    for (std::int64_t i = 1; i <= nsteps; ++i) {
      Status s = st.step();
      const bool saving = --to_save == 0 || i == nsteps;
      if (s == Status::success) {
        // u every step; v and a where a state is saved. A non-finite v_n or a_n makes u_{n+1}
        // non-finite in every scheme, so a run still stops within one step, and no saved row holds a
        // non-finite value.
        if (!stepped_displacement_ok(st, bound) || (saving && !rates_ok(st.v(), st.a()))) {
          res.failure = divergence(st, i, bound, why);
          s = Status::diverged;
        }
      } else {
        res.failure = st.failure();
      }
      if (s == Status::success && !obs.accepted(st, i, res.failure)) s = res.failure.status;
      if (s != Status::success) {
        res.status = s;
        if (s == Status::collapsed) obs.collapsed(st);  // the state it collapsed in
        break;
      }
      done = i;
      if (obs.peaks) obs.peaks->update(st);
      if (estimate) estimate->step(st, i);
      if (own_estimate) own_estimate->step(st, i);
      if (saving) {
        obs.save(st);
        to_save = k;
      }
      if (poll.tick()) {
        observe(i, nsteps);
        poll_interrupt();
      }
    }
  }
#if defined(__GLIBCXX__)
  catch (abi::__forced_unwind&) {
    throw;  // a thread being ended (pthread_exit, pthread_cancel) must not be kept from ending
  }
#endif
  catch (...) {
    if (!opt.keep_partial) throw;
    finish();
    res.status = Status::interrupted;
    res.failure = Failure{};
    res.failure.status = Status::interrupted;
    res.failure.step = done + 1;  // the step under way (a step the interrupt hook stopped after is complete)
    res.failure.t = obs.row > 0 ? res.t[obs.row - 1] : st.time();
    res.failure.message = "interrupted after step " + std::to_string(done) + " of " + std::to_string(nsteps) +
                          "; the history is saved up to t = " +
                          (obs.row > 0 ? detail::fmt(res.t[obs.row - 1]) : std::string("the start"));
    throw PartialRun{std::move(res), std::current_exception()};
  }
  observe(done, nsteps);  // once at the end too, however short the run
  finish();
  if (res.status != Status::success && res.status != Status::collapsed && opt.throw_on_failure) throw_failure(res.failure);
  return res;
}

template <class Scheme, class ModelT>
typename Scheme::template stepper<ModelT> make_stepper(const Scheme& scheme, ModelT model, double dt) {
  return typename Scheme::template stepper<ModelT>(scheme, std::move(model), dt);
}

// Integrates from (t0, u0, v0) to t_end. Counters include the start-up
// (initial acceleration, PIM's exponential).
template <class Scheme, class ModelT, class Observer = NoObserver>
Result solve(const ModelT& model, const Scheme& scheme, double dt, double t_end, const Vector& u0,
             const Vector& v0, const SolveOptions& opt = {}, Observer&& observe = Observer{}) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  run_steps(opt.t0, t_end, dt);  // validate before any work
  auto st = make_stepper(scheme, model, dt);
  st.initialize(opt.t0, u0, v0);
  const Stats init = st.stats();
  SolveOptions inner = opt;
  inner.throw_on_failure = false;
  Result res;
  try {
    res = integrate(st, t_end, inner, std::forward<Observer>(observe));
  } catch (PartialRun& p) {
    p.partial.stats += init;
    p.partial.stats.wall_time = std::chrono::duration<double>(clock::now() - start).count();
    throw;
  }
  const double wall = std::chrono::duration<double>(clock::now() - start).count();
  res.stats += init;
  res.stats.wall_time = wall;
  if (res.status != Status::success && res.status != Status::collapsed && opt.throw_on_failure)
    throw_failure(res.failure);
  return res;
}

}  // namespace nvib

#include "adaptive.hpp"
