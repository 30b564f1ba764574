// A law of one's own in C++, without editing nvib's headers: two structs with the contract of the
// built-in laws (nvib/effects/law.hpp), made effects by nvib::effects::make_user_effect, in a two-storey
// shear frame under a ground motion, integrated with every scheme. The user's hardening spring does
// hardening_spring's arithmetic: its runs must equal the built-in law's bit for bit. The user's
// elastic-perfectly plastic spring (a law with memory) must follow the built-in bilinear law with b = 0
// within 1e-9 of the peak, as its return mapping is written differently (measured: bit for bit all the
// same). The program says so and fails otherwise (a ctest).
#include <nvib/nvib.hpp>

#include <cmath>
#include <cstdio>

namespace fx = nvib::effects;

// f = k0 (1 + a d^2) d, without memory.
struct UserHardening : fx::LawBase {
  static constexpr const char* key = "user_hardening";
  static constexpr const char* doc = "a hardening spring written by a user";
  static constexpr std::array<fx::Parameter, 2> parameters{{{"k0", fx::kRequired, "stiffness"},
                                                            {"a", fx::kRequired, "hardening coefficient"}}};
  struct Params {
    double k0, a;
  };
  static void validate(const double* x) { NVIB_CHECK(x[0] > 0.0, "k0", "must be > 0"); }
  static Params prepare(const double* x, const fx::Signal*) { return {x[0], x[1]}; }
  static double value(const Params& p, double d, double, double) { return p.k0 * (1.0 + p.a * d * d) * d; }
  static fx::Slopes slopes(const Params& p, double d, double, double) { return {p.k0 * (1.0 + 3.0 * p.a * d * d), 0.0}; }
  static bool is_linear(const Params&) { return false; }
};

// Elastic-perfectly plastic: stiffness k, strength fy; its plastic deformation is its memory.
struct UserElastoPlastic : fx::LawBase {
  static constexpr const char* key = "user_epp";
  static constexpr const char* doc = "an elastic-perfectly plastic spring written by a user";
  static constexpr std::array<fx::Parameter, 2> parameters{{{"k", fx::kRequired, "stiffness"},
                                                            {"fy", fx::kRequired, "yield force"}}};
  struct Params {
    double k, fy;
  };
  struct State {
    double dp;  // plastic deformation
    double d;   // the deformation it was committed at
  };
  static constexpr std::array<const char*, 2> state_names{{"plastic_deformation", "deformation"}};
  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "k", "must be > 0");
    NVIB_CHECK(x[1] > 0.0, "fy", "must be > 0");
  }
  static Params prepare(const double* x, const fx::Signal*) { return {x[0], x[1]}; }
  // A pure trial from the committed state: the elastic trial, returned to the yield surface if beyond it;
  // at the committed deformation on the surface, the loading slope (0), as the built-in law.
  static fx::Trial<State> trial(const Params& p, const State& c, double d, double, double) {
    fx::Trial<State> r{p.k * (d - c.dp), p.k, 0.0, {c.dp, d}};
    const double excess = std::abs(r.f) - p.fy;
    if (d == c.d) {
      if (excess >= -1e-9 * p.fy) r.kd = 0.0;
    } else if (excess > 0.0) {
      const double s = r.f > 0.0 ? 1.0 : -1.0;
      r.state.dp += s * excess / p.k;
      r.f = s * p.fy;
      r.kd = 0.0;
    }
    return r;
  }
  static double recoverable(const Params& p, const State& s, double d) { return 0.5 * p.k * (d - s.dp) * (d - s.dp); }
  static bool is_linear(const Params&) { return false; }
};

// Two storeys of 1e5 kg on `first` and `second`, dampers, and a ground motion 3 sin(5 t) m/s^2.
nvib::Model<fx::EffectSet> frame(fx::Effect first, fx::Effect second) {
  std::vector<fx::Effect> effects{std::move(first), std::move(second),
                                  fx::make_effect("damper", {{0, 1.0}}, {{"c", 2e5}}),
                                  fx::make_effect("damper", {{1, 1.0}, {0, -1.0}}, {{"c", 2e5}}),
                                  fx::make_effect("ground_acceleration", {{0, 1.0}, {1, 1.0}}, {},
                                                  fx::Signal::sine(3.0, 5.0, 0.0))};
  return fx::make_effect_model(nvib::Mass::diagonal(nvib::Vector::Constant(2, 1e5)), std::move(effects));
}

template <class Scheme>
bool compare(const char* label, const Scheme& scheme) {
  const nvib::Vector zero = nvib::Vector::Zero(2);
  const double k0 = 1e8, a = 10.0, k = 2e7, fy = 3e4;
  auto builtin = frame(fx::make_effect("hardening_spring", {{0, 1.0}}, {{"k0", k0}, {"a", a}}),
                       fx::make_effect("bilinear", {{1, 1.0}, {0, -1.0}}, {{"k", k}, {"fy", fy}, {"b", 0.0}}));
  auto user = frame(fx::make_user_effect<UserHardening>({{0, 1.0}}, {k0, a}),
                    fx::make_user_effect<UserElastoPlastic>({{1, 1.0}, {0, -1.0}}, {k, fy}));
  const nvib::Result r1 = nvib::solve(builtin, scheme, 2e-3, 4.0, zero, zero);
  const nvib::Result r2 = nvib::solve(user, scheme, 2e-3, 4.0, zero, zero);
  const double peak = r1.u.cwiseAbs().maxCoeff();
  const double x1 = (r1.u.col(0) - r2.u.col(0)).cwiseAbs().maxCoeff();  // the hardening storey's DOF
  const double x2 = (r1.u - r2.u).cwiseAbs().maxCoeff() / peak;
  const double drift = (r1.u.col(1) - r1.u.col(0)).cwiseAbs().maxCoeff();
  const bool yielded = drift > 1.5 * fy / k;
  const bool ok = x2 <= 1e-9 && yielded;
  std::printf("%-10s both storeys: max |u_user - u_builtin| = %.2e of the peak (x1 alone %.2e m); drift %.3g m "
              "(yield at %.3g m) %s\n",
              label, x2, x1, drift, fy / k, ok ? "ok" : "FAILED");
  return ok;
}

// Alone on a one-storey model the user's hardening spring is the built-in one bit for bit.
template <class Scheme>
bool bit_for_bit(const char* label, const Scheme& scheme) {
  const nvib::Vector u0 = nvib::Vector::Constant(1, 0.05), v0 = nvib::Vector::Zero(1);
  auto mass = nvib::Mass::diagonal(nvib::Vector::Constant(1, 1e5));
  auto builtin = fx::make_effect_model(mass, {fx::make_effect("hardening_spring", {{0, 1.0}}, {{"k0", 1e8}, {"a", 10.0}})});
  auto user = fx::make_effect_model(mass, {fx::make_user_effect<UserHardening>({{0, 1.0}}, {1e8, 10.0})});
  const nvib::Result r1 = nvib::solve(builtin, scheme, 1e-3, 1.0, u0, v0);
  const nvib::Result r2 = nvib::solve(user, scheme, 1e-3, 1.0, u0, v0);
  const bool ok = r1.u == r2.u && r1.v == r2.v;
  std::printf("%-10s hardening alone: bit for bit %s\n", label, ok ? "ok" : "FAILED");
  return ok;
}

int main() {
  bool ok = true;
  ok &= bit_for_bit("LCDM", nvib::CentralDifference()) && compare("LCDM", nvib::CentralDifference());
  ok &= bit_for_bit("CEMDTS", nvib::CEMDTS(0.45)) && compare("CEMDTS", nvib::CEMDTS(0.45));
  ok &= bit_for_bit("Zhai", nvib::Zhai(0.5, 0.5)) && compare("Zhai", nvib::Zhai(0.5, 0.5));
  ok &= bit_for_bit("Newmark", nvib::Newmark(0.25, 0.5)) && compare("Newmark", nvib::Newmark(0.25, 0.5));
  ok &= bit_for_bit("GalphaM", nvib::GeneralizedAlpha(0.5, 0.5, 0.25, 0.5)) &&
        compare("GalphaM", nvib::GeneralizedAlpha(0.5, 0.5, 0.25, 0.5));
  ok &= bit_for_bit("PIM", nvib::PreciseIntegration(20, 2)) && compare("PIM", nvib::PreciseIntegration(20, 2));
  std::printf("%s\n", ok ? "user laws: ok" : "user laws: FAILED");
  return ok ? 0 : 1;
}
