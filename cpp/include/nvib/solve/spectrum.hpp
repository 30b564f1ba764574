// Exact elastic response spectra: the linear SDOF
//
//     u'' + 2 zeta w u' + w^2 u = -a_g(t),   u(t0) = u'(t0) = 0   (unit mass, w = 2 pi / T)
//
// under a ground acceleration that is linear between its samples has a closed-form solution over
// each interval (Nigam & Jennings 1969; Chopra, Dynamics of Structures, §5.2): the state at the
// samples follows a fixed linear recurrence, and between them the peaks are located exactly. For
// each oscillator (T, zeta):
//
//   Sd = max |u|, Sv = max |u'| (relative), PSv = w Sd, PSa = w^2 Sd,
//   Sa = max |u'' + a_g| = max |2 zeta w u' + w^2 u| (absolute acceleration),
//
// the maxima over the continuous time of the record and of the free vibration after it (a_g = 0
// past the last sample), with the times at which they occur.
//
// Between samples: on an interval, u^(k) for k >= 2 is a homogeneous solution of the oscillator
// (the particular solution under a linear load is linear), so the zeros of u'' and u''' are known in
// closed form (homogeneous_zeros). Sd's extremum is a zero of u', which is monotone between the
// zeros of u'': a bracketed Newton iteration finds it. Sv's extrema are the zeros of u'' themselves.
// Sa = |f| with f = u'' + a_g, f' = u''' + da_g/dt monotone between the zeros of u'''': as Sd.
// Only the intervals whose peak can exceed the current one are searched: the energy
// R = sqrt(u'^2 + w^2 u^2) grows by at most |a_g| per unit time (dR/dt <= |a_g|), so over an
// interval |u| <= R/w, |u'| <= R and |u'' + a_g| <= sqrt(w^2 + 4 zeta^2 w^2) R are bounds.
//
// Free vibration after the record: each of u, u', u'' is then a damped sinusoid (or for zeta >= 1
// a sum of decaying exponentials), whose successive extrema shrink, so its peak is its first
// extremum: one closed-form zero, no time stepping.
//
// Accuracy: the recurrence's coefficients come from the closed form when w h > 1 and from its Taylor
// series (to round-off) when w h <= 1, where the closed form cancels (c0 ~ a_g / w^2 against u).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "../base/compiler.hpp"
#include "../base/errors.hpp"
#include "../base/format.hpp"
#include "../base/types.hpp"

namespace nvib {

// The spectrum of one record at n oscillators (period, damping), flat: entry i is (periods[i],
// damping[i]). t_* are the times of the peaks (from the record's first sample's time).
struct ElasticSpectrum {
  Vector periods, damping;
  Vector Sd, Sv, PSv, PSa, Sa;
  Vector t_Sd, t_Sv, t_Sa;
};

struct ElasticSpectrumOptions {
  bool free_vibration = true;  // include the free vibration after the record (a_g = 0 past its end)
};

namespace spectrum_detail {

constexpr double kPi = 3.14159265358979323846;

// The oscillator u'' + 2 alpha u' + w2 u = -g(t): alpha = zeta w. Its homogeneous solution from
// (r0, r1) at 0 is e^{-alpha t} (r0 C(t) + (r1 + alpha r0) S(t)) with C, S = cos(mu t), sin(mu t)/mu
// (zeta < 1, mu = w sqrt(1 - zeta^2)), 1, t (zeta = 1), cosh(mu t), sinh(mu t)/mu (zeta > 1).
struct Oscillator {
  double w, zeta, alpha, w2, mu, rate;  // rate: the largest |eigenvalue| (Taylor series' radius)
  int regime;                           // 0 underdamped, 1 critical, 2 overdamped

  Oscillator(double period, double z) : w(2.0 * kPi / period), zeta(z) {
    alpha = zeta * w;
    w2 = w * w;
    if (zeta < 1.0) {
      regime = 0;
      mu = w * std::sqrt((1.0 - zeta) * (1.0 + zeta));
      rate = w;
    } else if (zeta == 1.0) {
      regime = 1;
      mu = 0.0;
      rate = w;
    } else {
      regime = 2;
      mu = w * std::sqrt((zeta - 1.0) * (zeta + 1.0));
      rate = alpha + mu;
    }
  }

  // e^{-alpha t} C(t) and e^{-alpha t} S(t), without overflow for a large overdamped alpha t.
  void eCS(double t, double& ec, double& es) const {
    if (regime == 0) {
      const double e = std::exp(-alpha * t);
      ec = e * std::cos(mu * t);
      es = e * std::sin(mu * t) / mu;
    } else if (regime == 1) {
      const double e = std::exp(-alpha * t);
      ec = e;
      es = e * t;
    } else if (mu * t < 0.5) {
      const double e = std::exp(-alpha * t);
      ec = e * std::cosh(mu * t);
      es = e * std::sinh(mu * t) / mu;
    } else {  // e^{-alpha t} cosh(mu t) = (e^{(mu - alpha) t} + e^{-(mu + alpha) t}) / 2, mu - alpha = -w^2/(alpha + mu)
      const double slow = std::exp(-w2 / (alpha + mu) * t), fast = std::exp(-(alpha + mu) * t);
      ec = 0.5 * (slow + fast);
      es = 0.5 * (slow - fast) / mu;
    }
  }

  // The homogeneous solution from (r0, r1) at 0, and its derivative, at t.
  void homogeneous(double t, double r0, double r1, double& x, double& dx) const {
    double ec, es;
    eCS(t, ec, es);
    x = r0 * ec + (r1 + alpha * r0) * es;
    const double r2 = -2.0 * alpha * r1 - w2 * r0;
    dx = r1 * ec + (r2 + alpha * r1) * es;
  }

  // Calls f(t) for each zero t in (0, t_max) of the homogeneous solution from (r0, r1), in order,
  // until f returns false.
  // Underdamped: r0 C + b S = 0 with b = r1 + alpha r0 is R cos(mu t - phi) = 0, phi = atan2(b, r0 mu),
  // zeros at mu t = phi + pi/2 + k pi. Critical: r0 + b t = 0. Overdamped: tanh(mu t) = -r0 mu / b.
  template <class F>
  void homogeneous_zeros(double r0, double r1, double t_max, F&& f) const {
    const double b = r1 + alpha * r0;
    if (regime == 0) {
      if (r0 == 0.0 && b == 0.0) return;
      double x = std::atan2(b, r0 * mu) + 0.5 * kPi;  // in (-pi/2, 3pi/2]
      if (x > kPi) x -= kPi;
      if (x <= 0.0) x += kPi;  // the first zero after 0, in (0, pi]
      for (; x < mu * t_max; x += kPi)
        if (!f(x / mu)) return;
    } else if (regime == 1) {
      if (b != 0.0) {
        const double t = -r0 / b;
        if (t > 0.0 && t < t_max) f(t);
      }
    } else if (b != 0.0) {
      const double q = -r0 * mu / b;
      if (q > 0.0 && q < 1.0) {
        const double t = std::atanh(q) / mu;
        if (t < t_max) f(t);
      }
    }
  }
};

// The state (u, u') at t in an interval starting at (u0, v0) under g(t) = g0 + s t. Taylor series
// of the exact solution when rate t <= 1 (its terms fall like (rate t)^n / n!; 24 terms reach
// round-off), the closed form otherwise (particular solution c0 + c1 t).
inline void interval_state(const Oscillator& o, double t, double u0, double v0, double g0, double s, double& u,
                           double& v) {
  const double x = o.rate * t;
  if (x <= 1.0) {
    // u = sum d_n t^n / n!, v = sum d_{n+1} t^n / n!, with d_0 = u0, d_1 = v0 and from the equation
    // d_2 = -g0 - 2 alpha d_1 - w2 d_0, d_3 = -s - 2 alpha d_2 - w2 d_1, d_{n+2} = -2 alpha d_{n+1} - w2 d_n;
    // the terms beyond n fall below x^n / n! of the largest: stopped at 1e-17
    static constexpr double inv[24] = {1.0,      1.0,      1.0 / 2,  1.0 / 3,  1.0 / 4,  1.0 / 5,
                                       1.0 / 6,  1.0 / 7,  1.0 / 8,  1.0 / 9,  1.0 / 10, 1.0 / 11,
                                       1.0 / 12, 1.0 / 13, 1.0 / 14, 1.0 / 15, 1.0 / 16, 1.0 / 17,
                                       1.0 / 18, 1.0 / 19, 1.0 / 20, 1.0 / 21, 1.0 / 22, 1.0 / 23};
    double dn = u0, dn1 = v0, dn2 = -g0 - 2.0 * o.alpha * v0 - o.w2 * u0;
    double fac = 1.0, size = 1.0;  // t^n / n!, x^n / n!
    u = 0.0;
    v = 0.0;
    for (int n = 0; n < 23 && size > 1e-17; ++n) {
      u += dn * fac;
      v += dn1 * fac;
      const double next = (n == 0 ? -s : 0.0) - 2.0 * o.alpha * dn2 - o.w2 * dn1;
      dn = dn1;
      dn1 = dn2;
      dn2 = next;
      fac *= t * inv[n + 1];
      size *= x * inv[n + 1];
    }
    return;
  }
  const double c1 = -s / o.w2;
  const double c0 = (-g0 - 2.0 * o.alpha * c1) / o.w2;
  double uh, vh;
  o.homogeneous(t, u0 - c0, v0 - c1, uh, vh);
  u = uh + c0 + c1 * t;
  v = vh + c1;
}

// One interval of the record: start state, load g0 + s t over [0, h].
struct Interval {
  double h, u0, v0, g0, s;
};

// The spectral quantity f at t in the interval and its first two derivatives.
// kind 0: f = u (Sd); kind 1: f = u' (Sv); kind 2: f = u'' + g = -(2 alpha u' + w2 u) (Sa).
inline void quantity(const Oscillator& o, const Interval& I, int kind, double t, double& f, double& df,
                     double& ddf) {
  double u, v;
  interval_state(o, t, I.u0, I.v0, I.g0, I.s, u, v);
  const double g = I.g0 + I.s * t;
  const double a = -g - 2.0 * o.alpha * v - o.w2 * u;  // u''
  if (kind == 0) {
    f = u, df = v, ddf = a;
    return;
  }
  const double j = -I.s - 2.0 * o.alpha * a - o.w2 * v;  // u'''
  if (kind == 1) {
    f = v, df = a, ddf = j;
    return;
  }
  f = a + g, df = j + I.s, ddf = -2.0 * o.alpha * j - o.w2 * a;
}

struct Peak {
  double value = 0.0, time = 0.0;
  void offer(double x, double t) {
    if (std::abs(x) > value) value = std::abs(x), time = t;
  }
};

// The values of f, f', f'' at an interval's ends, and of f''' at its start, for one quantity.
struct Ends {
  double f0, f1, g0, g1, c0, c1, d0;
};

// The extremum of f in [lo, hi], where f' is monotone and goes from glo to ghi of opposite signs:
// Newton's iteration on f' kept inside the bracket (bisection when a step leaves it), from the
// secant point. f is returned at the last iterate, within 1e-9 h of the zero: f is flat there, so
// its error is below (1e-9 w h)^2 of f.
inline void bracketed_extremum(const Oscillator& o, const Interval& I, int kind, double lo, double hi, double glo,
                               double ghi, double& f_ext, double& t_ext) {
  double f = 0.0, g, dg;
  double t = lo + (hi - lo) * glo / (glo - ghi);
  const double tol = 1e-9 * I.h;
  for (int it = 0; it < 100; ++it) {
    quantity(o, I, kind, t, f, g, dg);
    if (g == 0.0) break;
    if ((g > 0.0) == (glo > 0.0)) lo = t, glo = g;
    else hi = t;
    double next = t - g / dg;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - t) <= tol) break;
    t = next;
  }
  f_ext = f;
  t_ext = t;
}

// The peak of |f| strictly inside the interval, offered to `peak` (times from t_start).
// Sv: f' = u'' is a homogeneous solution: its zeros (closed form) are the extrema. Sd, Sa: the
// zeros of f' lie between those of f'' (homogeneous, closed form), where f' is monotone.
NVIB_NOINLINE inline void search_interval(const Oscillator& o, const Interval& I, int kind, const Ends& e,
                                          double t_start, Peak& peak) {
  double f, df, ddf;
  if (kind == 1) {
    o.homogeneous_zeros(e.g0, e.c0, I.h, [&](double t) {
      quantity(o, I, kind, t, f, df, ddf);
      peak.offer(f, t_start + t);
      return true;
    });
    return;
  }
  double lo = 0.0, glo = e.g0;
  auto piece = [&](double hi, double ghi) {
    if ((glo < 0.0 && ghi > 0.0) || (glo > 0.0 && ghi < 0.0)) {
      double t;
      bracketed_extremum(o, I, kind, lo, hi, glo, ghi, f, t);
      peak.offer(f, t_start + t);
    }
    lo = hi;
    glo = ghi;
  };
  o.homogeneous_zeros(e.c0, e.d0, I.h, [&](double t) {
    quantity(o, I, kind, t, f, df, ddf);
    peak.offer(f, t_start + t);  // a value of the response inside the interval
    piece(t, df);
    return true;
  });
  piece(I.h, e.g1);
}

// The peak of |f| over the free vibration from (u, v) at t_start (a_g = 0): its first extremum,
// the first zero of f' (a homogeneous solution), whatever the damping.
inline void free_vibration_peak(const Oscillator& o, double u, double v, int kind, double t_start, Peak& peak) {
  // u^(n) from the equation with g = 0; f is u^(kind), with Sa's f = u'' (the absolute acceleration)
  double d[5] = {u, v, 0.0, 0.0, 0.0};
  for (int n = 2; n < 5; ++n) d[n] = -2.0 * o.alpha * d[n - 1] - o.w2 * d[n - 2];
  const int first = kind;
  o.homogeneous_zeros(d[first + 1], d[first + 2], std::numeric_limits<double>::infinity(), [&](double t) {
    double x, dx;
    o.homogeneous(t, d[first], d[first + 1], x, dx);
    peak.offer(x, t_start + t);
    return false;  // the first extremum is the largest
  });
}

// The recurrence x_{i+1} = M x_i + N0 g_i + N1 g_{i+1} over an interval h (exact).
struct Recurrence {
  double m00 = 0, m01 = 0, m10 = 0, m11 = 0, n00 = 0, n01 = 0, n10 = 0, n11 = 0;
  Recurrence() = default;
  Recurrence(const Oscillator& o, double h) {
    interval_state(o, h, 1.0, 0.0, 0.0, 0.0, m00, m10);
    interval_state(o, h, 0.0, 1.0, 0.0, 0.0, m01, m11);
    interval_state(o, h, 0.0, 0.0, 1.0, -1.0 / h, n00, n10);
    interval_state(o, h, 0.0, 0.0, 0.0, 1.0 / h, n01, n11);
  }
};

// An interval whose energy bound exceeds one of the current peaks. For each quantity f, an
// extremum inside is searched for only if it can exceed the peak:
// - at an interior extremum t* (f'(t*) = 0), |f(t*)| <= max(|f(0)|, |f(h)|) + h^2/8 max|f''|, and f''
//   is a homogeneous solution, whose energy f''^2 + f'''^2 / w^2 does not grow;
// - and only if f' changes sign, or f'' does (f' may turn back), or f'' may have two zeros (wide).
NVIB_NOINLINE inline void check_interval(const Oscillator& o, const Interval& I, double u1, double v1, double g1,
                                         double bound, double t_start, bool wide, Peak* peaks) {
  const double al2 = 2.0 * o.alpha, w2 = o.w2, s = I.s, h2 = 0.125 * I.h * I.h, inv_w2 = 1.0 / w2;
  // u'' to u''''' at the start, u'' to u'''' at the end (s is this interval's slope)
  const double a0 = -I.g0 - al2 * I.v0 - w2 * I.u0, a1 = -g1 - al2 * v1 - w2 * u1;
  const double j0 = -s - al2 * a0 - w2 * I.v0, j1 = -s - al2 * a1 - w2 * v1;
  const double k0 = -al2 * j0 - w2 * a0, k1 = -al2 * j1 - w2 * a1;
  const double l0 = -al2 * k0 - w2 * j0;
  auto changes = [](double x, double y) { return !(x < 0.0 && y < 0.0) && !(x > 0.0 && y > 0.0); };
  auto examine = [&](int kind, const Ends& e, double energy_bound) {
    Peak& p = peaks[kind];
    if (energy_bound <= p.value) return;
    const double local =
        std::max(std::abs(e.f0), std::abs(e.f1)) + h2 * std::sqrt(e.c0 * e.c0 + e.d0 * e.d0 * inv_w2);
    if (local <= p.value) return;
    if (wide || changes(e.g0, e.g1) || changes(e.c0, e.c1)) search_interval(o, I, kind, e, t_start, p);
  };
  examine(0, Ends{I.u0, u1, I.v0, v1, a0, a1, j0}, bound / o.w);
  examine(1, Ends{I.v0, v1, a0, a1, j0, j1, k0}, bound);
  examine(2, Ends{a0 + I.g0, a1 + g1, j0 + s, j1 + s, k0, k1, l0}, bound * std::sqrt(w2 + al2 * al2));
}

// B oscillators over the record at once, times t0 + i dt (times == nullptr) or times[i]: their
// recurrences are independent chains, interleaved so that one's latency hides the others'.
template <int B>
inline void oscillators(const Oscillator* o, const double* ag, const double* times, Index n, double t0, double dt,
                        const ElasticSpectrumOptions& opt, std::array<Peak, 3>* peaks) {
  double h = times ? times[1] - times[0] : dt;
  Recurrence r[B];
  bool wide[B];
  double inv_kappa[B], u[B], v[B], limit[B];
  auto coefficients = [&] {
    for (int b = 0; b < B; ++b) {
      r[b] = Recurrence(o[b], h);
      // at most one zero of a homogeneous solution in an interval with mu h < pi (zeros pi/mu apart)
      wide[b] = o[b].regime == 0 && o[b].mu * h >= 3.0;
    }
  };
  coefficients();
  for (int b = 0; b < B; ++b) {
    inv_kappa[b] = 1.0 / std::sqrt(o[b].w2 + 4.0 * o[b].alpha * o[b].alpha);
    u[b] = v[b] = limit[b] = 0.0;
  }
  for (Index i = 0; i + 1 < n; ++i) {
    if (times && times[i + 1] - times[i] != h) {
      h = times[i + 1] - times[i];
      coefficients();
    }
    const double g0 = ag[i], g1 = ag[i + 1];
    const double ts = times ? times[i] : t0 + static_cast<double>(i) * dt;
    const double te = times ? times[i + 1] : t0 + static_cast<double>(i + 1) * dt;
    const double hg = h * std::max(std::abs(g0), std::abs(g1));
    for (int b = 0; b < B; ++b) {
      const double u1 = r[b].m00 * u[b] + r[b].m01 * v[b] + r[b].n00 * g0 + r[b].n01 * g1;
      const double v1 = r[b].m10 * u[b] + r[b].m11 * v[b] + r[b].n10 * g0 + r[b].n11 * g1;
      // the energy bound over the interval, against the smallest of the three scaled peaks
      const double bound = std::sqrt(v[b] * v[b] + o[b].w2 * u[b] * u[b]) + hg;
      Peak* p = peaks[b].data();
      if (bound > limit[b]) {
        const Interval I{h, u[b], v[b], g0, (g1 - g0) / h};
        check_interval(o[b], I, u1, v1, g1, bound, ts, wide[b], p);
      }
      p[0].offer(u1, te);
      p[1].offer(v1, te);
      p[2].offer(2.0 * o[b].alpha * v1 + o[b].w2 * u1, te);
      limit[b] = std::min(std::min(o[b].w * p[0].value, p[1].value), p[2].value * inv_kappa[b]);
      u[b] = u1;
      v[b] = v1;
    }
  }
  if (opt.free_vibration) {
    const double te = times ? times[n - 1] : t0 + static_cast<double>(n - 1) * dt;
    for (int b = 0; b < B; ++b)
      for (int kind = 0; kind < 3; ++kind) free_vibration_peak(o[b], u[b], v[b], kind, te, peaks[b][kind]);
  }
}

inline void check_record(const double* ag, Index n) {
  NVIB_CHECK(n >= 2, "ag", "the record needs at least 2 samples, got " + std::to_string(n));
  for (Index i = 0; i < n; ++i)
    NVIB_CHECK(std::isfinite(ag[i]), "ag", "sample " + std::to_string(i) + " is " + detail::fmt(ag[i]) +
                                               "; every sample must be finite");
}

inline void check_oscillators(const Vector& periods, const Vector& damping) {
  NVIB_CHECK(periods.size() > 0, "periods", "expected at least one period");
  NVIB_CHECK(damping.size() == periods.size(), "damping",
             "expected one damping per period (" + std::to_string(periods.size()) + "), got " +
                 std::to_string(damping.size()));
  for (Index i = 0; i < periods.size(); ++i)
    NVIB_CHECK(std::isfinite(periods[i]) && periods[i] > 0.0, "periods",
               "every period must be finite and > 0, got " + detail::fmt(periods[i]) + " at index " +
                   std::to_string(i));
  for (Index i = 0; i < damping.size(); ++i)
    NVIB_CHECK(std::isfinite(damping[i]) && damping[i] >= 0.0, "damping",
               "every damping ratio must be finite and >= 0, got " + detail::fmt(damping[i]) + " at index " +
                   std::to_string(i));
}

inline ElasticSpectrum run(const double* ag, const double* times, Index n, double t0, double dt,
                           const Vector& periods, const Vector& damping, const ElasticSpectrumOptions& opt) {
  check_record(ag, n);
  check_oscillators(periods, damping);
  const Index m = periods.size();
  ElasticSpectrum out;
  out.periods = periods;
  out.damping = damping;
  for (Vector* x : {&out.Sd, &out.Sv, &out.PSv, &out.PSa, &out.Sa, &out.t_Sd, &out.t_Sv, &out.t_Sa}) x->resize(m);
  std::vector<Oscillator> osc;
  osc.reserve(static_cast<std::size_t>(m));
  for (Index i = 0; i < m; ++i) {
    osc.emplace_back(periods[i], damping[i]);
    NVIB_CHECK(std::isfinite(osc.back().w2) && osc.back().w2 > 0.0, "periods",
               "the period " + detail::fmt(periods[i]) + " s gives a circular frequency whose square is not finite");
  }
  std::vector<std::array<Peak, 3>> peaks(static_cast<std::size_t>(m));
  for (auto& q : peaks)
    for (Peak& p : q) p.time = times ? times[0] : t0;
  auto block = [&](Index i) { return peaks.data() + i; };
  constexpr Index B = 8;  // oscillators interleaved: 8 hides the recurrence's latency best of 1, 2, 4, 8
  Index i = 0;
  for (; i + B <= m; i += B) oscillators<B>(osc.data() + i, ag, times, n, t0, dt, opt, block(i));
  for (; i < m; ++i) oscillators<1>(osc.data() + i, ag, times, n, t0, dt, opt, block(i));
  for (i = 0; i < m; ++i) {
    const Peak* p = peaks[static_cast<std::size_t>(i)].data();
    const Oscillator& o = osc[static_cast<std::size_t>(i)];
    out.Sd[i] = p[0].value;
    out.Sv[i] = p[1].value;
    out.Sa[i] = p[2].value;
    out.PSv[i] = o.w * p[0].value;
    out.PSa[i] = o.w2 * p[0].value;
    out.t_Sd[i] = p[0].time;
    out.t_Sv[i] = p[1].time;
    out.t_Sa[i] = p[2].time;
  }
  return out;
}

// Sd of one oscillator under a1 cos(theta) + a2 sin(theta) for each angle (column `col` of sd): the
// oscillator is linear, so its response is u1 cos(theta) + u2 sin(theta) from the histories under a1
// and a2, found once. Per angle, the peak at the samples and in the free vibration first; then the
// intervals whose bound can exceed it are searched as in check_interval. An interval is skipped for
// every angle at once when the bound of the two-component response (the norm of (u1, u2), whose
// energy grows by at most |(a1, a2)| per unit time) is below the smallest angle's peak.
inline void rotd_oscillator(const Oscillator& o, const double* a1, const double* a2, Index n, double dt,
                            const Vector& cosines, const Vector& sines, Matrix& sd, Index col) {
  const Recurrence r(o, dt);
  const bool wide = o.regime == 0 && o.mu * dt >= 3.0;
  std::vector<double> U1(static_cast<std::size_t>(n)), V1(U1.size()), U2(U1.size()), V2(U1.size());
  U1[0] = V1[0] = U2[0] = V2[0] = 0.0;
  for (Index i = 0; i + 1 < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    U1[k + 1] = r.m00 * U1[k] + r.m01 * V1[k] + r.n00 * a1[i] + r.n01 * a1[i + 1];
    V1[k + 1] = r.m10 * U1[k] + r.m11 * V1[k] + r.n10 * a1[i] + r.n11 * a1[i + 1];
    U2[k + 1] = r.m00 * U2[k] + r.m01 * V2[k] + r.n00 * a2[i] + r.n01 * a2[i + 1];
    V2[k + 1] = r.m10 * U2[k] + r.m11 * V2[k] + r.n10 * a2[i] + r.n11 * a2[i + 1];
  }
  const Index na = cosines.size();
  std::vector<Peak> peaks(static_cast<std::size_t>(na));
  double smallest = std::numeric_limits<double>::infinity();
  for (Index k = 0; k < na; ++k) {
    const double c = cosines[k], s = sines[k];
    double p = 0.0;
    for (std::size_t i = 0; i < U1.size(); ++i) p = std::max(p, std::abs(c * U1[i] + s * U2[i]));
    Peak& pk = peaks[static_cast<std::size_t>(k)];
    pk.value = p;
    const std::size_t last = U1.size() - 1;
    free_vibration_peak(o, c * U1[last] + s * U2[last], c * V1[last] + s * V2[last], 0, 0.0, pk);
    smallest = std::min(smallest, pk.value);
  }
  const double h2 = 0.125 * dt * dt, al2 = 2.0 * o.alpha, w2 = o.w2;
  for (Index i = 0; i + 1 < n; ++i) {
    const auto j = static_cast<std::size_t>(i);
    const double g = std::max(std::hypot(a1[i], a2[i]), std::hypot(a1[i + 1], a2[i + 1]));
    const double e2 = V1[j] * V1[j] + V2[j] * V2[j] + w2 * (U1[j] * U1[j] + U2[j] * U2[j]);
    if (std::sqrt(e2) + dt * g <= o.w * smallest) continue;
    for (Index k = 0; k < na; ++k) {
      const double c = cosines[k], s = sines[k];
      Peak& pk = peaks[static_cast<std::size_t>(k)];
      const double u0 = c * U1[j] + s * U2[j], v0 = c * V1[j] + s * V2[j];
      const double u1 = c * U1[j + 1] + s * U2[j + 1], v1 = c * V1[j + 1] + s * V2[j + 1];
      const double g0 = c * a1[i] + s * a2[i], g1 = c * a1[i + 1] + s * a2[i + 1];
      if (std::sqrt(v0 * v0 + w2 * u0 * u0) + dt * std::max(std::abs(g0), std::abs(g1)) <= o.w * pk.value) continue;
      const Interval I{dt, u0, v0, g0, (g1 - g0) / dt};
      const double a0 = -g0 - al2 * v0 - w2 * u0, a1e = -g1 - al2 * v1 - w2 * u1;
      const double j0 = -I.s - al2 * a0 - w2 * v0;
      if (std::max(std::abs(u0), std::abs(u1)) + h2 * std::sqrt(a0 * a0 + j0 * j0 / w2) <= pk.value) continue;
      auto changes = [](double x, double y) { return !(x < 0.0 && y < 0.0) && !(x > 0.0 && y > 0.0); };
      if (wide || changes(v0, v1) || changes(a0, a1e))
        search_interval(o, I, 0, Ends{u0, u1, v0, v1, a0, a1e, j0}, 0.0, pk);
    }
  }
  for (Index k = 0; k < na; ++k) sd(k, col) = peaks[static_cast<std::size_t>(k)].value;
}

}  // namespace spectrum_detail

// The exact spectrum of the record ag (samples dt apart from t0, linear between them) at the
// oscillators (periods[i], damping[i]); damping of size 1 applies to every period.
inline ElasticSpectrum elastic_spectrum(const CVecRef& ag, double dt, const CVecRef& periods, const CVecRef& damping,
                                        const ElasticSpectrumOptions& opt = {}, double t0 = 0.0) {
  check_time_step(dt);
  check_start_time(t0);
  const Vector z = damping.size() == 1 ? Vector::Constant(periods.size(), damping[0]) : Vector(damping);
  return spectrum_detail::run(ag.data(), nullptr, ag.size(), t0, dt, periods, z, opt);
}

// The same for samples at increasing times (any spacing).
inline ElasticSpectrum elastic_spectrum_at(const CVecRef& times, const CVecRef& ag, const CVecRef& periods,
                                           const CVecRef& damping, const ElasticSpectrumOptions& opt = {}) {
  NVIB_CHECK(times.size() == ag.size(), "times",
             "expected one time per sample (" + std::to_string(ag.size()) + "), got " + std::to_string(times.size()));
  for (Index i = 0; i < times.size(); ++i)
    NVIB_CHECK(std::isfinite(times[i]) && (i == 0 || times[i] > times[i - 1]), "times",
               "the times must be finite and increasing; index " + std::to_string(i) + " is " + detail::fmt(times[i]));
  const Vector z = damping.size() == 1 ? Vector::Constant(periods.size(), damping[0]) : Vector(damping);
  return spectrum_detail::run(ag.data(), times.data(), ag.size(), 0.0, 0.0, periods, z, opt);
}

// The spectra for each damping ratio (rows) at each period (columns): row k of each member is the
// spectrum at damping[k]; returned flat, damping-major (entry k * periods.size() + i).
inline ElasticSpectrum elastic_spectrum_grid(const CVecRef& ag, double dt, const CVecRef& periods,
                                             const CVecRef& damping, const ElasticSpectrumOptions& opt = {},
                                             double t0 = 0.0) {
  NVIB_CHECK(damping.size() > 0, "damping", "expected at least one damping ratio");
  const Index m = periods.size(), nz = damping.size();
  Vector P(m * nz), Z(m * nz);
  for (Index k = 0; k < nz; ++k) {
    P.segment(k * m, m) = periods;
    Z.segment(k * m, m).setConstant(damping[k]);
  }
  check_time_step(dt);
  check_start_time(t0);
  return spectrum_detail::run(ag.data(), nullptr, ag.size(), t0, dt, P, Z, opt);
}

// Sd of each oscillator (periods[i], damping[i], or damping[0] for all) under the two horizontal
// components a1, a2 (samples dt apart) rotated to each angle [degrees]: a1 cos(theta) + a2 sin(theta),
// exactly (peaks between samples, free vibration after the record); rows: angles, columns: periods.
// RotD50 and RotD100 (Boore 2010) are the median and the largest of each column over 0..179 degrees.
inline Matrix rotated_sd(const CVecRef& a1, const CVecRef& a2, double dt, const CVecRef& periods,
                         const CVecRef& damping, const CVecRef& angles_deg) {
  check_time_step(dt);
  spectrum_detail::check_record(a1.data(), a1.size());
  NVIB_CHECK(a2.size() == a1.size(), "a2",
             "expected as many samples as a1 (" + std::to_string(a1.size()) + "), got " + std::to_string(a2.size()));
  spectrum_detail::check_record(a2.data(), a2.size());
  NVIB_CHECK(angles_deg.size() > 0, "angles", "expected at least one angle");
  for (Index k = 0; k < angles_deg.size(); ++k)
    NVIB_CHECK(std::isfinite(angles_deg[k]), "angles", "every angle must be finite");
  const Vector z = damping.size() == 1 ? Vector::Constant(periods.size(), damping[0]) : Vector(damping);
  spectrum_detail::check_oscillators(periods, z);
  const Vector rad = angles_deg * (spectrum_detail::kPi / 180.0);
  const Vector c = rad.array().cos(), s = rad.array().sin();
  Matrix sd(angles_deg.size(), periods.size());
  for (Index i = 0; i < periods.size(); ++i)
    spectrum_detail::rotd_oscillator(spectrum_detail::Oscillator(periods[i], z[i]), a1.data(), a2.data(), a1.size(),
                                     dt, c, s, sd, i);
  return sd;
}

}  // namespace nvib
