// Adaptive steps (SolveOptions::tol): a run whose error relative to each DOF's peak is measured, and
// within tol, with steps chosen as the run goes and landing on the points where a declared force is
// not smooth. Included at the end of solve.hpp, whose integrate() hands a run with a tol here.
//
// Two runs side by side. A companion run takes steps H chosen by a local control (below); the answer
// takes two steps of H/2 over each, from its own state (kept in checkpoint slot 1 while the companion
// steps). Both are the same scheme of global order p on the same grid, so the companion's error is
// 2^p times the answer's where the steps resolve the motion, and the answer's error is
//     estimate_i = max_t |u_i - u_companion,i| / (2^p - 1) / peak_i
// (Richardson; p the scheme's order_u(): 2, or 1 for a first-order variant). This is the answer's
// Result::error_estimate. It sees what no local formula saw within a factor 3: the amplitude-dependent
// period of anharmonic motion, and the timing of wheel impacts. An attempt that ends above tol is
// redone from the start (slot 2) with a tighter control, at most kMaxRestarts times; the answer of the
// last attempt is returned, its estimate telling how far it is. The price: the companion's half of the
// answer's steps, and the attempts redone (Stats::num_check_steps, num_restarts).
//
// The local control (error per unit step). Over a step the phase error of the fixed-step estimate
// (error_estimate.hpp) grows at the rate rho_i = (c3 h^2 |da_i/dt| + c2 h |a_i|) / scale_i; a run of span
// T (its duration, or the memory sqrt(2)/lambda when shorter, lambda the dissipation rate) ends within
// a control c when rho_i T <= c. A companion step whose rho T exceeds 2 c is retaken shorter; the next
// step is the one that would meet 0.8 c (rho grows as h^2, as h for a first-order scheme), at most
// twice and at least a fifth of the last, and longer only by 25 % or more (a new length costs an
// implicit scheme a factorisation and a two-level explicit one a rescaled history). scale_i is DOF i's
// peak so far, at least 1e-3 of the largest and a tenth of the displacement the loads may cause (so a
// run that starts at rest is not held to an error of zero). c starts at 2 tol (the companion's error
// near 4x the answer's). Explicit schemes are stable only below a step of about 2/w_max, which no
// accuracy estimate sees before an unstable mode has grown: the companion's longest step is dt (which
// should be stable), unless max_dt says otherwise; implicit schemes may grow to 10 dt. The precise
// integration method has no local rate (it is exact on the linear modes): a tol is refused for it.
//
// Events. A law may declare where its force is not smooth (law::has_event: a Hertz contact opening or
// closing, a gap closing, a hook's slack taken up, a bilinear law's yield point). A companion step
// across which an event value changes sign is retaken, by the Illinois variant of regula falsi on the
// step length, until it ends past the event by a step within a few units of round-off of the time: the
// next step starts at the event. A crossing within the first 1e-6 of a step is the round-off of the last
// landing and is not an event. The answer's two half steps end where the companion's step ends: on the
// companion's event, which is the answer's to within the error of its timing.
//
// Rejection restores the stepper exactly (checkpoint() / rollback(): u, v, a, the scheme's history,
// the laws' committed internal variables): a step retaken at the same length equals the step taken
// once, which SolveOptions::reject_every tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace nvib {

namespace observe {

// The local control of an adaptive run's companion: the error rate of a step and the step it asks for
// (see the top of this file).
template <class Model>
class AdaptiveControl {
 public:
  static constexpr double kSqrt2 = 1.41421356237309504880;
  static constexpr std::int64_t kRateEvery = 16;  // accepted steps between samples of the dissipation rate

  AdaptiveControl(Model& model, const ErrorConstants& c, double blend, Index n, double span, double floor)
      : model_(model), c_(c), w_(blend), span_(span), floor_(floor) {
    b_.setZero(n);
    peak_.setZero(n);
  }
  template <class Stepper>
  void start(const Stepper& st) {
    b_ = st.a();
    peak_ = st.u().cwiseAbs();
    hyst0_ = model_.hysteretic_dissipation();
    t0_ = st.time();
  }
  // The worst DOF's rho T / control for the step just taken (length h, state in st, not yet accepted):
  // the ratio of the step's error rate to what the control allows.
  template <class Stepper>
  double measure(const Stepper& st, double h, double tol) {
    const Index n = b_.size();
    const double* a = st.a().data();
    const double* u = st.u().data();
    double top = 0.0;
    for (Index k = 0; k < n; ++k) top = std::max(top, std::max(peak_[k], std::abs(u[k])));
    const double floor = std::max(1e-3 * top, floor_);
    double worst = 0.0;
    for (Index k = 0; k < n; ++k) {
      const double now = (1.0 - w_) * a[k] + w_ * aprev_[k];
      const double jerk = std::abs(now - b_[k]) / h;
      const double rho = c_.c3 * h * h * jerk + c_.c2 * h * std::abs(now);
      const double scale = std::max(std::max(peak_[k], std::abs(u[k])), floor);
      if (scale > 0.0) worst = std::max(worst, rho / scale);
    }
    return worst * horizon() / tol;
  }
  // After an accepted step of length h: the peaks, the slope's base and the dissipation rate.
  template <class Stepper>
  void accept(const Stepper& st, double h) {
    ++accepted_;
    if (accepted_ % kRateEvery == 0) {
      dissipated_ += h * model_.dissipated_power(st.v());
      kinetic_ += h * 2.0 * model_.kinetic(st.v());
      const double elapsed = st.time() - t0_;
      const double hyst = elapsed > 0.0 ? (model_.hysteretic_dissipation() - hyst0_) / elapsed * kRateEvery * h : 0.0;
      rate_ = kinetic_ > 0.0 ? std::max(0.0, (dissipated_ + hyst) / kinetic_) : 0.0;
    }
    const Index n = b_.size();
    const double* a = st.a().data();
    for (Index k = 0; k < n; ++k) {
      peak_[k] = std::max(peak_[k], std::abs(st.u()[k]));
      b_[k] = (1.0 - w_) * a[k] + w_ * aprev_[k];
    }
    if (w_ != 0.0) aprev_ = st.a();
  }
  // Before the first step: generalized-alpha's blend needs a_n.
  template <class Stepper>
  void prime(const Stepper& st) {
    aprev_ = st.a();
  }
  // The order of the error rate in h, and of the global error: 2 (c3), 1 where a first-order scheme's c2
  // term leads.
  static double order(const ErrorConstants& c) { return c.c2 > 0.0 ? 1.0 : 2.0; }

 private:
  double horizon() const { return rate_ > 0.0 ? std::min(span_, kSqrt2 / rate_) : span_; }

  Model& model_;
  ErrorConstants c_;
  double w_, span_, floor_;
  Vector b_, aprev_, peak_;
  double rate_ = 0.0, dissipated_ = 0.0, kinetic_ = 0.0, hyst0_ = 0.0, t0_ = 0.0;
  std::int64_t accepted_ = 0;
};

}  // namespace observe

namespace detail {

// One attempt of an adaptive run (see the top of this file): the companion run on steps H chosen by
// the estimate's control at `control` (in place of tol), and the answer on H/2, H/2 in slot 1 beside
// it; `measured` gets the largest of the answer's error per DOF, |u - u_companion| / (2^p - 1) relative
// to the DOF's peak. The stepper ends at the answer's last accepted state.
template <class Stepper, class Observer>
Result adaptive_attempt(Stepper& st, double t_end, const SolveOptions& opt, double control, double& measured,
                        Observer&& observe) {
  using clock = std::chrono::steady_clock;
  using Model = std::decay_t<decltype(st.model())>;
  const double t_start = st.time();
  const double load_scale = std::isfinite(t_end) ? load_displacement_scale(st.model(), t_start, t_end) : 0.0;
  const auto start = clock::now();
  const Index n = st.size();
  const double dt0 = st.dt();
  const bool is_explicit = std::decay_t<decltype(st.scheme())>::is_explicit;
  const double max_dt = std::isnan(opt.max_dt) ? (is_explicit ? dt0 : 10.0 * dt0) : opt.max_dt;
  const double min_dt = std::isnan(opt.min_dt) ? 1e-6 * dt0 : opt.min_dt;
  auto& model = st.model();
  const effects::EffectSet* set = effect_set_of(model.nonlinear_force());
  const double energy_limit = detail::checked_run_options(opt, model, n);

  // The estimator: the scheme's error constants.
  const ErrorConstants constants = cached_error_constants(st.scheme());

  // The history grows as the run goes: its length is not known in advance.
  std::int64_t capacity = std::max<std::int64_t>(16, std::min<std::int64_t>(steps_to_reach(t_start, t_end, dt0) /
                                                                               opt.save_every + 2, 1 << 20));
  Result res;
  res.num_steps_requested = 0;
  RunObservers<Model> obs(res, model, set, opt, n, capacity, energy_limit, dt0);
  const double memory_limit = RunObservers<Model>::memory_limit(opt);
  const double row_bytes =
      RunObservers<Model>::row_bytes(opt, set, opt.dofs.empty() ? n : static_cast<Index>(opt.dofs.size()));

  double floor0 = 0.1 * load_scale;
  if (n > 0) floor0 = std::max(floor0, 0.1 * st.u().cwiseAbs().maxCoeff());
  observe::AdaptiveControl<Model> estimate(model, constants, error_blend(st.scheme()), n, t_end - t_start, floor0);
  const double order = observe::AdaptiveControl<Model>::order(constants);

  auto save = [&] {  // the history grows by doubling, under the memory limit
    if (obs.row == capacity) {
      const std::int64_t more = 2 * capacity;
      NVIB_CHECK(memory_limit <= 0.0 || static_cast<double>(more) * row_bytes <= memory_limit, "save_every, dofs",
                 "the saved history would need " + detail::fmt(static_cast<double>(more) * row_bytes / 1e9) +
                     " GB, more than the limit of " + detail::fmt(memory_limit / 1e9) +
                     " GB; save fewer states (a larger save_every) or fewer DOFs (dofs)");
      capacity = more;
      obs.resize(capacity);
    }
    obs.save(st);
  };
  obs.start(st);
  estimate.start(st);
  estimate.prime(st);

  // Events: the declared non-smooth points, their values at the step's start (from the committed
  // states there) and at a trial's end (from the same committed states).
  const Index nev = set != nullptr ? set->num_events() : 0;
  std::vector<double> committed0, g0(static_cast<size_t>(nev)), g1(static_cast<size_t>(nev));
  if (nev > 0) committed0.resize(static_cast<size_t>(set->state_size()));
  auto event_values = [&](std::vector<double>& g) {
    set->events(st.u().data(), st.v().data(), st.time(), committed0.data(), g.data());
  };
  // The earliest crossing of the trial just taken: its index and the fraction of the step at which the
  // values, linear in between, cross (2 if none).
  auto earliest_crossing = [&](Index& which) {
    double first = 2.0;
    which = -1;
    for (Index j = 0; j < nev; ++j) {
      const double a = g0[static_cast<size_t>(j)], b = g1[static_cast<size_t>(j)];
      if ((a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0)) {
        const double theta = a / (a - b);
        if (theta > 1e-6 && theta < first) {
          first = theta;
          which = j;
        }
      }
    }
    return first;
  };

  const Stats before = st.stats();
  std::string why;
  const double bound = detail::divergence_bound(opt, st, t_end - t_start, load_scale, why);
  ClockPoll poll(opt.observe_period);
  std::int64_t done = 0, checked = 0, rejected = 0, landed = 0;
  // The answer's error: |u - u_companion| / (2^p - 1) per DOF, its largest so far, and the DOF's peak.
  const double richardson = std::pow(2.0, st.scheme().order_u()) - 1.0;
  Vector companion(n), apart = Vector::Zero(n), top = st.u().cwiseAbs();
  bool answer_loaded = false;  // the stepper holds the answer's state (slot 1), not the companion's
  st.checkpoint(1);
  auto progress = [&] {
    const double span = t_end - t_start;
    return static_cast<std::int64_t>(std::floor(1000.0 * std::min(1.0, (st.time() - t_start) / span)));
  };
  auto finish = [&] {
    obs.resize(obs.row);
    res.max_residual = obs.max_residual;
    Vector error(n);
    const double floor = n > 0 ? 1e-3 * top.maxCoeff() : 0.0;
    for (Index k = 0; k < n; ++k) {
      const double scale = std::max(top[k], floor);
      error[k] = scale > 0.0 ? apart[k] / scale : (apart[k] > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
    }
    measured = n > 0 ? error.maxCoeff() : 0.0;
    if (opt.error_estimate) res.error_estimate = error;
    res.num_steps_requested = done;
    res.stats = st.stats();
    res.stats -= before;
    res.stats.num_steps = done;  // accepted: the stepper counts every step it took, the retaken ones too
    res.stats.num_check_steps = checked;
    res.stats.num_rejected_steps = rejected;
    res.stats.num_events = landed;
    res.stats.wall_time = std::chrono::duration<double>(clock::now() - start).count();
  };
  auto fail = [&](Status s, const std::string& message) {
    res.status = s;
    res.failure = Failure{};
    res.failure.status = s;
    res.failure.step = done + 1;
    res.failure.t = st.time();
    res.failure.message = message;
  };
  // One trial from the checkpoint in `slot`: a step of length h, checked for failure and divergence.
  // (The first trial from a fresh checkpoint starts from the state it holds: no rollback is needed.)
  bool fresh = false;
  auto trial = [&](int slot, double h, Status& s) {
    if (!fresh) st.rollback(slot);
    fresh = false;
    st.set_dt(h);
    s = st.step();
    if (s == Status::success && (!displacement_ok(st.u(), bound) || !rates_ok(st.v(), st.a()))) {
      res.failure = divergence(st, done + 1, bound, why);
      s = Status::diverged;
    } else if (s != Status::success) {
      res.failure = st.failure();
    }
  };

  const double tiny_time = 4.0 * std::numeric_limits<double>::epsilon();
  // After a successful trial of step_h from the checkpoint in `slot` (at time t, event values g0 there):
  // land on the earliest event inside it, retaking it until it ends past the event by round-off; step_h
  // becomes the step taken. True if it landed.
  auto land = [&](int slot, double t, double& step_h, Status& s) {
    event_values(g1);
    Index which = -1;
    earliest_crossing(which);
    if (which < 0) return false;
    const size_t j = static_cast<size_t>(which);
    double lo = 0.0, hi = step_h, glo = g0[j], ghi = g1[j];
    int side = 0;
    bool at_hi = true;
    for (int it = 0; it < 200 && hi - lo > tiny_time * (std::abs(t) + hi); ++it) {
      double x = lo + (hi - lo) * (glo / (glo - ghi));
      if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
      trial(slot, x, s);
      if (s != Status::success) return false;
      event_values(g1);
      ++rejected;
      Index other = -1;
      earliest_crossing(other);
      if (other >= 0 && other != which) {  // another event comes first: land on that one instead
        hi = x;
        ghi = g1[static_cast<size_t>(other)];
        which = other;
        glo = g0[static_cast<size_t>(other)];
        at_hi = true;
        side = 0;
        continue;
      }
      const double gx = g1[static_cast<size_t>(which)];
      if (gx == 0.0 || (gx > 0.0) != (g0[static_cast<size_t>(which)] > 0.0)) {  // past it (or on it)
        hi = x;
        ghi = gx;
        at_hi = true;
        if (gx == 0.0) break;
        if (side == +1) glo *= 0.5;  // Illinois: the end that stays is halved
        side = +1;
      } else {
        lo = x;
        glo = gx;
        at_hi = false;
        if (side == -1) ghi *= 0.5;
        side = -1;
      }
    }
    if (!at_hi) {
      trial(slot, hi, s);
      ++rejected;
      if (s != Status::success) return false;
    }
    step_h = hi;
    return true;
  };

  double h = std::min(dt0, max_dt);
  try {
    while (st.time() < t_end) {
      const double t = st.time();
      // The last steps: end on t_end, without a sliver of a step before it.
      const double remaining = t_end - t;
      if (remaining <= tiny_time * std::max(1.0, std::abs(t_end))) break;
      double step_h = h;
      if (step_h >= remaining) step_h = remaining;
      else if (step_h > 0.5 * remaining) step_h = 0.5 * remaining;
      st.checkpoint();
      fresh = true;
      if (nev > 0) {
        set->get_state(committed0.data());
        event_values(g0);
      }
      if (opt.reject_every > 0 && (checked + 1) % opt.reject_every == 0) {  // a detour that must leave no trace
        Status s;
        trial(0, std::min(2.0 * step_h, remaining), s);
        ++rejected;
      }
      Status s = Status::success;
      double ratio = 0.0;
      for (;;) {
        trial(0, step_h, s);
        if (s == Status::success) {
          ratio = estimate.measure(st, step_h, control);
          if (!(ratio <= 2.0) && step_h > min_dt) {  // too inaccurate (or NaN): shorter
            ++rejected;
            const double shrink = std::isfinite(ratio) ? std::pow(0.8 / ratio, 1.0 / order) : 0.2;
            step_h = std::max(min_dt, step_h * std::max(0.2, shrink));
            continue;
          }
          if (!(ratio <= 2.0)) {
            fail(Status::diverged,
                 "the step fell to min_dt = " + detail::fmt(min_dt) + " at t = " + detail::fmt(t) +
                     " and the error estimate still exceeds tol = " + detail::fmt(opt.tol) + " (" +
                     detail::fmt(ratio) + " x what tol allows there): loosen tol or lower min_dt");
            s = Status::diverged;
          }
          break;
        }
        if (s == Status::diverged && res.failure.dof >= 0 && std::isfinite(st.u()[res.failure.dof])) break;  // beyond the bound
        if (step_h <= min_dt) {
          res.failure.message += " (at the smallest step min_dt = " + detail::fmt(min_dt) + ")";
          break;
        }
        ++rejected;  // a failed Newton iteration or a non-finite state: shorter
        step_h = std::max(min_dt, 0.25 * step_h);
      }
      const double control_h = step_h;  // the step the error control chose (a landing may shorten it)
      if (s == Status::success && nev > 0 && land(0, t, step_h, s)) estimate.measure(st, step_h, control);  // the step taken
      if (s != Status::success) {  // the companion failed: the run ends at the answer's last state
        res.status = s;
        break;
      }
      ++checked;
      estimate.accept(st, step_h);
      // The answer: steps of half the companion's, from its own state (slot 1), to the companion's end;
      // it lands on its own events too (slot 3 keeps its step's start).
      const double t_next = st.time(), half_h = 0.5 * step_h;
      companion = st.u();
      st.checkpoint(0);
      st.rollback(1);
      for (;;) {
        const double ta = st.time(), left = t_next - ta;
        if (left <= tiny_time * std::max(1.0, std::abs(t_next))) break;
        double hh = left < 2.0 * half_h ? (left <= half_h ? left : 0.5 * left) : half_h;  // no sliver at the end
        if (std::abs(hh - half_h) <= 1e-9 * half_h) hh = half_h;  // the companion's end, up to round-off
        if (nev > 0) {  // without events a failed step fails the run: there is nothing to retake
          st.checkpoint(3);
          set->get_state(committed0.data());
          event_values(g0);
        }
        fresh = true;
        trial(3, hh, s);
        if (s == Status::success && nev > 0 && land(3, ta, hh, s)) ++landed;
        if (s == Status::success) {
          if (obs.energy) obs.energy->set_dt(hh);
          if (!obs.accepted(st, done + 1, res.failure)) s = res.failure.status;
        }
        if (s != Status::success) break;
        ++done;
        if (obs.peaks) obs.peaks->update(st);
        if (done % opt.save_every == 0 || !(st.time() < t_end)) save();
      }
      if (s != Status::success) {  // the answer failed (or collapsed): the stepper holds its state
        res.status = s;
        if (s == Status::collapsed) {  // the state it collapsed in (save() grows the history if need be)
          save();
          if (obs.peaks) obs.peaks->update(st);
        }
        answer_loaded = true;
        break;
      }
      // The answer's error: the difference from the companion, whose error is 2^p times the answer's.
      for (Index k = 0; k < n; ++k) {
        apart[k] = std::max(apart[k], std::abs(st.u()[k] - companion[k]) / richardson);
        top[k] = std::max(top[k], std::abs(st.u()[k]));
      }
      st.checkpoint(1);
      st.rollback(0);
      // The next step: the one that meets 0.8 tol, within [0.2, 2] of this one and [min_dt, max_dt].
      const double grow = ratio > 0.0 ? std::pow(0.8 / ratio, 1.0 / order) : 2.0;
      h = std::min(max_dt, std::max(min_dt, control_h * std::min(2.0, std::max(0.2, grow))));
      // A new length costs an implicit scheme a factorisation, and a two-level explicit one a rescaled
      // history (whose extrapolation error adds up over many small changes): lengthen by 25 % or more.
      if (h > control_h && h < 1.25 * control_h) h = control_h;
      if (poll.tick()) {
        observe(progress(), 1000);
        poll_interrupt();
      }
    }
    if (!answer_loaded) st.rollback(1);
    answer_loaded = true;
    // The history ends with the last accepted state.
    if (res.status == Status::success && (obs.row == 0 || res.t[obs.row - 1] != st.time())) save();
  }
#if defined(__GLIBCXX__)
  catch (abi::__forced_unwind&) {
    throw;
  }
#endif
  catch (...) {
    if (!answer_loaded) st.rollback(1);
    if (!opt.keep_partial) throw;
    finish();
    res.status = Status::interrupted;
    res.failure = Failure{};
    res.failure.status = Status::interrupted;
    res.failure.step = done + 1;
    res.failure.t = obs.row > 0 ? res.t[obs.row - 1] : st.time();
    res.failure.message = "interrupted after step " + std::to_string(done) + " at t = " + detail::fmt(st.time()) +
                          "; the history is saved up to t = " +
                          (obs.row > 0 ? detail::fmt(res.t[obs.row - 1]) : std::string("the start"));
    throw PartialRun{std::move(res), std::current_exception()};
  }
  observe(progress(), 1000);
  finish();
  if (res.status != Status::success && res.status != Status::collapsed && opt.throw_on_failure) throw_failure(res.failure);
  return res;
}

}  // namespace detail

template <class Stepper, class Observer>
Result integrate_adaptive(Stepper& st, double t_end, const SolveOptions& opt, Observer&& observe) {
  const double t_start = st.time();
  steps_to_reach(t_start, t_end, st.dt());  // the checks of t_end and dt
  NVIB_CHECK(opt.tol > 0.0 && opt.tol < 1.0, "tol", "must lie in (0, 1) (an error relative to each DOF's peak), got " +
                                                         detail::fmt(opt.tol));
  NVIB_CHECK(opt.reject_every >= 0, "reject_every", "must be >= 0, got " + std::to_string(opt.reject_every));
  const double dt0 = st.dt();
  const bool is_explicit = std::decay_t<decltype(st.scheme())>::is_explicit;
  const double max_dt = std::isnan(opt.max_dt) ? (is_explicit ? dt0 : 10.0 * dt0) : opt.max_dt;
  const double min_dt = std::isnan(opt.min_dt) ? 1e-6 * dt0 : opt.min_dt;
  NVIB_CHECK(max_dt > 0.0 && std::isfinite(max_dt), "max_dt", "must be > 0 and finite, got " + detail::fmt(max_dt));
  NVIB_CHECK(min_dt > 0.0 && min_dt <= max_dt, "min_dt",
             "must be > 0 and <= max_dt (" + detail::fmt(max_dt) + "), got " + detail::fmt(min_dt));
  NVIB_CHECK(cached_error_constants(st.scheme()).available, "tol",
             "the scheme has no error estimate to control its step with (PreciseIntegration is exact on linear "
             "modes; its corrector's local estimate under-states its error on nonlinear ones and is not used)");

  // The companion's control starts at kFirstControl tol: its error is then near 4x the estimate's
  // target, the answer's a quarter of that. A run whose measured error exceeds tol is redone from the
  // start with the control scaled by 0.7 tol / measured (the error is near proportional to it). (Two
  // ways to redo less were tried and dropped: stopping an attempt once its error exceeds tol, with the
  // error carried on to t_end in proportion to time, made as many restarts on the vehicle and more on
  // the oscillators; a control that follows the measured error during the run oscillated and missed
  // tol up to 11x.)
  constexpr double kFirstControl = 2.0;
  constexpr int kMaxRestarts = 3;
  const auto start = std::chrono::steady_clock::now();
  const Stats before = st.stats();
  st.checkpoint(2);
  double control = kFirstControl * opt.tol;
  for (int restarts = 0;; ++restarts) {
    double measured = 0.0;
    Result res = detail::adaptive_attempt(st, t_end, opt, control, measured, observe);
    if (res.status != Status::success || !(measured > opt.tol) || restarts == kMaxRestarts) {
      const Stats mine = res.stats;
      res.stats = st.stats();
      res.stats -= before;  // every attempt's work
      res.stats.num_steps = mine.num_steps;
      res.stats.num_check_steps = mine.num_check_steps;
      res.stats.num_rejected_steps = mine.num_rejected_steps;
      res.stats.num_events = mine.num_events;
      res.stats.num_restarts = restarts;
      res.stats.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return res;
    }
    control *= std::max(0.05, std::min(0.7, 0.7 * opt.tol / measured));
    st.rollback(2);
  }
}

}  // namespace nvib
