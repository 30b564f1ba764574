// Zhai's explicit two-step method (Zhai 1996, IJNME 39:4199-4214), the pure
// method (a) of that paper, without a Newmark corrector:
//   u_{n+1} = u_n + h v_n + (1/2 + psi) h^2 a_n - psi h^2 a_{n-1}
//   v_{n+1} = v_n + (1 + phi) h a_n - phi h a_{n-1}
//   a_{n+1} = a(u_{n+1}, v_{n+1}, t_{n+1})
// Start-up with a_{-1} = a_0 (identical to psi = phi = 0 on the first step).
#pragma once

#include <string>

#include "scheme.hpp"
#include "stepper.hpp"

namespace nvib {

template <class ModelT>
class ZhaiStepper;

struct Zhai {
  static constexpr const char* name = "Zhai";
  static constexpr const char* key = "zhai";
  static constexpr const char* doc =
      "Zhai's explicit two-step method (Zhai 1996, IJNME 39:4199), the pure method without a Newmark "
      "corrector. psi = phi = 1/2: central-difference displacements, second order; phi != 1/2 is first order.";
  static constexpr bool is_explicit = true;
  double psi = 0.5;
  double phi = 0.5;

  explicit Zhai(double psi_ = 0.5, double phi_ = 0.5) : psi(psi_), phi(phi_) { validate(); }

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.psi, param::real("psi", "weight of a_{n-1} in the displacement").range(0.0, 1.0));
    v(s.phi, param::real("phi", "weight of a_{n-1} in the velocity").range(0.0, 1.0));
  }
  void validate() const { param::check_ranges(*this); }
  std::string label() const { return "Zhai(" + detail::short_number(psi) + "," + detail::short_number(phi) + ")"; }
  // v_{n+1} - v(t_{n+1}) = (phi - 1/2) h^2 a'(t_n) + O(h^3) per step, and u inherits v's error.
  int order_u() const { return phi == 0.5 ? 2 : 1; }
  int order_v() const { return phi == 0.5 ? 2 : 1; }
  template <class M>
  using stepper = ZhaiStepper<M>;
};

template <class ModelT>
class ZhaiStepper : public TwoLevelStepper<ModelT> {
  using Base = TwoLevelStepper<ModelT>;
  NVIB_STEPPER_STATE(Base);
  using Base::aprev_;

 public:
  ZhaiStepper(const Zhai& scheme, ModelT model, double h) : Base(std::move(model), h), scheme_(scheme) {
  }

  void initialize(double t0, const Vector& u0, const Vector& v0) {
    this->start_two_level(t0, u0, v0);
  }

  Status step() {
    const double t1 = this->next_time();
    const double psi = scheme_.psi, phi = scheme_.phi, h2 = h_ * h_, h = h_;
    const double cu = (0.5 + psi) * h2, cp = psi * h2, va = (1.0 + phi) * h_, vp = phi * h_;
    if (stream_) return step_streamed(t1, h, cu, cp, va, vp);
    advance_state(u_.size(), u_.data(), v_.data(), a_.data(), aprev_.data(), h, cu, cp, va, vp);
    aprev_.swap(a_);
    model_.acceleration(u_, v_, t1, a_, stats_);
    return this->advance();
  }

  const Zhai& scheme() const { return scheme_; }

  // The same updates, block by block along the DOFs around the force (streamed_step), out of line as
  // CentralDifference's; a_{n+1} goes where a_{n-1} was: each DOF's a_{n-1} is read (by its update)
  // before its a_{n+1} is written.
  NVIB_NOINLINE Status step_streamed(double t1, double h, double cu, double cp, double va, double vp) {
    double *u = u_.data(), *v = v_.data(), *a = a_.data(), *ap = aprev_.data();
    this->streamed_step(
        v, t1, ap, [=](Index p, Index q) { advance_state(q - p, u + p, v + p, a + p, ap + p, h, cu, cp, va, vp); },
        [](Index, Index) {});
    aprev_.swap(a_);
    return this->advance();
  }

  // u += h v + cu a - cp a_prev, then v += va a - vp a_prev, entry by entry (u reads v_n), on
  // non-overlapping arrays, unrolled up to 8 DOFs (see CentralDifference).
  static void advance_state(Index n, double* __restrict u, double* __restrict v, const double* __restrict a,
                            const double* __restrict ap, double h, double cu, double cp, double va, double vp) {
    detail::for_each_index(n, [=](Index i) {
      u[i] += h * v[i] + cu * a[i] - cp * ap[i];
      v[i] += va * a[i] - vp * ap[i];
    });
  }

  // State: [u; v; a; a_{n-1}; internal variables of the laws with memory] (TwoLevelStepper).

 private:
  Zhai scheme_;
};

}  // namespace nvib
