// Generalized-alpha (Chung & Hulbert 1993, J. Appl. Mech. 60:371) and its
// special cases HHT and WBZ (Newmark, alpha_m = alpha_f = 0, is in newmark.hpp),
// with Newton iteration on the displacement.
//
// Convention (Chung-Hulbert): alpha weights the old level, x_{n+1-a} = (1-a) x_{n+1} + a x_n.
// Newmark relations for a trial u_{n+1}:
//   a_{n+1} = (u_{n+1} - u_n - h v_n) / (beta h^2) - (1/(2 beta) - 1) a_n
//   v_{n+1} = v_n + h (1 - gamma) a_n + h gamma a_{n+1}
// Residual in the alpha-point form (G = K u + C v + f(u, v, t) includes -P):
//   r = (1-am) M a_{n+1} + am M a_n + G(u_{n+1-af}, v_{n+1-af}, t_{n+1-af})
// Tangent: S = (1-am)/(beta h^2) M + (1-af) [gamma/(beta h) C_t + K_t] at the alpha point.
// Why not the averaged-force form (1-af) G_{n+1} + af G_n: once Newton has
// converged, M a_n + G_n = 0 and, for am = af, that form reduces exactly to
// Newmark, so the paper's GaM (am = af = 1/2) would be Newmark under another
// name. In the alpha-point form am = af = 1/2 is the implicit midpoint rule.
// Both forms are identical for linear models.
// The acceleration is carried in the state, never re-derived from equilibrium.
#pragma once

#include <algorithm>
#include <limits>
#include <string>

#include "../core/newton.hpp"
#include "../core/stepper.hpp"
#include "../linalg/dense_lu.hpp"

namespace nvib {

struct GeneralizedAlpha {
  double alpha_m = 0.5, alpha_f = 0.5, beta = 0.25, gamma = 0.5;
  Iteration iteration = Iteration::newton;
  NewtonOptions newton{};

  // Defaults: the paper's non-dissipative member (alpha_m = alpha_f = 1/2, beta = 1/4,
  // gamma = 1/2), which is also from_rho_inf(1).
  explicit GeneralizedAlpha(double am = 0.5, double af = 0.5, double b = 0.25, double g = 0.5,
                            Iteration it = Iteration::newton, NewtonOptions nw = {})
      : alpha_m(am), alpha_f(af), beta(b), gamma(g), iteration(it), newton(nw) {
    validate();
  }

  static GeneralizedAlpha from_rho_inf(double rho, Iteration it = Iteration::newton, NewtonOptions nw = {}) {
    detail::require(std::isfinite(rho) && rho >= 0.0 && rho <= 1.0,
                    "rho_inf: needs 0 <= rho_inf <= 1, got " + detail::fmt(rho));
    const double am = (2.0 * rho - 1.0) / (rho + 1.0);
    const double af = rho / (rho + 1.0);
    const double g = 0.5 - am + af;
    const double b = 0.25 * (1.0 - am + af) * (1.0 - am + af);
    return GeneralizedAlpha(am, af, b, g, it, nw);
  }
  // Hilber-Hughes-Taylor (1977): their alpha in [-1/3, 0]; alpha_f = -alpha here.
  static GeneralizedAlpha hht(double alpha, Iteration it = Iteration::newton, NewtonOptions nw = {}) {
    detail::require(std::isfinite(alpha) && alpha >= -1.0 / 3.0 && alpha <= 0.0,
                    "alpha: HHT needs -1/3 <= alpha <= 0 (Hilber et al. 1977 sign), got " + detail::fmt(alpha) +
                        "; OpenSees' HHT alpha in [2/3, 1] corresponds to alpha - 1");
    return GeneralizedAlpha(0.0, -alpha, 0.25 * (1.0 - alpha) * (1.0 - alpha), 0.5 - alpha, it, nw);
  }
  // Wood-Bossak-Zienkiewicz (1980): alpha in [-1, 0]; alpha_m = alpha here.
  static GeneralizedAlpha wbz(double alpha, Iteration it = Iteration::newton, NewtonOptions nw = {}) {
    detail::require(std::isfinite(alpha) && alpha >= -1.0 && alpha <= 0.0,
                    "alpha: WBZ needs -1 <= alpha <= 0, got " + detail::fmt(alpha));
    return GeneralizedAlpha(alpha, 0.0, 0.25 * (1.0 - alpha) * (1.0 - alpha), 0.5 - alpha, it, nw);
  }

  void validate() const {
    using detail::fmt;
    using detail::require;
    require(std::isfinite(alpha_m) && std::isfinite(alpha_f) && std::isfinite(beta) && std::isfinite(gamma),
            "GeneralizedAlpha: alpha_m, alpha_f, beta and gamma must be finite");
    require(alpha_m <= alpha_f,
            "alpha_m, alpha_f: unconditional stability needs alpha_m <= alpha_f (Chung-Hulbert 1993), got alpha_m = " +
                fmt(alpha_m) + ", alpha_f = " + fmt(alpha_f));
    require(alpha_f >= 0.0 && alpha_f <= 0.5,
            "alpha_f: needs 0 <= alpha_f <= 1/2, got " + fmt(alpha_f));
    require(alpha_m >= -1.0, "alpha_m: needs alpha_m >= -1, got " + fmt(alpha_m));
    require(beta > 0.0, "beta: needs beta > 0 (beta = 0 is explicit; use CentralDifference), got " + fmt(beta));
    require(beta <= 1.0, "beta: needs beta <= 1, got " + fmt(beta));
    require(gamma >= 0.5 && gamma <= 1.5,
            "gamma: needs 1/2 <= gamma <= 3/2 (gamma < 1/2 amplifies the response), got " + fmt(gamma));
    require(beta >= 0.25 + 0.5 * (alpha_f - alpha_m) - 1e-15,
            "beta: unconditional stability needs beta >= 1/4 + (alpha_f - alpha_m)/2 = " +
                fmt(0.25 + 0.5 * (alpha_f - alpha_m)) + ", got " + fmt(beta));
    newton.validate();
  }

  int order() const { return std::abs(gamma - (0.5 - alpha_m + alpha_f)) < 1e-12 ? 2 : 1; }
  static bool is_explicit() { return false; }
  std::string name() const {
    return "GeneralizedAlpha(alpha_m=" + detail::fmt(alpha_m) + ", alpha_f=" + detail::fmt(alpha_f) +
           ", beta=" + detail::fmt(beta) + ", gamma=" + detail::fmt(gamma) + ", iteration=" + to_string(iteration) + ")";
  }
};

template <class ModelT>
class GeneralizedAlphaStepper : public StepperBase<ModelT> {
  using Base = StepperBase<ModelT>;
  NVIB_STEPPER_STATE(Base);

 public:
  GeneralizedAlphaStepper(const GeneralizedAlpha& scheme, ModelT model, double h)
      : Base(std::move(model), h), p_(scheme) {
    const Index n = this->size();
    G1_.setZero(n);
    ua_.setZero(n);
    va_.setZero(n);
    u1_.setZero(n);
    v1_.setZero(n);
    a1_.setZero(n);
    r_.setZero(n);
    du_.setZero(n);
    w_.setZero(n);
    Kt_.setZero(n, n);
    Ct_.setZero(n, n);
    S_.setZero(n, n);
    lu_.resize(n);
    residuals_.reserve(static_cast<size_t>(p_.newton.max_iter) + 2);
  }

  void initialize(double t0, const Vector& u0, const Vector& v0) {
    this->start(t0, u0, v0);
    factorized_ = false;
  }

  // Newton residual norms of the last step (for the quadratic-convergence check).
  const std::vector<double>& last_residuals() const { return residuals_; }
  const GeneralizedAlpha& scheme() const { return p_; }

  Status step() {
    const double h = h_, beta = p_.beta, gamma = p_.gamma, am = p_.alpha_m, af = p_.alpha_f;
    const double c0 = 1.0 / (beta * h * h), c1 = gamma / (beta * h);
    const double t1 = this->next_time();
    const bool linear = model_.is_linear();
    const bool fd = p_.newton.jacobian == Jacobian::finite_difference;
    residuals_.clear();
    du_small_ = false;

    u1_ = u_;  // constant-displacement predictor (the incremental format's starting point)
    update_kinematics(c0);
    const double ta = t1 - af * h;
    accepted_residual_ = std::numeric_limits<double>::quiet_NaN();
    for (int k = 0;; ++k) {
      double fscale = 0.0;
      const double rnorm = residual(ta, fscale);
      residuals_.push_back(rnorm);
      if (!std::isfinite(rnorm)) return nonfinite_residual(t1);
      const double tol = p_.newton.atol + p_.newton.rtol * fscale;
      // A negligible increment ends the iteration only once the residual has
      // stopped falling: then it sits at its round-off floor (forces that
      // cancel, as at a static preload). While it still falls, Newton goes on.
      if (k > 0 && (rnorm <= tol || (du_small_ && rnorm >= residuals_[static_cast<size_t>(k) - 1]))) {
        accepted_residual_ = relative(rnorm, fscale);
        break;
      }
      if (k == 0 && rnorm == 0.0) {  // the predictor is in equilibrium to the last bit
        accepted_residual_ = 0.0;
        break;
      }
      if (k >= p_.newton.max_iter) return newton_failure(t1, tol);

      const bool refactor = linear ? !factorized_ : (k == 0 || p_.iteration == Iteration::newton);
      if (refactor) {
        model_.tangent(ua_, va_, ta, Kt_, Ct_, stats_, fd);
        S_ = (1.0 - af) * Kt_;
        model_.mass().add_to(S_, (1.0 - am) * c0);
        if (model_.uses_velocity()) S_.noalias() += ((1.0 - af) * c1) * Ct_;
        const bool regular = lu_.compute(S_);
        ++stats_.num_factorizations;
        factorized_ = true;
        // An overflowing tangent shows up as a failed factorisation; name it as such.
        if (!regular && !(Kt_.allFinite() && Ct_.allFinite())) return nonfinite_tangent(t1);
        if (!regular)
          return this->fail(Status::singular_matrix, rnorm,
                            "singular iteration matrix at t = " + detail::fmt(t1) + " (step " +
                                std::to_string(n_ + 1) + ")");
      }
      du_ = -r_;
      lu_.solve_in_place(du_);
      ++stats_.num_linear_solves;
      ++stats_.num_newton_iters;
      u1_ += du_;
      update_kinematics(c0);
      du_small_ = du_.template lpNorm<Eigen::Infinity>() <=
                  p_.newton.atol + 1e-3 * p_.newton.rtol * u1_.template lpNorm<Eigen::Infinity>();
      // A linear model is in equilibrium after one solve, up to round-off.
      if (linear) break;
      if (p_.iteration == Iteration::none) {
        // The incremental format accepts the step without iterating, but not
        // unseen: the residual left at the new state is measured (one force
        // evaluation) and reported, in last_residuals() and Result::max_residual.
        const double after = residual(ta, fscale);
        residuals_.push_back(after);
        if (!std::isfinite(after)) return nonfinite_residual(t1);
        accepted_residual_ = relative(after, fscale);
        break;
      }
    }
    u_.swap(u1_);
    v_.swap(v1_);
    a_.swap(a1_);
    return this->advance();
  }

  // Residual of the last accepted step relative to its force scale:
  // ||r||inf / (f + atol/rtol), f the largest inertia or force term, so at
  // most rtol after Newton converges; the equilibrium error left by
  // iteration = none; NaN where not evaluated (a linear model, exact after one solve).
  double accepted_residual() const { return accepted_residual_; }

 private:
  // r_ = (1-am) M a1 + am M a_n + G(alpha point) and its max-norm; fscale is the
  // largest of the three terms.
  double residual(double ta, double& fscale) {
    const double am = p_.alpha_m, af = p_.alpha_f;
    // alpha point: x_{n+1-af} = (1-af) x_{n+1} + af x_n
    ua_ = (1.0 - af) * u1_ + af * u_;
    va_ = (1.0 - af) * v1_ + af * v_;
    model_.force(ua_, va_, ta, G1_, stats_);
    if (model_.mass().is_diagonal()) {  // one pass: r, its norm and the force scale together
      const double* m = model_.mass().diagonal_entries().data();
      const double *a1 = a1_.data(), *a0 = a_.data(), *g = G1_.data();
      double* r = r_.data();
      double rn = 0.0, scale = 0.0;
      for (Index i = 0, n = r_.size(); i < n; ++i) {
        const double inertia_new = (1.0 - am) * m[i] * a1[i], inertia_old = am * m[i] * a0[i];
        r[i] = inertia_new + inertia_old + g[i];
        rn = std::max(rn, std::abs(r[i]));
        scale = std::max(scale, std::max(std::abs(inertia_new), std::max(std::abs(inertia_old), std::abs(g[i]))));
        if (std::isnan(r[i])) rn = r[i];  // max() would drop a NaN
      }
      fscale = scale;
      return rn;
    }
    model_.mass().apply(a1_, r_);
    r_ *= (1.0 - am);
    fscale = r_.template lpNorm<Eigen::Infinity>();
    if (am != 0.0) {
      model_.mass().apply(a_, w_);
      r_ += am * w_;
      fscale = std::max(fscale, std::abs(am) * w_.template lpNorm<Eigen::Infinity>());
    }
    r_ += G1_;
    fscale = std::max(fscale, G1_.template lpNorm<Eigen::Infinity>());
    return r_.template lpNorm<Eigen::Infinity>();
  }
  // In the units of the relative tolerance: rnorm <= atol + rtol fscale is
  // relative() <= rtol, so a converged step reports at most rtol.
  double relative(double rnorm, double fscale) const {
    const double floor = p_.newton.rtol > 0.0 ? p_.newton.atol / p_.newton.rtol : 0.0;
    const double scale = fscale + floor;
    return scale > 0.0 ? rnorm / scale : rnorm;
  }

  // An overflowing force overflows its tangent too: that is divergence, not a singular matrix.
  Status nonfinite_tangent(double t1) {
    Index dof = 0;
    while (dof + 1 < Kt_.rows() && Kt_.row(dof).allFinite() && Ct_.row(dof).allFinite()) ++dof;
    this->fail(Status::diverged, residuals_.back(),
               "diverged at t = " + detail::fmt(t1) + " (step " + std::to_string(n_ + 1) +
                   "): the tangent of the forces is not finite at DOF " + std::to_string(dof));
    this->failure_.dof = dof;
    this->failure_.residuals = residuals_;
    return Status::diverged;
  }

  // Names the first non-finite residual entry, the time and the step.
  Status nonfinite_residual(double t1) {
    Index dof = 0;
    while (dof + 1 < r_.size() && std::isfinite(r_[dof])) ++dof;
    this->fail(Status::diverged, residuals_.back(),
               "diverged at t = " + detail::fmt(t1) + " (step " + std::to_string(n_ + 1) +
                   "): the equilibrium residual is not finite at DOF " + std::to_string(dof) + " (residual[" +
                   std::to_string(dof) + "] = " + detail::fmt(r_[dof]) + ")");
    this->failure_.dof = dof;
    this->failure_.residuals = residuals_;
    return Status::diverged;
  }

  // a1, v1 from u1 by the Newmark relations.
  void update_kinematics(double c0) {
    const double h = h_, beta = p_.beta, gamma = p_.gamma;
    a1_ = c0 * (u1_ - u_ - h * v_) - (0.5 / beta - 1.0) * a_;
    v1_ = v_ + (h * (1.0 - gamma)) * a_ + (h * gamma) * a1_;
  }

  Status newton_failure(double t1, double tol) {
    this->fail(Status::newton_failed, residuals_.back(),
               "Newton did not converge in " + std::to_string(p_.newton.max_iter) + " iterations at t = " +
                   detail::fmt(t1) + " (step " + std::to_string(n_ + 1) + "; residual " +
                   detail::fmt(residuals_.back()) + " > tolerance " + detail::fmt(tol) + ")");
    this->failure_.residuals = residuals_;
    return Status::newton_failed;
  }

  GeneralizedAlpha p_;
  Vector G1_, ua_, va_, u1_, v1_, a1_, r_, du_, w_;
  Matrix Kt_, Ct_, S_;
  DenseLU lu_;
  bool factorized_ = false;
  bool du_small_ = false;
  double accepted_residual_ = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> residuals_;
};

template <class ModelT>
struct stepper_for<GeneralizedAlpha, ModelT> {
  using type = GeneralizedAlphaStepper<ModelT>;
};

}  // namespace nvib
