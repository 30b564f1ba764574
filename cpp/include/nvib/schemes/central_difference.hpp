// Leapfrog central difference method (LCDM).
//
// velocity = synchronized (default):
//   u_{n+1} = u_n + h v_n + h^2/2 a_n
//   v*      = v_n + h a_n                (predictor, only if forces use velocity)
//   a_{n+1} = a(u_{n+1}, v*, t_{n+1})
//   v_{n+1} = v_n + h/2 (a_n + a_{n+1})
// velocity = half_step: the classic leapfrog that carries v_{n+1/2} = v_{n-1/2} + h a_n
// and reports it as the velocity at t_{n+1}. Velocity-dependent forces get
// v_{n+1/2} + h/2 a_n: the lagged v_{n+1/2} itself would make the scheme first
// order with damping. Both variants give the same displacements.
#pragma once

#include <array>
#include <string>

#include "scheme.hpp"
#include "stepper.hpp"

namespace nvib {

template <class ModelT>
class CentralDifferenceStepper;

struct CentralDifference {
  static constexpr const char* name = "CentralDifference";
  static constexpr const char* key = "lcdm";
  static constexpr const char* doc =
      "Leapfrog central difference method (LCDM). velocity='synchronized' reports v_{n+1} "
      "(second order); 'half_step' carries and reports v_{n+1/2} (first order against v(t_{n+1})).";
  static constexpr bool is_explicit = true;
  enum class Velocity { synchronized, half_step };
  Velocity velocity = Velocity::synchronized;

  explicit CentralDifference(Velocity vel = Velocity::synchronized) : velocity(vel) {}

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.velocity, param::choice("velocity", "velocity carried and reported", {"synchronized", "half_step"}));
  }
  void validate() const {}
  std::string label() const { return velocity == Velocity::synchronized ? "LCDM" : "LCDM (half-step v)"; }
  int order_u() const { return 2; }
  int order_v() const { return velocity == Velocity::synchronized ? 2 : 1; }
  template <class M>
  using stepper = CentralDifferenceStepper<M>;
};

template <class ModelT>
class CentralDifferenceStepper : public StepperBase<ModelT> {
  using Base = StepperBase<ModelT>;
  NVIB_STEPPER_STATE(Base);

 public:
  CentralDifferenceStepper(const CentralDifference& scheme, ModelT model, double h)
      : Base(std::move(model), h), scheme_(scheme) {
    anew_.setZero(this->size());
    vstar_.setZero(this->size());
  }

  void initialize(double t0, const Vector& u0, const Vector& v0) {
    this->start(t0, u0, v0);
    first_ = true;
  }

  Status step() {
    const double t1 = this->next_time();
    if (scheme_.velocity == CentralDifference::Velocity::synchronized) {
      const double c = 0.5 * h_ * h_, h = h_, hh = 0.5 * h_;
      const Index n = u_.size();
      if (stream_) return step_streamed(t1, h, c, hh);
      if (model_.uses_velocity()) {  // u and the velocity predictor in one pass over memory
        drift_predict(n, u_.data(), vstar_.data(), v_.data(), a_.data(), h, c);
        model_.acceleration(u_, vstar_, t1, anew_, stats_);
      } else {
        drift(n, u_.data(), v_.data(), a_.data(), h, c);
        model_.acceleration(u_, v_, t1, anew_, stats_);
      }
      kick(n, v_.data(), a_.data(), anew_.data(), hh);
      a_.swap(anew_);
    } else {
      // v_ holds v_{n-1/2} (v_0 before the first kick, which is a half kick).
      v_ += ((first_ ? 0.5 : 1.0) * h_) * a_;
      u_ += h_ * v_;
      if (model_.uses_velocity()) {
        vstar_ = v_ + (0.5 * h_) * a_;  // = v_n + h a_n, the synchronized predictor
        model_.acceleration(u_, vstar_, t1, a_, stats_);
      } else {
        model_.acceleration(u_, v_, t1, a_, stats_);
      }
      first_ = false;
    }
    return this->advance();
  }

  const CentralDifference& scheme() const { return scheme_; }
  // a_{n-1} where the step keeps it (the synchronized velocity: the swap leaves it in anew_), else null.
  const double* previous_a() const {
    return scheme_.velocity == CentralDifference::Velocity::synchronized && this->step_index() > 0 ? anew_.data() : nullptr;
  }

  // The same updates, block by block along the DOFs around the force (streamed_step). Out of line: in
  // step() it took the inliner's budget from the small models' path (the six-storey building's step 25 %
  // more instructions).
  NVIB_NOINLINE Status step_streamed(double t1, double h, double c, double hh) {
    double *u = u_.data(), *v = v_.data(), *a = a_.data(), *an = anew_.data(), *vs = vstar_.data();
    const bool velocity = model_.uses_velocity();
    this->streamed_step(
        velocity ? vs : v, t1, an,
        [=](Index p, Index q) {
          if (velocity)
            drift_predict(q - p, u + p, vs + p, v + p, a + p, h, c);
          else
            drift(q - p, u + p, v + p, a + p, h, c);
        },
        [=](Index p, Index q) { kick(q - p, v + p, a + p, an + p, hh); });
    a_.swap(anew_);
    return this->advance();
  }

  // The synchronized step's loops, on arrays that do not overlap (so the compiler need not check),
  // unrolled up to 8 DOFs (detail::for_each_index): on a model of a few DOFs a general loop's
  // set-up costs more than its arithmetic. The same operations in the same order as the vector forms
  // u += h v + c a and v += hh (a + a_new).
  NVIB_ALWAYS_INLINE static void drift(Index n, double* __restrict u, const double* __restrict v, const double* __restrict a, double h,
                    double c) {
    detail::for_each_index(n, [=](Index i) { u[i] += h * v[i] + c * a[i]; });
  }
  NVIB_ALWAYS_INLINE static void drift_predict(Index n, double* __restrict u, double* __restrict vs, const double* __restrict v,
                            const double* __restrict a, double h, double c) {
    detail::for_each_index(n, [=](Index i) {
      u[i] += h * v[i] + c * a[i];
      vs[i] = v[i] + h * a[i];
    });
  }
  NVIB_ALWAYS_INLINE static void kick(Index n, double* __restrict v, const double* __restrict a, const double* __restrict an, double hh) {
    detail::for_each_index(n, [=](Index i) { v[i] += hh * (a[i] + an[i]); });
  }
  // Variable steps: the synchronized form is one-step; half_step carries v_{n-1/2}, and its next kick
  // must be (h_{n-1} + h_n)/2 a_n, so the carried velocity is moved by (h_{n-1} - h_n)/2 a_n.
  void set_dt(double h) {
    if (h == h_) return;
    if (scheme_.velocity == CentralDifference::Velocity::half_step && !first_) v_ += (0.5 * (h_ - h)) * a_;
    Base::set_dt(h);
  }
  void checkpoint(int slot = 0) {
    Base::checkpoint(slot);
    ck_first_[static_cast<size_t>(slot)] = first_;
  }
  void rollback(int slot = 0) {
    Base::rollback(slot);
    first_ = ck_first_[static_cast<size_t>(slot)];
  }

  // State: [u; v; a]; with velocity = half_step, v is the carried v_{n-1/2}
  // and the next step is a full kick from it.
  void set_state(double t, const Vector& x) {
    Base::set_state(t, x);
    first_ = false;
  }

 private:
  CentralDifference scheme_;
  Vector anew_, vstar_;
  bool first_ = true;
  std::array<bool, Base::kCheckpoints> ck_first_{true, true, true, true};
};

}  // namespace nvib
