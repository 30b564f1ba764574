// Corrected explicit method of double time steps (CEMDTS), as reconstructed
// from the properties stated in Yang et al. 2017 (J. Cent. South Univ.
// 24:1090, section 3.1; the equations were lost from the available text):
//   u_{n+1} = u_n + h v_n + h^2 [(1/2 + eta) a_n - eta a_{n-1}]
//   v*      = v_n + h [(1 + eta) a_n - eta a_{n-1}]           (predictor)
//   a_{n+1} = a(u_{n+1}, v*, t_{n+1})
//   v_{n+1} = v_n + h [(1/2 - eta) a_{n+1} + (1/2 + 2 eta) a_n - eta a_{n-1}]
//   a_{-1}  = a_0
// The original formulas were not available. The reconstruction rests on what
// the paper states of the method: explicit, built on two acceleration levels
// (a_n and a_{n-1}, the "double time steps") with eta weighting the older one,
// a predicted velocity in the force and a corrected one after it, and a
// stability interval no smaller than LCDM's. Of the schemes of this stencil,
// this is the one family whose displacements are the central-difference ones
// for every eta (so the undamped stability limit is omega h < 2); eta = 0 is
// LCDM, eta = 1/2 is Zhai(1/2, 1/2). At eta = 1/12 the velocity corrector is
// third order locally (one-step error O(h^4)); globally the velocity stays
// second order, being built from second-order displacements (measured on the
// hardening oscillator: order 1.99, its error 7 % below LCDM's).
#pragma once

#include <string>

#include "scheme.hpp"
#include "stepper.hpp"

namespace nvib {

template <class ModelT>
class CEMDTSStepper;

struct CEMDTS {
  static constexpr const char* name = "CEMDTS";
  static constexpr const char* key = "cemdts";
  static constexpr const char* doc =
      "Corrected explicit method of double time steps, as reconstructed from the properties stated in "
      "Yang et al. 2017 (the original formulas were not available). Central-difference displacements for "
      "every eta; the velocity corrector weighs a_{n-1} by eta (0: LCDM, 1/2: Zhai(1/2, 1/2)); locally third "
      "order in v at eta = 1/12, globally second order.";
  static constexpr bool is_explicit = true;
  double eta = 0.45;

  explicit CEMDTS(double eta_ = 0.45) : eta(eta_) { validate(); }

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.eta, param::real("eta", "weight of a_{n-1} in the velocity (0: LCDM, 1/2: Zhai)").range(0.0, 1.0));
  }
  void validate() const { param::check_ranges(*this); }
  std::string label() const { return "CEMDTS(" + detail::short_number(eta) + ")"; }
  int order_u() const { return 2; }
  int order_v() const { return 2; }
  template <class M>
  using stepper = CEMDTSStepper<M>;
};

template <class ModelT>
class CEMDTSStepper : public TwoLevelStepper<ModelT> {
  using Base = TwoLevelStepper<ModelT>;
  NVIB_STEPPER_STATE(Base);
  using Base::aprev_;

 public:
  CEMDTSStepper(const CEMDTS& scheme, ModelT model, double h) : Base(std::move(model), h), scheme_(scheme) {
    anew_.setZero(this->size());
    vstar_.setZero(this->size());
  }

  void initialize(double t0, const Vector& u0, const Vector& v0) {
    this->start_two_level(t0, u0, v0);
  }

  Status step() {
    const double t1 = this->next_time();
    const double eta = scheme_.eta, h2 = h_ * h_, h = h_;
    const double cu = (0.5 + eta) * h2, cp = eta * h2;                                // u
    const double vn = (0.5 - eta) * h_, va = (0.5 + 2.0 * eta) * h_, vp = eta * h_;  // v
    const Index n = u_.size();
    if (stream_) return step_streamed(t1, h, cu, cp, vn, va, vp);
    if (model_.uses_velocity()) {
      drift_predict(n, u_.data(), vstar_.data(), v_.data(), a_.data(), aprev_.data(), h, cu, cp, (1.0 + eta) * h_, vp);
      model_.acceleration(u_, vstar_, t1, anew_, stats_);
    } else {
      drift(n, u_.data(), v_.data(), a_.data(), aprev_.data(), h, cu, cp);
      model_.acceleration(u_, v_, t1, anew_, stats_);
    }
    kick(n, v_.data(), anew_.data(), a_.data(), aprev_.data(), vn, va, vp);
    aprev_.swap(a_);  // a_{n-1} <- a_n
    a_.swap(anew_);   // a_n <- a_{n+1}
    return this->advance();
  }

  const CEMDTS& scheme() const { return scheme_; }

  // The same updates, block by block along the DOFs around the force (streamed_step); out of line, as
  // CentralDifference's.
  NVIB_NOINLINE Status step_streamed(double t1, double h, double cu, double cp, double vn, double va, double vp) {
    double *u = u_.data(), *v = v_.data(), *a = a_.data(), *ap = aprev_.data(), *an = anew_.data(), *vs = vstar_.data();
    const bool velocity = model_.uses_velocity();
    const double ca = (1.0 + scheme_.eta) * h_;
    this->streamed_step(
        velocity ? vs : v, t1, an,
        [=](Index p, Index q) {
          if (velocity)
            drift_predict(q - p, u + p, vs + p, v + p, a + p, ap + p, h, cu, cp, ca, vp);
          else
            drift(q - p, u + p, v + p, a + p, ap + p, h, cu, cp);
        },
        [=](Index p, Index q) { kick(q - p, v + p, an + p, a + p, ap + p, vn, va, vp); });
    aprev_.swap(a_);
    a_.swap(anew_);
    return this->advance();
  }

  // The step's loops on non-overlapping arrays, unrolled up to 8 DOFs (see CentralDifference): the
  // same operations in the same order as u += h v + cu a - cp a_prev, v* = v + ca a - vp a_prev and
  // v += vn a_new + va a - vp a_prev.
  NVIB_ALWAYS_INLINE static void drift(Index n, double* __restrict u, const double* __restrict v, const double* __restrict a,
                    const double* __restrict ap, double h, double cu, double cp) {
    detail::for_each_index(n, [=](Index i) { u[i] += h * v[i] + cu * a[i] - cp * ap[i]; });
  }
  NVIB_ALWAYS_INLINE static void drift_predict(Index n, double* __restrict u, double* __restrict vs, const double* __restrict v,
                            const double* __restrict a, const double* __restrict ap, double h, double cu, double cp,
                            double ca, double vp) {
    detail::for_each_index(n, [=](Index i) {
      u[i] += h * v[i] + cu * a[i] - cp * ap[i];
      vs[i] = v[i] + ca * a[i] - vp * ap[i];
    });
  }
  NVIB_ALWAYS_INLINE static void kick(Index n, double* __restrict v, const double* __restrict an, const double* __restrict a,
                   const double* __restrict ap, double vn, double va, double vp) {
    detail::for_each_index(n, [=](Index i) { v[i] += vn * an[i] + va * a[i] - vp * ap[i]; });
  }

  // State: [u; v; a; a_{n-1}; internal variables of the laws with memory] (TwoLevelStepper).

 private:
  CEMDTS scheme_;
  Vector anew_, vstar_;
};

}  // namespace nvib
