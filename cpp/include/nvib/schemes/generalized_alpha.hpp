// Generalized-alpha (Chung & Hulbert 1993, J. Appl. Mech. 60:371) and its
// special cases HHT and WBZ (Newmark, alpha_m = alpha_f = 0, is in newmark.hpp);
// the equation of each step is solved by the Newton component.
//
// Convention (Chung-Hulbert): alpha weights the old level, x_{n+1-a} = (1-a) x_{n+1} + a x_n.
// Newmark relations for a trial u_{n+1}:
//   a_{n+1} = (u_{n+1} - u_n - h v_n) / (beta h^2) - (1/(2 beta) - 1) a_n
//   v_{n+1} = v_n + h (1 - gamma) a_n + h gamma a_{n+1}
// Residual in the alpha-point form (G = K u + C v + f(u, v, t) includes -P):
//   r = (1-am) M a_{n+1} + am M a_n + G(u_{n+1-af}, v_{n+1-af}, t_{n+1-af})
// Iteration matrix: S = (1-am)/(beta h^2) M + (1-af) [gamma/(beta h) C_t + K_t] at the alpha point.
// Why not the averaged-force form (1-af) G_{n+1} + af G_n: once Newton has
// converged, M a_n + G_n = 0 and, for am = af, that form reduces exactly to
// Newmark, so the paper's GaM (am = af = 1/2) would be Newmark under another
// name. In the alpha-point form am = af = 1/2 is the implicit midpoint rule.
// Both forms are identical for linear models.
// The acceleration is carried in the state, never re-derived from equilibrium.
//
// Incremental format (Chopra section 5.7, for am = af = 0): the equation at t_n,
// M a_n + G_n = 0, is taken as satisfied and subtracted, and the increment of G
// is linearised at the start of the step:
//   (1-am) M (a_{n+1} - a_n) + (1-af) [K_t du + C_t dv + G(u_n, v_n, t_{n+1}) - G_n] = 0.
// For am = af this is Newmark's incremental format divided by (1 - am): the
// paper's GaM (am = af = 1/2) and Newmark then give the same steps.
#pragma once

#include <algorithm>
#include <limits>
#include <string>

#include "../newton/newton.hpp"
#include "scheme.hpp"
#include "stepper.hpp"

namespace nvib {

template <class ModelT>
class GeneralizedAlphaStepper;

struct GeneralizedAlpha {
  static constexpr const char* name = "GeneralizedAlpha";
  static constexpr const char* key = "galpha";
  static constexpr const char* doc =
      "Generalized-alpha (Chung & Hulbert 1993, alpha on the old level) in the alpha-point form, solved by "
      "Newton's method (see Newton). Defaults are the paper's alpha_m = alpha_f = 1/2, beta = 1/4, gamma = 1/2 "
      "(= from_rho_inf(1), the implicit midpoint rule).";
  static constexpr bool is_explicit = false;
  double alpha_m = 0.5, alpha_f = 0.5, beta = 0.25, gamma = 0.5;
  Newton newton{};

  explicit GeneralizedAlpha(double am = 0.5, double af = 0.5, double b = 0.25, double g = 0.5, Newton nw = {})
      : alpha_m(am), alpha_f(af), beta(b), gamma(g), newton(nw) {
    validate();
  }

  static GeneralizedAlpha from_rho_inf(double rho, Newton nw = {}) {
    NVIB_CHECK(std::isfinite(rho) && rho >= 0.0 && rho <= 1.0, "rho_inf", "needs 0 <= rho_inf <= 1, got " + detail::fmt(rho));
    const double am = (2.0 * rho - 1.0) / (rho + 1.0);
    const double af = rho / (rho + 1.0);
    const double g = 0.5 - am + af;
    const double b = 0.25 * (1.0 - am + af) * (1.0 - am + af);
    return GeneralizedAlpha(am, af, b, g, nw);
  }
  // Hilber-Hughes-Taylor (1977): their alpha in [-1/3, 0]; alpha_f = -alpha here.
  static GeneralizedAlpha hht(double alpha, Newton nw = {}) {
    NVIB_CHECK(std::isfinite(alpha) && alpha >= -1.0 / 3.0 && alpha <= 0.0, "alpha",
               "HHT needs -1/3 <= alpha <= 0 (Hilber et al. 1977 sign), got " + detail::fmt(alpha) +
                   "; OpenSees' HHT alpha in [2/3, 1] corresponds to alpha - 1");
    return GeneralizedAlpha(0.0, 0.0 - alpha, 0.25 * (1.0 - alpha) * (1.0 - alpha), 0.5 - alpha, nw);  // never -0
  }
  // Wood-Bossak-Zienkiewicz (1980): alpha in [-1, 0]; alpha_m = alpha here.
  static GeneralizedAlpha wbz(double alpha, Newton nw = {}) {
    NVIB_CHECK(std::isfinite(alpha) && alpha >= -1.0 && alpha <= 0.0, "alpha",
               "WBZ needs -1 <= alpha <= 0, got " + detail::fmt(alpha));
    return GeneralizedAlpha(alpha + 0.0, 0.0, 0.25 * (1.0 - alpha) * (1.0 - alpha), 0.5 - alpha, nw);  // never -0
  }
  template <class V>
  static void factories(V&& v) {
    v("from_rho_inf", param::real("rho_inf", "spectral radius at infinity; sets alpha_m, alpha_f, beta, gamma"),
      &from_rho_inf);
    v("hht", param::real("alpha", "Hilber-Hughes-Taylor alpha in [-1/3, 0]"), &hht);
    v("wbz", param::real("alpha", "Wood-Bossak-Zienkiewicz alpha in [-1, 0]"), &wbz);
  }

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.alpha_m, param::real("alpha_m", "weight of a_n in the inertia term").at_least(-1.0));
    v(s.alpha_f, param::real("alpha_f", "weight of the old level in the forces").range(0.0, 0.5));
    v(s.beta, param::real("beta", "Newmark beta")
                  .above(0.0)
                  .at_most(1.0)
                  .because("beta = 0 is explicit; use CentralDifference"));
    v(s.gamma, param::real("gamma", "Newmark gamma").range(0.5, 1.5).because("gamma < 1/2 amplifies the response"));
    v(s.newton, param::newton("newton", "options of the Newton iteration"));
  }

  void validate() const {
    param::check_ranges(*this);
    NVIB_CHECK(alpha_m <= alpha_f, "alpha_m, alpha_f",
               "unconditional stability needs alpha_m <= alpha_f (Chung-Hulbert 1993), got alpha_m = " +
                   detail::fmt(alpha_m) + ", alpha_f = " + detail::fmt(alpha_f));
    NVIB_CHECK(beta >= 0.25 + 0.5 * (alpha_f - alpha_m) - 1e-15, "beta",
               "unconditional stability needs beta >= 1/4 + (alpha_f - alpha_m)/2 = " +
                   detail::fmt(0.25 + 0.5 * (alpha_f - alpha_m)) + ", got " + detail::fmt(beta));
    newton.validate();
  }

  std::string label() const {
    using detail::short_number;
    std::string s = "G\xce\xb1M(" + short_number(alpha_m) + "," + short_number(alpha_f);
    if (beta != 0.25 || gamma != 0.5) s += "," + short_number(beta) + "," + short_number(gamma);
    return s + ")";
  }
  // Second order exactly when gamma = 1/2 - alpha_m + alpha_f (Chung & Hulbert 1993), except in the
  // incremental format, first order on nonlinear models (its linearisation error is never corrected).
  int order_u() const {
    return std::abs(gamma - (0.5 - alpha_m + alpha_f)) < 1e-12 && newton.iteration != NewtonMode::incremental ? 2 : 1;
  }
  int order_v() const { return order_u(); }
  template <class M>
  using stepper = GeneralizedAlphaStepper<M>;
};

template <class ModelT>
class GeneralizedAlphaStepper : public StepperBase<ModelT> {
  using Base = StepperBase<ModelT>;
  NVIB_STEPPER_STATE(Base);
  using Solver = NewtonSolver<IterationSystem>;
  friend Solver;

 public:
  GeneralizedAlphaStepper(const GeneralizedAlpha& scheme, ModelT model, double h)
      : Base(std::move(model), h), p_(scheme), newton_(scheme.newton, this->size()) {
    const Index n = this->size();
    G1_.setZero(n);
    G0_.setZero(n);
    ua_.setZero(n);
    va_.setZero(n);
    u1_.setZero(n);
    v1_.setZero(n);
    a1_.setZero(n);
    w_.setZero(n);
  }

  void initialize(double t0, const Vector& u0, const Vector& v0) {
    this->start(t0, u0, v0);
    newton_.reset();
  }

  // Newton residual norms of the last step (for the quadratic-convergence check).
  const std::vector<double>& last_residuals() const { return newton_.residuals(); }
  const GeneralizedAlpha& scheme() const { return p_; }

  Status step() {
    const double h = h_;
    c0_ = 1.0 / (p_.beta * h * h);
    c1_ = p_.gamma / (p_.beta * h);
    t1_ = this->next_time();
    ta_ = t1_ - p_.alpha_f * h;
    const Status s = newton_.solve(*this, model_, u1_, t1_, n_ + 1, stats_);
    if (s != Status::success) return this->fail(newton_.failure());
    u_.swap(u1_);
    v_.swap(v1_);
    a_.swap(a1_);
    // Laws with memory: Newton's last evaluation was at the end of the step only for alpha_f = 0;
    // otherwise it was at the alpha-point and the end state gets a trial of its own (as OpenSees'
    // HHT::commit updates the domain at t_{n+1} before committing it).
    return this->advance(p_.alpha_f == 0.0);
  }

  // Variable steps: the scheme is one-step (u, v, a); its iteration matrix holds 1/h^2 and 1/h, so a
  // new step length is refactorised (the initial-tangent mode's too, at the state it changes at).
  void set_dt(double h) {
    if (h == h_) return;
    Base::set_dt(h);
    newton_.reset();
  }
  void rollback(int slot = 0) {
    const double h = h_;
    Base::rollback(slot);
    if (h_ != h) newton_.reset();
  }

  // Residual of the last accepted step relative to its force scale:
  // ||r||inf / (f + atol/rtol), f the largest inertia or force term, so at
  // most rtol after Newton converges; the equilibrium error left by the
  // incremental and one_iteration modes; NaN where not evaluated (a linear
  // model, exact after one solve).
  double accepted_residual() const { return newton_.accepted_residual(); }

 private:
  // ---- the equation of the step, for the Newton component ----
  bool linear() const { return model_.is_linear(); }
  void predict(Vector& x) const { x = u_; }  // constant displacement (the incremental format's starting point)
  // a1, v1 from u1 by the Newmark relations (at the predictor).
  void update(const Vector& x) {
    const double h = h_, c0 = c0_, ka = 0.5 / p_.beta - 1.0, hv = h * (1.0 - p_.gamma), ha = h * p_.gamma;
    const double *xp = x.data(), *u = u_.data(), *v = v_.data(), *a = a_.data();
    double *a1 = a1_.data(), *v1 = v1_.data();
    detail::for_each_index(x.size(), [=](Index i) {
      a1[i] = c0 * (xp[i] - u[i] - h * v[i]) - ka * a[i];
      v1[i] = v[i] + hv * a[i] + ha * a1[i];
    });
  }
  // ... and by the increments of the same relations in the iterations: da1 = c0 du, dv1 = c1 du.
  // Recomputed from u1, a1 would carry the round-off of c0 (u1 - u_n - h v_n), about eps c0 |u| (4e-4 N
  // on the building's 1e5 kg floors at dt = 1e-4 s), above a tolerance of 1e-10 of the forces (2.5e-5 N
  // there): Newton would end on its stall test after a wasted iteration. By increments the round-off is
  // eps c0 (h |v_n| + |u1 - u_n|), a few hundred times smaller there.
  void increment(const Vector& du) {
    const double c0 = c0_, c1 = c1_;
    const double* d = du.data();
    double *a1 = a1_.data(), *v1 = v1_.data();
    detail::for_each_index(du.size(), [=](Index i) {
      a1[i] += c0 * d[i];
      v1[i] += c1 * d[i];
    });
  }
  IterationMatrix matrix() const { return coefficients(*ua_at_, *va_at_, ta_); }
  IterationMatrix start_matrix() const { return coefficients(u_, v_, this->time()); }
  IterationMatrix coefficients(const Vector& u, const Vector& v, double t) const {
    const double am = p_.alpha_m, af = p_.alpha_f;
    return {(1.0 - am) * c0_, (1.0 - af) * c1_, 1.0 - af, &u, &v, t};
  }

  // r = (1-am) M a1 + am M a_n + G(alpha point); the scale is the largest of the three terms.
  Residual residual(Vector& r) {
    const double am = p_.alpha_m, af = p_.alpha_f;
    // alpha point: x_{n+1-af} = (1-af) x_{n+1} + af x_n
    // (Newmark, af = 0: the end of the step itself; the velocity only where forces use it)
    ua_at_ = &u1_;
    va_at_ = &v1_;
    if (af != 0.0) {  // (the products and sum of the vector expression, entry by entry)
      const double cn = 1.0 - af;
      auto blend = [&](const Vector& x1, const Vector& x0, Vector& out) {
        const double *a = x1.data(), *b = x0.data();
        double* o = out.data();
        detail::for_each_index(x1.size(), [=](Index i) { o[i] = cn * a[i] + af * b[i]; });
      };
      blend(u1_, u_, ua_);
      ua_at_ = &ua_;
      if (model_.uses_velocity()) {
        blend(v1_, v_, va_);
        va_at_ = &va_;
      }
    }
    model_.force(*ua_at_, *va_at_, ta_, G1_, stats_);
    if (model_.mass().is_diagonal()) {  // one pass: r, its norm and the force scale together
      const double* m = model_.mass().diagonal_entries().data();
      const double *a1 = a1_.data(), *a0 = a_.data(), *g = G1_.data();
      double* rp = r.data();
      double rn = 0.0, scale = 0.0;
      bool nan = false;
      // With alpha_m = 0 (Newmark) the inertia of a_n is 0 and left out of the sums.
      auto pass = [&](auto with_old) {
        constexpr bool Old = decltype(with_old)::value;
        const double cn = Old ? 1.0 - am : 1.0;
        detail::for_each_index(r.size(), [&](Index i) {
          const double inertia_new = cn * m[i] * a1[i];
          double others = std::abs(g[i]);
          if constexpr (Old) {
            const double inertia_old = am * m[i] * a0[i];
            rp[i] = inertia_new + inertia_old + g[i];
            others = std::max(std::abs(inertia_old), others);
          } else {
            rp[i] = inertia_new + g[i];
          }
          rn = std::max(rn, std::abs(rp[i]));
          scale = std::max(scale, std::max(std::abs(inertia_new), others));
          nan = nan || std::isnan(rp[i]);  // max() would drop a NaN
        });
      };
      if (am == 0.0)
        pass(std::false_type{});
      else
        pass(std::true_type{});
      return {nan ? std::numeric_limits<double>::quiet_NaN() : rn, scale};
    }
    model_.mass().apply(a1_, r);
    r *= (1.0 - am);
    double scale = r.template lpNorm<Eigen::Infinity>();
    if (am != 0.0) {
      model_.mass().apply(a_, w_);
      r += am * w_;
      scale = std::max(scale, std::abs(am) * w_.template lpNorm<Eigen::Infinity>());
    }
    r += G1_;
    scale = std::max(scale, G1_.template lpNorm<Eigen::Infinity>());
    return {r.template lpNorm<Eigen::Infinity>(), scale};
  }

  // Round-off in the residual at the current iterate: 8 eps times the
  // magnitudes that enter it, c0 (h |v_n| + |u1 - u_n|) in a1 (the
  // predictor's a1 and the increments added to it), the inertia of a_n and
  // the force terms (their sum cancels to the residual).
  double residual_roundoff() {
    const double am = p_.alpha_m, k = std::abs(0.5 / p_.beta - 1.0);
    model_.force_magnitude(*ua_at_, *va_at_, ta_, G1_, G0_);  // G1_: the force residual() evaluated here
    w_ = (1.0 - am) * (c0_ * ((u1_ - u_).cwiseAbs() + h_ * v_.cwiseAbs()) + k * a_.cwiseAbs()) +
         std::abs(am) * a_.cwiseAbs();
    model_.mass().apply(w_, G1_);
    G1_ += G0_;
    return 8.0 * std::numeric_limits<double>::epsilon() * G1_.template lpNorm<Eigen::Infinity>();
  }

  // The incremental format's residual at the predictor (u1 = u_n, see the top of this file):
  //   r = (1-am) M (a1 - a_n) + (1-af) [C_t (v1 - v_n) + G(u_n, v_n, t_{n+1}) - G(u_n, v_n, t_n)].
  template <class LinearSolver>
  Residual incremental_residual(Vector& r, const LinearSolver& ls) {
    const double am = p_.alpha_m, af = p_.alpha_f;
    w_ = a1_ - a_;
    model_.mass().apply(w_, r);
    r *= (1.0 - am);
    double scale = r.template lpNorm<Eigen::Infinity>();
    if (model_.uses_velocity()) {
      w_ = v1_ - v_;
      ls.multiply_C(w_, G1_);
      r += (1.0 - af) * G1_;
      scale = std::max(scale, (1.0 - af) * G1_.template lpNorm<Eigen::Infinity>());
    }
    if (model_.uses_time()) {  // the load increment of the step, at the start state
      model_.force(u_, v_, t1_, G1_, stats_);
      model_.force(u_, v_, this->time(), G0_, stats_);
      G1_ -= G0_;
      r += (1.0 - af) * G1_;
      scale = std::max(scale, (1.0 - af) * G1_.template lpNorm<Eigen::Infinity>());
    }
    return {r.template lpNorm<Eigen::Infinity>(), scale};
  }

  GeneralizedAlpha p_;
  Solver newton_;
  double c0_ = 0.0, c1_ = 0.0, t1_ = 0.0, ta_ = 0.0;
  Vector G1_, G0_, ua_, va_, u1_, v1_, a1_, w_;
  const Vector* ua_at_ = &ua_;  // the alpha point: ua_ and va_, or u1_ and v1_ where af = 0
  const Vector* va_at_ = &va_;
};

}  // namespace nvib
