// The exact elastic spectrum (solve/spectrum.hpp) against closed forms derived here: the step
// a_g = A and the ramp a_g = c t are linear between any samples, so the kernel must match their
// continuous-time peaks to round-off, including peaks that fall between samples, periods shorter
// than the step, zeta = 0, 0 < zeta < 1, zeta = 1, zeta > 1, and the free vibration after the record.
#include <nvib/solve/spectrum.hpp>

#include <cstdio>
#include <functional>
#include <string>

#include "check.hpp"

using nvib::Vector;
constexpr double kPi = 3.14159265358979323846;

namespace {

// max |F| over [a, b]: a grid, then golden sections around the best point (a value accurate to round-off)
double max_abs(const std::function<double(double)>& F, double a, double b, double* where = nullptr) {
  const int n = 20000;
  int best = 0;
  double bv = -1.0;
  for (int i = 0; i <= n; ++i) {
    const double v = std::abs(F(a + (b - a) * i / n));
    if (v > bv) bv = v, best = i;
  }
  double lo = a + (b - a) * std::max(best - 1, 0) / n, hi = a + (b - a) * std::min(best + 1, n) / n;
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 200 && hi - lo > 1e-15 * (1.0 + std::abs(hi)); ++it) {
    const double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
    if (std::abs(F(x1)) > std::abs(F(x2))) hi = x2;
    else lo = x1;
  }
  const double x = 0.5 * (lo + hi);
  if (where) *where = x;
  return std::max(bv, std::abs(F(x)));
}

Vector constant_record(double A, int n) { return Vector::Constant(n, A); }
Vector ramp_record(double c, double dt, int n) {
  Vector g(n);
  for (int i = 0; i < n; ++i) g[i] = c * dt * i;
  return g;
}

bool rel(double a, double b, double tol) { return std::abs(a - b) <= tol * std::abs(b); }
#define CHECK_REL(a, b, tol)                                                                          \
  do {                                                                                                \
    const double x_ = (a), y_ = (b);                                                                  \
    CHECK(rel(x_, y_, tol));                                                                          \
    if (!rel(x_, y_, tol)) std::printf("  %s = %.17g, %s = %.17g, rel %.3g\n", #a, x_, #b, y_, std::abs(x_ - y_) / std::abs(y_)); \
  } while (0)

nvib::ElasticSpectrum one(const Vector& g, double dt, double T, double zeta, bool free_vibration) {
  nvib::ElasticSpectrumOptions opt;
  opt.free_vibration = free_vibration;
  return nvib::elastic_spectrum(g, dt, Vector::Constant(1, T), Vector::Constant(1, zeta), opt);
}

// Step a_g = A, underdamped: u = -(A/w^2)(1 - e^{-alpha t}(cos wd t + alpha/wd sin wd t)),
// v = -(A/wd) e^{-alpha t} sin wd t; first peak of u at pi/wd: (A/w^2)(1 + e^{-alpha pi/wd}).
void step_underdamped(double T, double zeta, double dt, double L) {
  const double A = 3.0, w = 2.0 * kPi / T, al = zeta * w, wd = w * std::sqrt(1.0 - zeta * zeta);
  const int n = static_cast<int>(std::round(L / dt)) + 1;
  const auto s = one(constant_record(A, n), dt, T, zeta, false);
  auto u = [&](double t) { return -(A / (w * w)) * (1.0 - std::exp(-al * t) * (std::cos(wd * t) + al / wd * std::sin(wd * t))); };
  auto v = [&](double t) { return -(A / wd) * std::exp(-al * t) * std::sin(wd * t); };
  auto abs_a = [&](double t) { return -(2.0 * al * v(t) + w * w * u(t)); };
  const double tend = dt * (n - 1);
  CHECK_REL(s.Sd[0], (A / (w * w)) * (1.0 + std::exp(-al * kPi / wd)), 1e-12);
  if (zeta > 0.0) CHECK_CLOSE(s.t_Sd[0], kPi / wd, 1e-8 * dt);  // undamped: every peak is as large
  CHECK_REL(s.Sd[0], max_abs(u, 0.0, tend), 1e-12);
  CHECK_REL(s.Sv[0], max_abs(v, 0.0, tend), 1e-12);
  CHECK_REL(s.Sa[0], max_abs(abs_a, 0.0, tend), 1e-12);
  CHECK_REL(s.PSa[0], w * w * s.Sd[0], 1e-15);
  CHECK_REL(s.PSv[0], w * s.Sd[0], 1e-15);
  // the kernel's peak is never below the record's samples' peak
  double sampled = 0.0;
  for (int i = 0; i < n; ++i) sampled = std::max(sampled, std::abs(u(dt * i)));
  CHECK(s.Sd[0] >= sampled * (1.0 - 1e-14));
}

}  // namespace

int main() {
  // the peak falls mid-interval: T = 0.05 s, dt = 0.01 s, first peak at 0.025 s, the samples miss it by > 1 %
  {
    const double A = 2.0, T = 0.05, zeta = 0.02, dt = 0.01, w = 2.0 * kPi / T, al = zeta * w;
    const double wd = w * std::sqrt(1.0 - zeta * zeta);
    const auto s = one(constant_record(A, 101), dt, T, zeta, false);
    const double exact = (A / (w * w)) * (1.0 + std::exp(-al * kPi / wd));
    double sampled = 0.0;
    for (int i = 0; i < 101; ++i) {
      const double t = dt * i;
      sampled = std::max(sampled, (A / (w * w)) * std::abs(1.0 - std::exp(-al * t) * (std::cos(wd * t) + al / wd * std::sin(wd * t))));
    }
    CHECK(sampled < 0.99 * exact);
    CHECK_REL(s.Sd[0], exact, 1e-12);
  }
  for (double zeta : {0.0, 0.02, 0.05, 0.3, 0.9}) {
    step_underdamped(0.05, zeta, 0.01, 1.0);   // w h = 1.26: closed-form intervals
    step_underdamped(1.0, zeta, 0.01, 3.0);    // w h = 0.063: Taylor intervals
    step_underdamped(0.003, zeta, 0.01, 0.2);  // period shorter than the step: several extrema per interval
    step_underdamped(0.0123, zeta, 0.005, 0.2);
  }
  // Ramp a_g = c t, zeta = 0: u = -(c/w^2)(t - sin(w t)/w) grows monotonically; after the record the free
  // vibration's amplitude sqrt(u_L^2 + (v_L/w)^2) is Sd, and w Sd, w^2 Sd are Sv, Sa
  for (double T : {0.02, 0.3, 2.0, 10.0}) {
    const double c = 1.5, dt = 0.01, L = 4.0, w = 2.0 * kPi / T;
    const int n = 401;
    const auto s = one(ramp_record(c, dt, n), dt, T, 0.0, true);
    const double uL = -(c / (w * w)) * (L - std::sin(w * L) / w), vL = -(c / (w * w)) * (1.0 - std::cos(w * L));
    const double amp = std::sqrt(uL * uL + vL * vL / (w * w));
    CHECK_REL(s.Sd[0], amp, 1e-12);
    CHECK_REL(s.Sv[0], w * amp, 1e-12);
    CHECK_REL(s.Sa[0], w * w * amp, 1e-12);
    // without the free vibration: Sd = |u(L)| at the last sample
    const auto r = one(ramp_record(c, dt, n), dt, T, 0.0, false);
    CHECK_REL(r.Sd[0], std::abs(uL), 1e-12);
  }
  // Ramp, damped: x = t - 2 zeta/w + e^{-alpha t}((2 zeta/w) cos wd t - ((1 - 2 zeta^2)/wd) sin wd t), u = -(c/w^2) x
  for (double zeta : {0.02, 0.05, 0.5}) {
    for (double T : {0.02, 0.5, 3.0}) {
      const double c = 1.5, dt = 0.01, w = 2.0 * kPi / T, al = zeta * w, wd = w * std::sqrt(1.0 - zeta * zeta);
      const int n = 301;
      const double L = dt * (n - 1);
      const auto s = one(ramp_record(c, dt, n), dt, T, zeta, false);
      auto u = [&](double t) {
        return -(c / (w * w)) * (t - 2.0 * zeta / w + std::exp(-al * t) * ((2.0 * zeta / w) * std::cos(wd * t) - ((1.0 - 2.0 * zeta * zeta) / wd) * std::sin(wd * t)));
      };
      auto v = [&](double t) { return -(c / (w * w)) * (1.0 - std::exp(-al * t) * (std::cos(wd * t) + al / wd * std::sin(wd * t))); };
      auto abs_a = [&](double t) { return -(2.0 * al * v(t) + w * w * u(t)); };
      CHECK_REL(s.Sd[0], max_abs(u, 0.0, L), 1e-12);
      CHECK_REL(s.Sv[0], max_abs(v, 0.0, L), 1e-12);
      CHECK_REL(s.Sa[0], max_abs(abs_a, 0.0, L), 1e-12);
    }
  }
  // Critical damping, step A for L, then free vibration e^{-w tau}(p + q tau)
  for (double T : {0.004, 0.05, 1.0}) {
    const double A = 1.0, dt = 0.01, w = 2.0 * kPi / T;
    const int n = 41;
    const double L = dt * (n - 1);
    const auto s = one(constant_record(A, n), dt, T, 1.0, true);
    auto u_rec = [&](double t) { return -(A / (w * w)) * (1.0 - std::exp(-w * t) * (1.0 + w * t)); };
    auto v_rec = [&](double t) { return -A * t * std::exp(-w * t); };
    const double uL = u_rec(L), vL = v_rec(L);
    auto u = [&](double t) { return t <= L ? u_rec(t) : std::exp(-w * (t - L)) * (uL + (vL + w * uL) * (t - L)); };
    auto v = [&](double t) {
      if (t <= L) return v_rec(t);
      const double aL = -2.0 * w * vL - w * w * uL;
      return std::exp(-w * (t - L)) * (vL + (aL + w * vL) * (t - L));
    };
    auto abs_a = [&](double t) { return -(2.0 * w * v(t) + w * w * u(t)); };
    const double horizon = L + 40.0 / w;
    CHECK_REL(s.Sd[0], max_abs(u, 0.0, horizon), 1e-11);
    CHECK_REL(s.Sv[0], max_abs(v, 0.0, horizon), 1e-11);
    CHECK_REL(s.Sa[0], max_abs(abs_a, 0.0, horizon), 1e-11);
  }
  // Overdamped zeta = 2, step: u = -(A/w^2)(1 + C1 e^{l1 t} + C2 e^{l2 t}), C1 = l2/(l1 - l2), C2 = -l1/(l1 - l2)
  for (double T : {0.004, 0.05, 1.0}) {
    const double A = 1.0, dt = 0.01, zeta = 2.0, w = 2.0 * kPi / T;
    const double l1 = -w * (zeta - std::sqrt(zeta * zeta - 1.0)), l2 = -w * (zeta + std::sqrt(zeta * zeta - 1.0));
    const double C1 = l2 / (l1 - l2), C2 = -l1 / (l1 - l2);
    const int n = 51;
    const double L = dt * (n - 1);
    const auto s = one(constant_record(A, n), dt, T, zeta, false);
    auto u = [&](double t) { return -(A / (w * w)) * (1.0 + C1 * std::exp(l1 * t) + C2 * std::exp(l2 * t)); };
    auto v = [&](double t) { return -(A / (w * w)) * (C1 * l1 * std::exp(l1 * t) + C2 * l2 * std::exp(l2 * t)); };
    auto abs_a = [&](double t) { return -(2.0 * zeta * w * v(t) + w * w * u(t)); };
    CHECK_REL(s.Sd[0], max_abs(u, 0.0, L), 1e-11);
    CHECK_REL(s.Sv[0], max_abs(v, 0.0, L), 1e-11);
    CHECK_REL(s.Sa[0], max_abs(abs_a, 0.0, L), 1e-11);
  }
  // rotated components: a2 = 0 gives |cos theta| Sd of a1; a2 = a1 gives |cos theta + sin theta| Sd
  {
    Vector a1 = ramp_record(1.0, 0.01, 301), zero = Vector::Zero(301), angles(4);
    for (int i = 0; i < 301; ++i) a1[i] = std::sin(0.37 * i) * std::exp(-0.01 * i);
    angles << 0.0, 30.0, 45.0, 120.0;
    const Vector P = (Vector(3) << 0.013, 0.4, 2.0).finished(), Z = Vector::Constant(1, 0.05);
    const auto s = nvib::elastic_spectrum(a1, 0.01, P, Z);
    const nvib::Matrix one = nvib::rotated_sd(a1, zero, 0.01, P, Z, angles);
    const nvib::Matrix two = nvib::rotated_sd(a1, a1, 0.01, P, Z, angles);
    for (int k = 0; k < 4; ++k) {
      const double th = angles[k] * kPi / 180.0;
      for (int i = 0; i < 3; ++i) {
        CHECK_REL(one(k, i), std::abs(std::cos(th)) * s.Sd[i], 1e-12);
        CHECK_REL(two(k, i), std::abs(std::cos(th) + std::sin(th)) * s.Sd[i], 1e-12);
      }
    }
  }
  // errors name the argument
  auto names = [](const std::function<void()>& f, const std::string& arg) {
    try {
      f();
    } catch (const nvib::ArgumentError& e) {
      return e.argument() == arg;
    }
    return false;
  };
  const Vector g = Vector::Constant(10, 1.0), P = Vector::Constant(2, 1.0), Z = Vector::Constant(1, 0.05);
  CHECK(names([&] { nvib::elastic_spectrum(g, 0.0, P, Z); }, "dt"));
  CHECK(names([&] { nvib::elastic_spectrum(g, 0.01, Vector::Constant(1, -1.0), Z); }, "periods"));
  CHECK(names([&] { nvib::elastic_spectrum(g, 0.01, Vector::Constant(1, NAN), Z); }, "periods"));
  CHECK(names([&] { nvib::elastic_spectrum(g, 0.01, P, Vector::Constant(1, -0.1)); }, "damping"));
  CHECK(names([&] { nvib::elastic_spectrum(g, 0.01, P, Vector::Constant(3, 0.1)); }, "damping"));
  CHECK(names([&] { nvib::elastic_spectrum(Vector::Constant(1, 1.0), 0.01, P, Z); }, "ag"));
  Vector bad = g;
  bad[3] = INFINITY;
  CHECK(names([&] { nvib::elastic_spectrum(bad, 0.01, P, Z); }, "ag"));
  CHECK(names([&] { nvib::elastic_spectrum_at(Vector::LinSpaced(10, 1.0, 0.0), g, P, Z); }, "times"));
  return nvib_test::finish("test_spectrum");
}
