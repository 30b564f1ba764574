// Hardening oscillator m x'' + k0 (1 + a x^2) x = 0 (Yang et al. 2017, section 4.2)
// integrated with every scheme through a C++ functor; prints the final state,
// the maximum relative energy error and the counters.
#include <nvib/nvib.hpp>

#include <cstdio>

struct Hardening {
  double k0 = 100.0, a = 30.0;
  void operator()(const nvib::CVecRef& u, const nvib::CVecRef&, double, nvib::VecRef out) const {
    out[0] = k0 * (1.0 + a * u[0] * u[0]) * u[0];
  }
  void tangent(const nvib::CVecRef& u, const nvib::CVecRef&, double, nvib::MatRef K, nvib::MatRef C) const {
    K(0, 0) = k0 * (1.0 + 3.0 * a * u[0] * u[0]);
    C(0, 0) = 0.0;
  }
  bool uses_velocity() const { return false; }
  bool uses_time() const { return false; }
  double energy(double x, double v) const { return 0.5 * v * v + k0 * (0.5 * x * x + 0.25 * a * x * x * x * x); }
};

template <class Scheme>
void run(const char* label, const Scheme& scheme) {
  const Hardening f;
  auto model = nvib::make_model(nvib::Mass::diagonal(nvib::Vector::Ones(1)), f);
  nvib::Vector u0(1), v0(1);
  u0 << 1.5;
  v0 << 0.0;
  const nvib::Result r = nvib::solve(model, scheme, 1e-3, 0.3, u0, v0);
  const double e0 = f.energy(u0[0], v0[0]);
  double worst = 0.0;
  for (nvib::Index i = 0; i < r.t.size(); ++i)
    worst = std::max(worst, std::abs(f.energy(r.u(i, 0), r.v(i, 0)) - e0) / e0);
  std::printf("%-12s x(0.3) = %+.10f  v(0.3) = %+.8f  max rel. energy error %.3e  force evals %lld\n", label,
              r.u(r.t.size() - 1, 0), r.v(r.t.size() - 1, 0), worst,
              static_cast<long long>(r.stats.num_force_evals));
}

int main() {
  run("LCDM", nvib::CentralDifference());
  run("CEMDTS", nvib::CEMDTS(0.45));
  run("Zhai", nvib::Zhai(0.5, 0.5));
  run("Newmark", nvib::Newmark(0.25, 0.5));
  run("GalphaM", nvib::GeneralizedAlpha(0.5, 0.5, 0.25, 0.5));
  run("PIM", nvib::PreciseIntegration(20, 2));
  return 0;
}
