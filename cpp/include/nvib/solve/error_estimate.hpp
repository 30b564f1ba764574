// The error estimate every run carries (SolveOptions::error_estimate, on by default): an estimate of
// max_t |u_i(t) - u_i,exact(t)| / max_t |u_i(t)| for every DOF, from the accepted steps alone.
//
// The construction. A scheme of global order 2 integrates a linear mode of frequency w with a phase
// (and amplitude) error per step of c3 (w h)^3 + O(h^4), c3 the scheme's error constant: the distance
// of its principal eigenvalue from exp(i w h) over (w h)^3 (error_constants() measures it on the
// scheme's own stepper). The numerical solution of mode j is then the exact one shifted in time by
// c3 h^2 w_j^2 t, so its error is c3 h^2 w_j^2 t v_j(t), and summed over the modes with their signs
//     e(t) = c3 h^2 t sum_j w_j^2 v_j(t) = -c3 h^2 t da/dt(t)
// (free vibration: d3q/dt3 = -w^2 dq/dt). That needs no modes: the jerk da/dt of each DOF is the
// difference of the accelerations of two accepted steps over h. Summing absolute local errors instead
// would lose the signs of the modes and under-estimate a many-mode response (by 3x on the six-storey
// building); the jerk keeps them.
//
// Memory. The time t in e(t) is the age of the motion. A damped motion forgets: energy put in decays
// at the rate lambda = (dissipated power) / (2 x kinetic energy), averaged over the run so far
// (viscous dampers and the hysteretic dissipation of the laws with memory both count). The age tau
// follows tau' = 1 - tau lambda / sqrt(2): it grows with t in an undamped run and saturates at
// sqrt(2)/lambda = 1/(sqrt(2) zeta w), the RMS age of a stationary randomly forced oscillator.
//     estimate_i = c3 h^2 max_t (tau(t) |da_i/dt(t)|) / max_t |u_i(t)|
// plus, for a scheme of order 1 (c2 > 0: numerical damping of order w h), c2 h max_t (tau |a_i|) / peak.
//
// Generalized-alpha's a_{n+1} carries a sawtooth of period 2h when alpha_m > 0 (its equation holds
// at the alpha point); the estimate differentiates the alpha-point acceleration
// (1 - alpha_m) a_{n+1} + alpha_m a_n instead, which has none.
//
// The precise integration method is exact on linear modes, so none of the above applies: its error is
// the interpolation of the nonlinear remainder r within each step. The stepper follows it
// (PreciseIntegrationStepper::track_error): each step's local error is W0 C(m) D^m r, the m-th backward
// difference of the remainders times the interpolation's error constant, mapped to [u; v] by the integral
// of the exponential; the local errors are propagated by the exponential itself (blocks of 8 steps with
// their mean local error), so they keep their signs and decay where the model is damped.
//     estimate_i = max_t |e_u,i(t)| / max_t |u_i(t)|
// Near a kink of r (a yield point, a contact, a record's sample) the differences of successive steps
// alternate and would cancel in a block's sum, while the errors they stand for do not: a block adds the
// sizes of its steps' local errors, with the sign of their sum. The first steps, whose predictor has
// fewer points than their corrector, add the corrector's weight of the new point times the difference of
// r at the predicted and at the final state.
// The propagation is the linear part's (the tangent at rest): the phase drift of a strongly nonlinear
// motion's amplitude-dependent frequency is not in it. Measured (benchmarks/results/error_estimate.md):
// within a factor 3 on the building, the pendulum of small amplitude and the hardening oscillator over
// 0.3 s, 3-5x over on the inelastic building (its bilinear kinks), 0.02-0.06 of the truth on the pendulum
// near the top (0.05 on the hardening oscillator over 1 s); the vehicle's runs, 10-95 % off, warn. It
// costs 12 % of a PIM run on the six-storey building, whose steps are short (0.2 us), and O(n) + O(n^2) / 8
// per step against PIM's O(n^2).
//
// What it is not: an estimate of the error of an effect event (a contact opening, a yield point)
// beyond what the smooth formula sees, nor of an unconverged Newton step (Result::max_residual says
// that). The committed comparison with the true error is benchmarks/results/error_estimate.md.
#pragma once

#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <utility>

#include <Eigen/Eigenvalues>

#include "../base/loops.hpp"
#include "../base/types.hpp"
#include "../model/model.hpp"
#include "../schemes/scheme.hpp"
#include "options.hpp"

namespace nvib {

// Leading error of a scheme's principal eigenvalue on u'' + w^2 u = 0 at Omega = w h:
// |lambda - exp(i Omega)| = c2 Omega^2 + c3 Omega^3 + O(Omega^4). c2 > 0 only for a first-order scheme.
struct ErrorConstants {
  double c2 = 0.0, c3 = 0.0;
  // False where the scheme is exact on linear modes (the precise integration method): this estimate
  // then says nothing (PIM follows its own error instead, below).
  bool available = true;
};

namespace detail {
template <class S, class = void>
struct has_alpha_m : std::false_type {};
template <class S>
struct has_alpha_m<S, std::void_t<decltype(std::declval<const S&>().alpha_m)>> : std::true_type {};

// The principal eigenvalue's distance from exp(i Omega), one step of the scheme's stepper on a unit oscillator.
template <class Scheme>
double principal_error(const Scheme& scheme, double omega) {
  using Linear = decltype(make_linear_model(Mass::diagonal(Vector::Ones(1)), Matrix()));
  typename Scheme::template stepper<Linear> st(
      scheme, make_linear_model(Mass::diagonal(Vector::Ones(1)), Matrix::Constant(1, 1, omega * omega)), 1.0);
  st.initialize(0.0, Vector::Zero(1), Vector::Zero(1));
  const Index m = st.state_size();
  Matrix A(m, m);
  Vector e = Vector::Zero(m);
  for (Index j = 0; j < m; ++j) {
    e[j] = 1.0;
    st.set_state(0.0, e);
    st.step();
    A.col(j) = st.state();
    e[j] = 0.0;
  }
  const std::complex<double> exact = std::polar(1.0, omega);
  Eigen::EigenSolver<Matrix> es(A, false);
  double best = std::numeric_limits<double>::infinity();
  for (Index k = 0; k < m; ++k) best = std::min(best, std::abs(es.eigenvalues()[k] - exact));
  return best;
}
}  // namespace detail

// The weight of a_n in the acceleration the estimate differentiates (alpha_m for generalized-alpha, else 0).
template <class Scheme>
double error_blend(const Scheme& scheme) {
  if constexpr (detail::has_alpha_m<Scheme>::value) return scheme.alpha_m;
  (void)scheme;
  return 0.0;
}

// c2 and c3 from the principal eigenvalue at Omega = 0.02 and 0.04 (Omega^2 and Omega^3 fitted; the
// O(Omega^4) remainder changes c3 by under 1 % for the schemes of the registry).
template <class Scheme>
ErrorConstants error_constants(const Scheme& scheme) {
  constexpr double w1 = 0.02, w2 = 0.04;
  const double e1 = detail::principal_error(scheme, w1), e2 = detail::principal_error(scheme, w2);
  // e = c2 w^2 + c3 w^3 at both points
  const double det = w1 * w1 * w2 * w2 * w2 - w2 * w2 * w1 * w1 * w1;
  ErrorConstants c;
  c.c2 = (e1 * w2 * w2 * w2 - e2 * w1 * w1 * w1) / det;
  c.c3 = (w1 * w1 * e2 - w2 * w2 * e1) / det;
  // A second-order scheme's c2 is round-off; a first-order one's is at least 1e-4 (gamma - 1/2 >= 2e-4).
  if (std::abs(c.c2) < 1e-6) c.c2 = 0.0;
  c.c3 = std::abs(c.c3);
  c.available = c.c2 > 0.0 || c.c3 > 1e-6;
  return c;
}

// error_constants() once per scheme and thread: a batch of short runs of one scheme (an inelastic
// spectrum's) solves the two small eigenproblems once, not once a run.
template <class Scheme>
const ErrorConstants& cached_error_constants(const Scheme& scheme) {
  thread_local std::unordered_map<std::string, ErrorConstants> cache;
  const std::string key = scheme_repr(scheme);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, error_constants(scheme)).first;
  return it->second;
}

namespace observe {

// Per DOF, an error relative to its peak (a DOF whose peak is under 1e-3 of the largest is measured
// against 1e-3 of the largest, as the references measure it).
inline Vector relative_to_peaks(const Vector& error, const Vector& peak) {
  const Index n = peak.size();
  Vector out(n);
  const double floor = n > 0 ? 1e-3 * peak.maxCoeff() : 0.0;
  for (Index k = 0; k < n; ++k) {
    const double scale = std::max(peak[k], floor), e = error[k];
    out[k] = scale > 0.0 ? e / scale : (e > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
  }
  return out;
}

// Steppers that keep a_{n-1} (previous_a()).
template <class S, class = void>
struct keeps_previous_a : std::false_type {};
template <class S>
struct keeps_previous_a<S, std::void_t<decltype(std::declval<const S&>().previous_a())>> : std::true_type {};

// Estimates every DOF's error relative to its peak (see the top of this file) into Result::error_estimate.
template <class Model>
class ErrorEstimate {
 public:
  // Steps between two samples of the dissipation rate (a product with C and the mass per sample).
  static constexpr std::int64_t kRateEvery = 64;
  // Steps between two samples of the jerk and the peaks (every step for generalized-alpha, whose
  // alpha-point acceleration needs each a_n). The maxima over a run are taken over every 8th step, so
  // that the estimate costs about one pass over memory per step on average: 8 % of an LCDM run on a 10^5-DOF chain
  // (benchmarks/results/error_estimate.md, which compares the estimate so sampled with the true error).
  // Over a run of many periods the sampled maxima come close to the maxima over every step; a short
  // event (an impact lasting a few steps) may fall between two samples.
  static constexpr std::int64_t kSampleEvery = 8;

  ErrorEstimate(Result& res, Model& model, const ErrorConstants& c, double blend, double h, Index n)
      : res_(res), model_(model), c_(c), w_(blend), h_(h) {
    jerk_.setZero(n);
    level_.setZero(n);
    peak_.setZero(n);
    prev_.resize(n);
    if (w_ != 0.0) blended_.resize(n);
  }
  template <class Stepper>
  void start(const Stepper& st) {
    prev_ = st.a();
    if (w_ != 0.0) blended_ = st.a();
    peak_ = st.u().cwiseAbs();
    hyst0_ = model_.hysteretic_dissipation();
  }
  // The age of the motion at step i: tau' = 1 - tau / T over the steps since the last call, T = sqrt(2) /
  // rate (rate: the dissipation rate, sampled every kRateEvery steps; tau grows as t where it is 0).
  template <class Stepper>
  void age_to(const Stepper& st, std::int64_t i) {
    if (i / kRateEvery != aged_ / kRateEvery) {
      dissipated_ += model_.dissipated_power(st.v());
      kinetic_ += 2.0 * model_.kinetic(st.v());
      const double hyst = (model_.hysteretic_dissipation() - hyst0_) / (h_ * kRateEvery);
      rate_ = kinetic_ > 0.0 ? std::max(0.0, (dissipated_ + hyst) / kinetic_) : 0.0;
    }
    const double span = h_ * static_cast<double>(i - aged_);
    aged_ = i;
    if (rate_ > 0.0) {
      const double T = kSqrt2 / rate_;
      // exp(-span / T) kept while span and T do not change (generalized-alpha ages every step)
      if (!(span == decay_span_ && T == decay_T_)) {
        decay_ = std::exp(-span / T);
        decay_span_ = span;
        decay_T_ = T;
      }
      age_ = T + (age_ - T) * decay_;
    } else {
      age_ += span;
    }
  }
  // jerk, level and peak of every DOF at a sample, in one pass: now(k) the differentiated acceleration
  // at this step, before(k) at the step before; then keep(k, now(k)) (what the next sample reads).
  template <class Stepper, class Now, class Before, class Keep>
  void sample(const Stepper& st, Now now, Before before, Keep keep) {
    const double tau = age_;
    const double* __restrict u = st.u().data();
    double *__restrict j = jerk_.data(), *__restrict l = level_.data(), *__restrict pk = peak_.data();
    auto pass = [&](auto with_level) {
      detail::for_each_index(jerk_.size(), [&](Index k) {  // (unrolled up to 8 DOFs)
        const double x = now(k);
        j[k] = std::max(j[k], tau * std::abs(x - before(k)));
        if constexpr (decltype(with_level)::value) l[k] = std::max(l[k], tau * std::abs(x));
        pk[k] = std::max(pk[k], std::abs(u[k]));
        keep(k, x);
      });
    };
    if (c_.c2 > 0.0)
      pass(std::true_type{});
    else
      pass(std::false_type{});
  }
  template <class Stepper>
  void step(const Stepper& st, std::int64_t i) {
    const std::int64_t phase = i % kSampleEvery;
    const Index n = prev_.size();
    const double* a = st.a().data();
    double* p = prev_.data();
    if (w_ == 0.0) {
      // Sampled: a_{n-1} is kept at the step before each sample (or read from the stepper that keeps
      // it), the jerk and the peak taken at the sample.
      const double* kept = previous_a(st);
      if (phase == kSampleEvery - 1 && kept == nullptr) {
        for (Index k = 0; k < n; ++k) p[k] = a[k];
      } else if (phase == 0) {
        age_to(st, i);
        const double* before = kept != nullptr ? kept : p;
        sample(st, [a](Index k) { return a[k]; }, [before](Index k) { return before[k]; }, [](Index, double) {});
      }
      return;
    }
    age_to(st, i);
    // Every step: the alpha-point acceleration x sampled against the one of the step before (b), then
    // x kept in b and a_n in p for the next step.
    double* b = blended_.data();
    const double w = w_;
    sample(
        st, [a, p, w](Index k) { return (1.0 - w) * a[k] + w * p[k]; }, [b](Index k) { return b[k]; },
        [a, p, b](Index k, double x) {
          b[k] = x;
          p[k] = a[k];
        });
  }
  // a_{n-1} from a stepper that keeps it (previous_a(), null where it does not at this step), else null.
  template <class Stepper>
  static const double* previous_a(const Stepper& st) {
    if constexpr (keeps_previous_a<Stepper>::value)
      return st.previous_a();
    else
      return nullptr;
  }
  // Into the result: per DOF, relative to its peak.
  void finish() { res_.error_estimate = relative_to_peaks(c_.c3 * h_ * jerk_ + c_.c2 * h_ * level_, peak_); }

 private:
  static constexpr double kSqrt2 = 1.41421356237309504880;
  Result& res_;
  Model& model_;
  ErrorConstants c_;
  double w_, h_;
  Vector prev_, blended_, jerk_, level_, peak_;
  double age_ = 0.0, rate_ = 0.0, dissipated_ = 0.0, kinetic_ = 0.0, hyst0_ = 0.0;
  double decay_ = 1.0, decay_span_ = std::numeric_limits<double>::quiet_NaN(), decay_T_ = decay_span_;  // age_to()'s
  std::int64_t aged_ = 0;  // the step the age is of
};

// A stepper that follows its own error (the precise integration method: track_error, error_u).
template <class S, class = void>
struct tracks_own_error : std::false_type {};
template <class S>
struct tracks_own_error<S, std::void_t<decltype(std::declval<S&>().track_error(true)),
                                       decltype(std::declval<const S&>().error_u())>> : std::true_type {};

// Result::error_estimate from a stepper's own error: max |e_u,i| over the run over max |u_i|. Its calls
// do nothing for a stepper that does not follow its error (the loop holds one only for one that does).
class OwnErrorEstimate {
 public:
  OwnErrorEstimate(Result& res, Index n) : res_(res) {
    worst_.setZero(n);
    peak_.setZero(n);
  }
  template <class Stepper>
  void start(Stepper& st) {
    if constexpr (tracks_own_error<Stepper>::value) {
      st.track_error(true);
      peak_ = st.u().cwiseAbs();
      seen_ = st.error_updates();
    }
  }
  template <class Stepper>
  void step(const Stepper& st, std::int64_t) {
    if constexpr (tracks_own_error<Stepper>::value) {
      // Sampled where the error is updated (every kErrorBlock steps), as ErrorEstimate samples its peaks.
      if (st.error_updates() == seen_) return;
      seen_ = st.error_updates();
      peak_ = peak_.cwiseMax(st.u().cwiseAbs());
      worst_ = worst_.cwiseMax(st.error_u().cwiseAbs());
    }
  }
  template <class Stepper>
  void finish(Stepper& st) {
    if constexpr (tracks_own_error<Stepper>::value) {
      st.flush_error();
      peak_ = peak_.cwiseMax(st.u().cwiseAbs());
      worst_ = worst_.cwiseMax(st.error_u().cwiseAbs());
      st.track_error(false);
      res_.error_estimate = relative_to_peaks(worst_, peak_);
    }
  }

 private:
  Result& res_;
  Vector worst_, peak_;
  std::int64_t seen_ = 0;
};

}  // namespace observe
}  // namespace nvib
