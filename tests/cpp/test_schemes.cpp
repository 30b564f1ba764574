// C++-level checks of the schemes through the public C++ API: orders on the
// linear oscillator against its closed form, identities, failures reported
// as the documented exceptions, validation of parameters.
#include <nvib/nvib.hpp>

#include <functional>
#include <limits>
#include <string>

#include "check.hpp"
#include "models.hpp"

using nvib::Index;
using nvib::Vector;

namespace {

const double kM = 2.0, kK = 50.0;

double exact_x(double t, double c) {  // x0 = 1, v0 = 0
  const double w = std::sqrt(kK / kM), xi = c / (2.0 * kM * w), wd = w * std::sqrt(1.0 - xi * xi);
  return std::exp(-xi * w * t) * (std::cos(wd * t) + xi * w / wd * std::sin(wd * t));
}

template <class Scheme>
double max_error(const Scheme& s, double h, double c) {
  nvib::Matrix K(1, 1), C(1, 1);
  K << kK;
  C << c;
  auto model = nvib::make_linear_model(nvib::Mass::diagonal(Vector::Constant(1, kM)), K, c > 0 ? C : nvib::Matrix());
  Vector u0 = Vector::Ones(1), v0 = Vector::Zero(1);
  auto r = nvib::solve(model, s, h, 2.0, u0, v0);
  double e = 0.0;
  for (Index i = 0; i < r.t.size(); ++i) e = std::max(e, std::abs(r.u(i, 0) - exact_x(r.t[i], c)));
  return e;
}

template <class Scheme>
double fitted_order(const Scheme& s, double c) {
  // least-squares slope of log e vs log h over 4 halvings
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const int m = 4;
  for (int i = 0; i < m; ++i) {
    const double h = 0.02 / std::pow(2.0, i);
    const double x = std::log(h), y = std::log(max_error(s, h, c));
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

// Finite forces whose tangent overflows on DOF 1.
struct OverflowingTangent {
  void operator()(const nvib::CVecRef& u, const nvib::CVecRef&, double, nvib::VecRef out) const { out = u; }
  void tangent(const nvib::CVecRef&, const nvib::CVecRef&, double, nvib::MatRef K, nvib::MatRef C) const {
    K.setIdentity();
    K(1, 1) = std::numeric_limits<double>::infinity();
    C.setZero();
  }
  bool uses_velocity() const { return false; }
};

using nvib_test::Hardening;

// 100 (1 + 30 u^2) u + 0.1 v^3 on every DOF, with its tangent.
struct Duffing {
  void operator()(const nvib::CVecRef& u, const nvib::CVecRef& v, double, nvib::VecRef out) const {
    for (Index i = 0; i < u.size(); ++i) out[i] = 100.0 * (1.0 + 30.0 * u[i] * u[i]) * u[i] + 0.1 * v[i] * v[i] * v[i];
  }
  void tangent(const nvib::CVecRef& u, const nvib::CVecRef& v, double, nvib::MatRef K, nvib::MatRef C) const {
    K.setZero();
    C.setZero();
    for (Index i = 0; i < u.size(); ++i) {
      K(i, i) = 100.0 * (1.0 + 90.0 * u[i] * u[i]);
      C(i, i) = 0.3 * v[i] * v[i];
    }
  }
};

// Effects plus a C++ functor equal the same laws declared as effects.
template <class Scheme>
void check_effects_plus_functor(const Scheme& scheme) {
  using namespace nvib::effects;
  const Index n = 3;
  std::vector<Effect> chain = {spring({{0, 1.0}}, 40.0), damper({{1, 1.0}, {0, -1.0}}, 0.4),
                               cubic_spring({{2, 1.0}, {1, -1.0}}, 25.0),
                               harmonic_force({{0, 1.0}, {2, 0.5}}, 3.0, 2.0)};
  std::vector<Effect> declared = chain;
  for (Index i = 0; i < n; ++i) {
    declared.push_back(hardening_spring({{i, 1.0}}, 100.0, 30.0));
    declared.push_back(power_damper({{i, 1.0}}, 0.1, 3.0));
  }
  const nvib::Mass mass = nvib::Mass::diagonal(Vector::LinSpaced(n, 1.0, 2.0));
  const auto plus = make_effect_model(mass, chain, Duffing{});
  const auto effects_only = make_effect_model(mass, declared);
  CHECK(plus.uses_velocity() && plus.uses_time() && !plus.is_linear() && plus.has_analytic_tangent());
  Vector u0(n), v0(n);
  u0 << 0.3, -0.2, 0.1;
  v0 << 0.0, 0.5, -0.4;
  const auto a = nvib::solve(plus, scheme, 1e-3, 0.5, u0, v0);
  const auto b = nvib::solve(effects_only, scheme, 1e-3, 0.5, u0, v0);
  const double scale = b.u.cwiseAbs().maxCoeff();
  CHECK((a.u - b.u).cwiseAbs().maxCoeff() <= 1e-12 * scale);
  CHECK(a.stats.num_force_evals == b.stats.num_force_evals);
  CHECK(a.stats.num_fd_force_evals == 0);
}

nvib::Newton one_iteration() {
  nvib::Newton nw;
  nw.iteration = nvib::NewtonMode::one_iteration;
  return nw;
}

template <class Fn>
bool throws_invalid(Fn&& fn) {
  try {
    fn();
  } catch (const std::invalid_argument&) {
    return true;
  }
  return false;
}

}  // namespace

int main() {
  for (double c : {0.0, 2.0 * 0.05 * kM * std::sqrt(kK / kM)}) {
    const double orders[] = {
        fitted_order(nvib::CentralDifference(), c),
        fitted_order(nvib::Zhai(), c),
        fitted_order(nvib::CEMDTS(0.45), c),
        fitted_order(nvib::CEMDTS(1.0 / 12.0), c),
        fitted_order(nvib::Newmark(), c),
        fitted_order(nvib::Newmark(0.25, 0.5, one_iteration()), c),
        fitted_order(nvib::GeneralizedAlpha(), c),
        fitted_order(nvib::GeneralizedAlpha::from_rho_inf(0.6), c)};
    const char* names[] = {"CentralDifference", "Zhai", "CEMDTS(0.45)", "CEMDTS(1/12)", "Newmark",
                           "Newmark one_iteration", "GeneralizedAlpha", "GeneralizedAlpha(0.6)"};
    // Measured: 1.999 to 2.000 undamped, 1.999 to 2.009 damped.
    for (int i = 0; i < 8; ++i) {
      std::printf("c = %g, %-22s fitted order %.3f\n", c, names[i], orders[i]);
      CHECK_CLOSE(orders[i], 2.0, 0.1);
    }
    // PIM on a linear model: the exponential is exact.
    CHECK(max_error(nvib::PreciseIntegration(), 0.05, c) < 1e-12);
  }

  // CEMDTS(0) is LCDM; Zhai(1/2, 1/2) has LCDM's displacements.
  {
    auto model = nvib::make_model(nvib::Mass::diagonal(Vector::Ones(1)), Hardening{});
    Vector u0 = Vector::Constant(1, 1.5), v0 = Vector::Zero(1);
    auto a = nvib::solve(model, nvib::CEMDTS(0.0), 1e-3, 0.3, u0, v0);
    auto b = nvib::solve(model, nvib::CentralDifference(), 1e-3, 0.3, u0, v0);
    auto z = nvib::solve(model, nvib::Zhai(), 1e-3, 0.3, u0, v0);
    CHECK((a.u - b.u).cwiseAbs().maxCoeff() < 1e-12 * 1.5);
    CHECK((a.v - b.v).cwiseAbs().maxCoeff() < 1e-12 * 100.0);
    CHECK((z.u - b.u).cwiseAbs().maxCoeff() < 1e-12 * 1.5);
    CHECK(b.stats.num_force_evals == 301);  // 300 steps + a0
  }

  // Failures reach a C++ caller as the documented exceptions.
  {
    nvib::Matrix K(1, 1);
    K << 1e6;
    auto stiff = nvib::make_linear_model(nvib::Mass::diagonal(Vector::Ones(1)), K);
    Vector u0 = Vector::Ones(1), v0 = Vector::Zero(1);
    bool diverged = false;
    try {
      nvib::solve(stiff, nvib::CentralDifference(), 3e-3, 10.0, u0, v0);  // omega h = 3 > 2
    } catch (const nvib::DivergenceError& e) {
      diverged = e.failure.dof == 0 && e.failure.step > 1;
    }
    CHECK(diverged);
    nvib::SolveOptions opt;
    opt.throw_on_failure = false;
    auto r = nvib::solve(stiff, nvib::CentralDifference(), 3e-3, 10.0, u0, v0, opt);
    CHECK(r.status == nvib::Status::diverged);
    CHECK(r.t.size() > 1 && r.t.size() < 3335);
    CHECK(r.u.allFinite());

    auto hard = nvib::make_model(nvib::Mass::diagonal(Vector::Ones(1)), Hardening{});
    nvib::Newton nw;
    nw.max_iter = 1;
    nw.rtol = 1e-14;
    bool newton_failed = false;
    try {
      nvib::solve(hard, nvib::Newmark(0.25, 0.5, nw), 0.05, 1.0, Vector::Constant(1, 1.5), v0);
    } catch (const nvib::ConvergenceError& e) {
      newton_failed = e.failure.residuals.size() == 2 && e.failure.step == 1;
    }
    CHECK(newton_failed);

    // The default bound (NaN in SolveOptions) is 1e10 x max(1, |u0|, |v0| T):
    // a diverging run stops there, naming the DOF, long before overflow.
    auto d = nvib::solve(stiff, nvib::CentralDifference(), 3e-3, 10.0, u0, v0, opt);
    CHECK(d.status == nvib::Status::diverged && d.failure.dof == 0);
    CHECK(d.failure.message.find("beyond the bound 1e+10") != std::string::npos);
    CHECK(d.u.cwiseAbs().maxCoeff() <= 1e10);
    CHECK(nvib::default_max_displacement(Vector::Constant(1, -3.0), Vector::Constant(1, 2.0), 5.0) == 1e11);
    nvib::SolveOptions unbounded = opt;
    unbounded.max_displacement = std::numeric_limits<double>::infinity();
    auto e = nvib::solve(stiff, nvib::CentralDifference(), 3e-3, 10.0, u0, v0, unbounded);
    CHECK(e.status == nvib::Status::diverged && e.failure.message.find("not finite") != std::string::npos);

    // An exception out of the step loop: by default it leaves as itself; with keep_partial as a
    // PartialRun carrying it and the history saved before it, with the counters of the steps taken.
    struct Stop {};
    struct StopsAtHalf {
      void operator()(const nvib::CVecRef& u, const nvib::CVecRef&, double t, nvib::VecRef out) const {
        if (t > 0.5) throw Stop{};
        out = 100.0 * u;
      }
    };
    auto stops = nvib::make_model(nvib::Mass::diagonal(Vector::Ones(1)), StopsAtHalf{});
    nvib::SolveOptions every10 = opt;
    every10.save_every = 10;
    bool plain = false;
    try {
      nvib::solve(stops, nvib::CentralDifference(), 1e-3, 1.0, u0, v0, every10);
    } catch (const Stop&) {
      plain = true;
    }
    CHECK(plain);
    every10.keep_partial = true;
    bool partial = false;
    try {
      nvib::solve(stops, nvib::CentralDifference(), 1e-3, 1.0, u0, v0, every10);
    } catch (const nvib::PartialRun& p) {
      const nvib::Result& h = p.partial;
      bool cause = false;
      try {
        std::rethrow_exception(p.cause);
      } catch (const Stop&) {
        cause = true;
      }
      // saved at steps 0, 10, ..., 500; the force at t = 0.501 (step 501) threw
      partial = cause && h.t.size() == 51 && h.u.rows() == 51 && std::abs(h.t[50] - 0.5) < 1e-12 &&
                h.u.allFinite() && h.stats.num_steps == 500 && h.stats.num_force_evals == 502;
    }
    CHECK(partial);

    // One iteration per step accepts each step after one solve, and reports
    // the residual it leaves; Newton reports at most about rtol.
    const Vector x0 = Vector::Constant(1, 1.5);
    auto none = nvib::solve(hard, nvib::Newmark(0.25, 0.5, one_iteration()), 1e-2, 0.3, x0, v0);
    auto newton = nvib::solve(hard, nvib::Newmark(), 1e-2, 0.3, x0, v0);
    auto expl = nvib::solve(hard, nvib::CEMDTS(), 1e-3, 0.3, x0, v0);
    CHECK(none.max_residual > 1e-3);
    CHECK(newton.max_residual <= 1e-9);
    CHECK(std::isnan(expl.max_residual));
    CHECK(none.stats.num_force_evals == 2 * 30 + 1);
    auto st = nvib::make_stepper(nvib::Newmark(0.25, 0.5, one_iteration()), hard, 1e-2);
    st.initialize(0.0, x0, v0);
    st.step();
    CHECK(st.last_residuals().size() == 2 && st.last_residuals()[1] > 0.0);
    CHECK(st.accepted_residual() > 0.0);

    // A tangent that overflows is divergence at that DOF, not a singular matrix.
    auto inf_tangent = nvib::make_model(nvib::Mass::diagonal(Vector::Ones(2)), OverflowingTangent{});
    nvib::SolveOptions quiet;
    quiet.throw_on_failure = false;
    auto f = nvib::solve(inf_tangent, nvib::Newmark(), 1e-2, 0.1, Vector::Ones(2), Vector::Zero(2), quiet);
    CHECK(f.status == nvib::Status::diverged && f.failure.dof == 1 && f.failure.step == 1);
    CHECK(f.failure.message.find("tangent of the forces is not finite at DOF 1") != std::string::npos);
  }

  // Validation names the parameter and never clamps.
  CHECK(throws_invalid([] { nvib::CEMDTS(-0.1); }));
  CHECK(throws_invalid([] { nvib::Zhai(0.5, 1.5); }));
  CHECK(throws_invalid([] { nvib::Newmark(0.0, 0.5); }));
  CHECK(throws_invalid([] { nvib::Newmark(0.25, 0.4); }));
  CHECK(throws_invalid([] { nvib::GeneralizedAlpha(0.6, 0.5); }));
  CHECK(throws_invalid([] { nvib::GeneralizedAlpha::from_rho_inf(1.5); }));
  CHECK(throws_invalid([] { nvib::PreciseIntegration(0); }));
  CHECK(throws_invalid([] { nvib::PreciseIntegration(20, 4); }));
  CHECK(throws_invalid([] { nvib::Mass::diagonal(Vector::Constant(2, -1.0)); }));
  CHECK(throws_invalid([] {
    nvib::Matrix M(2, 2);
    M << 1, 2, 2, 1;  // symmetric, indefinite
    nvib::Mass::dense(M);
  }));
  check_effects_plus_functor(nvib::CentralDifference());
  check_effects_plus_functor(nvib::CEMDTS(0.45));
  check_effects_plus_functor(nvib::Newmark());
  check_effects_plus_functor(nvib::GeneralizedAlpha::from_rho_inf(0.8));
  check_effects_plus_functor(nvib::PreciseIntegration());

  CHECK(nvib::steps_to_reach(0.0, 0.3, 1e-3) == 300);
  CHECK(nvib::steps_to_reach(0.0, 1.0, 0.3) == 4);

  // Peaks tracked over every step whatever save_every: max |u_i| and max |D u| equal those of the history
  // saved every step, while only steps 0, 1000, 2000 and the last are saved.
  {
    auto model = nvib::make_model(nvib::Mass::diagonal(Vector::Ones(2)), Hardening{});
    const Vector u0 = (Vector(2) << 1.5, -0.4).finished(), v0 = Vector::Zero(2);
    const auto full = nvib::solve(model, nvib::Newmark(), 1e-3, 2.5, u0, v0);
    nvib::SolveOptions opt;
    opt.save_every = 1000;
    opt.peaks = true;
    opt.peak_measures.resize(1, 2);
    opt.peak_measures.insert(0, 0) = -1.0;
    opt.peak_measures.insert(0, 1) = 1.0;
    const auto sparse = nvib::solve(model, nvib::Newmark(), 1e-3, 2.5, u0, v0, opt);
    CHECK(sparse.t.size() == 4);
    CHECK(sparse.peak_u.size() == 2 && sparse.peak_measures.size() == 1);
    CHECK(sparse.peak_u == full.u.cwiseAbs().colwise().maxCoeff().transpose());
    CHECK(sparse.peak_measures[0] == (full.u.col(1) - full.u.col(0)).cwiseAbs().maxCoeff());
    CHECK(full.peak_u.size() == 0 && std::isnan(full.peak_energy_error));  // not asked for
  }
  // The error estimate's constants: the principal eigenvalue's distance from exp(i w h) over (w h)^3 is
  // 1/24 for central differences (period error -(w h)^2/24) and 1/12 for the trapezoidal rule; a
  // first-order Newmark (gamma > 1/2) has a c2, and PIM, exact on linear modes, none (its estimate is
  // its own, below).
  {
    const auto cd = nvib::error_constants(nvib::CentralDifference());
    const auto nm = nvib::error_constants(nvib::Newmark());
    const auto damped = nvib::error_constants(nvib::Newmark(0.3025, 0.6));
    const auto pim = nvib::error_constants(nvib::PreciseIntegration());
    CHECK(std::abs(cd.c3 - 1.0 / 24.0) < 1e-3 / 24.0 && cd.c2 == 0.0 && cd.available);
    CHECK(std::abs(nm.c3 - 1.0 / 12.0) < 1e-3 / 12.0 && nm.c2 == 0.0 && nm.available);
    CHECK(std::abs(damped.c2 - 0.05) < 1e-3 && damped.available);  // (gamma - 1/2) / 2
    CHECK(!pim.available);
    // On by default, one value per DOF; off when asked.
    auto model = nvib::make_model(nvib::Mass::diagonal(Vector::Ones(2)), Hardening{});
    const Vector u0 = (Vector(2) << 1.5, -0.4).finished(), v0 = Vector::Zero(2);
    const auto on = nvib::solve(model, nvib::Newmark(), 1e-3, 1.0, u0, v0);
    CHECK(on.error_estimate.size() == 2 && on.error_estimate.allFinite() && on.error_estimate.maxCoeff() > 0.0);
    const auto coarse = nvib::solve(model, nvib::Newmark(), 2e-3, 1.0, u0, v0);
    const double ratio = coarse.error_estimate.maxCoeff() / on.error_estimate.maxCoeff();
    CHECK(ratio > 3.0 && ratio < 5.0);  // second order: 4
    nvib::SolveOptions off;
    off.error_estimate = false;
    CHECK(nvib::solve(model, nvib::Newmark(), 1e-3, 0.1, u0, v0, off).error_estimate.size() == 0);
    // PIM follows its own error (the remainder's interpolation, propagated): third order over the first
    // periods (over longer runs the hardening's amplitude-dependent phase drift escapes it, see
    // error_estimate.hpp), and the run it watches is the run without it, bit for bit.
    const auto pim_fine = nvib::solve(model, nvib::PreciseIntegration(), 5e-4, 0.3, u0, v0);
    const auto pim_coarse = nvib::solve(model, nvib::PreciseIntegration(), 1e-3, 0.3, u0, v0);
    const double pim_ratio = pim_coarse.error_estimate.maxCoeff() / pim_fine.error_estimate.maxCoeff();
    CHECK(pim_fine.error_estimate.size() == 2 && pim_fine.error_estimate.allFinite());
    CHECK(pim_ratio > 5.66 && pim_ratio < 11.32);  // 2^3 = 8 within half an order (measured 10.5)
    CHECK(nvib::solve(model, nvib::PreciseIntegration(), 5e-4, 0.3, u0, v0, off).u == pim_fine.u);
  }
  return nvib_test::finish("test_schemes");
}
