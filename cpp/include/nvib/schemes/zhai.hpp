// Zhai's explicit two-step method (Zhai 1996, IJNME 39:4199-4214), the pure
// method (a) of that paper, without a Newmark corrector:
//   u_{n+1} = u_n + h v_n + (1/2 + psi) h^2 a_n - psi h^2 a_{n-1}
//   v_{n+1} = v_n + (1 + phi) h a_n - phi h a_{n-1}
//   a_{n+1} = a(u_{n+1}, v_{n+1}, t_{n+1})
// Start-up with a_{-1} = a_0 (identical to psi = phi = 0 on the first step).
#pragma once

#include <string>

#include "../core/stepper.hpp"

namespace nvib {

struct Zhai {
  double psi = 0.5;
  double phi = 0.5;

  explicit Zhai(double psi_ = 0.5, double phi_ = 0.5) : psi(psi_), phi(phi_) {
    detail::require(std::isfinite(psi) && psi >= 0.0 && psi <= 1.0,
                    "psi: Zhai needs 0 <= psi <= 1, got " + detail::fmt(psi));
    detail::require(std::isfinite(phi) && phi >= 0.0 && phi <= 1.0,
                    "phi: Zhai needs 0 <= phi <= 1, got " + detail::fmt(phi));
  }
  static int order() { return 2; }
  static bool is_explicit() { return true; }
  std::string name() const { return "Zhai(psi=" + detail::fmt(psi) + ", phi=" + detail::fmt(phi) + ")"; }
};

template <class ModelT>
class ZhaiStepper : public StepperBase<ModelT> {
  using Base = StepperBase<ModelT>;
  NVIB_STEPPER_STATE(Base);

 public:
  ZhaiStepper(const Zhai& scheme, ModelT model, double h) : Base(std::move(model), h), scheme_(scheme) {
    aprev_.setZero(this->size());
  }

  void initialize(double t0, const Vector& u0, const Vector& v0) {
    this->start(t0, u0, v0);
    aprev_ = a_;
  }

  Status step() {
    const double t1 = this->next_time();
    const double psi = scheme_.psi, phi = scheme_.phi, h2 = h_ * h_;
    u_ += h_ * v_ + ((0.5 + psi) * h2) * a_ - (psi * h2) * aprev_;
    v_ += ((1.0 + phi) * h_) * a_ - (phi * h_) * aprev_;
    aprev_.swap(a_);
    model_.acceleration(u_, v_, t1, a_, stats_);
    return this->advance();
  }

  const Zhai& scheme() const { return scheme_; }

  // State: [u; v; a; a_{n-1}].
  Index state_size() const { return 4 * this->size(); }
  Vector state() const { return this->state_with(aprev_); }
  void set_state(double t, const Vector& x) { this->set_state_with(t, x, aprev_); }

 private:
  Zhai scheme_;
  Vector aprev_;
};

template <class ModelT>
struct stepper_for<Zhai, ModelT> {
  using type = ZhaiStepper<ModelT>;
};

}  // namespace nvib
