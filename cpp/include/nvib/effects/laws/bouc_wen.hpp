// Smooth hysteresis of Bouc (1967) and Wen (1976), in its common normalised form:
//   f = alpha k d + (1 - alpha) fy z,    dz/dd = (A - |z|^n (beta sgn(d' z) + gamma)) / dy,  dy = fy / k,
// z dimensionless (|z| saturates at (A / (beta + gamma))^(1/n)), n >= 1. The evolution equation is
// rate-independent, so over one step it is an ODE in d along the increment d_c -> d, integrated
// inside the trial in one of two ways:
//   integration = "exact" (default): to round-off. For n = 1 the equation is linear in z between
//     the switches of sgn(d' z) at z = 0, and its solution an exponential (with expm1 and log1p
//     for the small arguments), landing exactly on z = 0; for other n an adaptive embedded
//     Runge-Kutta pair (Dormand & Prince 1980, 5(4)) with a tolerance of a few ulps, its steps landing
//     on z = 0. The consistent tangent is df/dd = alpha k + (1 - alpha) fy Phi(z)/dy, the derivative
//     of the flow at its end. The law adds no error of its own to the scheme's.
//   integration = "backward_euler": one implicit Euler step z = z_c + (d - d_c) Phi(z)/dy, solved by
//     a safeguarded Newton iteration to round-off, with its algorithmic tangent: the update of
//     OpenSees' BoucWen (first order in the increment, so a run is first order in the time step).
// Conditions for a bounded, dissipative loop (Ikhouane, Manosa & Rodellar 2007, J. Sound Vib.
// 302:47): A > 0, beta + gamma > 0, beta >= gamma. The energy stored in the hysteretic part is
// (1 - alpha) fy dy z^2 / (2 A); its dissipation rate, (1 - alpha) fy z d' |z|^n (beta sgn(d' z) +
// gamma) / A >= 0, is integrated with z.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "../law.hpp"

namespace nvib {
namespace effects {

struct BoucWen : LawBase {
  static constexpr const char* key = "bouc_wen";
  static constexpr const char* doc =
      "Bouc-Wen smooth hysteresis f = alpha k d + (1 - alpha) fy z, dz/dd = (A - |z|^n (beta sgn(d' z) + gamma)) / dy";
  static constexpr const char* source = "Bouc 1967; Wen 1976, J. Eng. Mech. Div. 102(2):249";
  enum Integration { exact = 0, backward_euler = 1 };
  static constexpr std::array<Parameter, 9> parameters{{{"k", kRequired, "initial stiffness"},
                                                        unset("fy", "yield force fy = k dy (or dy)"),
                                                        unset("dy", "yield displacement (or fy)"),
                                                        {"alpha", 0.0, "post-yield stiffness ratio, 0 <= alpha < 1"},
                                                        {"n", 1.0, "sharpness of the yield, n >= 1"},
                                                        {"beta", 0.5, "beta >= gamma, beta + gamma > 0"},
                                                        {"gamma", 0.5, "see beta"},
                                                        {"A", 1.0, "A > 0"},
                                                        choice("integration", "how z is integrated over a step",
                                                               "exact|backward_euler")}};
  struct Params {
    double k, fy, dy, alpha, n, beta, gamma, A;
    int integration;
  };
  struct State {
    double z;           // the hysteretic variable (dimensionless)
    double dissipated;  // energy dissipated by the hysteretic part
    double d;           // the deformation at which z holds
    double kt;          // the slope df/dd at the end of its last step
  };
  static constexpr std::array<const char*, 4> state_names{{"z", "dissipated", "deformation", "tangent"}};

  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "k", "must be > 0, got " + detail::fmt(x[0]));
    NVIB_CHECK(is_unset(x[1]) != is_unset(x[2]), is_unset(x[1]) ? "fy, dy" : "fy",
               is_unset(x[1]) ? "give the yield force fy or the yield displacement dy"
                              : "give fy or dy, not both (dy = fy / k)");
    if (!is_unset(x[1])) NVIB_CHECK(x[1] > 0.0, "fy", "must be > 0, got " + detail::fmt(x[1]));
    if (!is_unset(x[2])) NVIB_CHECK(x[2] > 0.0, "dy", "must be > 0, got " + detail::fmt(x[2]));
    NVIB_CHECK(x[3] >= 0.0 && x[3] < 1.0, "alpha", "needs 0 <= alpha < 1, got " + detail::fmt(x[3]));
    NVIB_CHECK(x[4] >= 1.0, "n", "needs n >= 1, got " + detail::fmt(x[4]));
    NVIB_CHECK(x[5] + x[6] > 0.0, "beta, gamma",
               "needs beta + gamma > 0 (a bounded loop), got " + detail::fmt(x[5] + x[6]));
    NVIB_CHECK(x[5] >= x[6], "beta, gamma",
               "needs beta >= gamma (a dissipative loop; Ikhouane et al. 2007), got beta = " + detail::fmt(x[5]) +
                   ", gamma = " + detail::fmt(x[6]));
    NVIB_CHECK(x[7] > 0.0, "A", "must be > 0, got " + detail::fmt(x[7]));
    NVIB_CHECK(x[8] == 0.0 || x[8] == 1.0, "integration", "expected 'exact' or 'backward_euler'");
  }
  static Params prepare(const double* x, const Signal*) {
    const double fy = is_unset(x[1]) ? x[0] * x[2] : x[1];
    const double dy = is_unset(x[2]) ? x[1] / x[0] : x[2];
    return {x[0], fy, dy, x[3], x[4], x[5], x[6], x[7], static_cast<int>(x[8])};
  }

  // |z|^n, without pow for the common n = 1 and n = 2.
  static double power(const Params& p, double a) { return p.n == 1.0 ? a : p.n == 2.0 ? a * a : std::pow(a, p.n); }
  // Phi(z) for motion in the direction s (sgn(0) = -1, as OpenSees takes it: the stiffer branch).
  static double phi(const Params& p, double z, double s) {
    const double sz = s * z > 0.0 ? 1.0 : -1.0;
    return p.A - power(p, std::abs(z)) * (p.beta * sz + p.gamma);
  }
  // dPhi/dz; at z = 0 (n = 1: a kink) on the side z moves to, the side of s (Phi(0) = A > 0).
  static double dphi(const Params& p, double z, double s) {
    if (z == 0.0) return p.n == 1.0 ? -s * (p.beta + p.gamma) : 0.0;
    const double sz = s * z > 0.0 ? 1.0 : -1.0;
    const double a = std::abs(z), an1 = p.n == 1.0 ? 1.0 : p.n == 2.0 ? a : std::pow(a, p.n - 1.0);
    return -p.n * an1 * (z > 0.0 ? 1.0 : -1.0) * (p.beta * sz + p.gamma);
  }

  static State initial(const Params& p) { return {0.0, 0.0, 0.0, p.alpha * p.k + (1.0 - p.alpha) * p.fy * p.A / p.dy}; }
  // At the committed deformation itself (no increment, so no direction) the slope is that of the last
  // step's end, the one a step that goes on in the same direction sees.
  static Trial<State> trial(const Params& p, const State& c, double d, double, double) {
    const double delta = d - c.d, s = delta > 0.0 ? 1.0 : -1.0;
    const double hk = (1.0 - p.alpha) * p.fy;
    if (delta == 0.0) return {p.alpha * p.k * d + hk * c.z, c.kt, 0.0, c};
    State next = c;
    next.d = d;
    double slope;  // dz/dd at the end
    if (p.integration == backward_euler) {
      slope = euler(p, c, delta, s, next);
    } else {
      if (p.n == 1.0)
        flow_linear(p, c, delta, s, next);
      else
        flow(p, c, delta, s, next);
      slope = phi(p, next.z, s) / p.dy;
    }
    next.kt = p.alpha * p.k + hk * slope;
    return {p.alpha * p.k * d + hk * next.z, next.kt, 0.0, next};
  }
  static double recoverable(const Params& p, const State& s, double d) {
    return 0.5 * p.alpha * p.k * d * d + 0.5 * (1.0 - p.alpha) * p.fy * p.dy * s.z * s.z / p.A;
  }
  static double dissipated(const Params&, const State& s) { return s.dissipated; }
  static bool is_linear(const Params&) { return false; }

 private:
  // The rates along the increment, in tau = |d - d_c|: dz/dtau = s Phi / dy, and the dissipation.
  static void rates(const Params& p, double z, double s, double& rz, double& rw) {
    const double az = power(p, std::abs(z)), sz = s * z > 0.0 ? 1.0 : -1.0;
    const double c = p.beta * sz + p.gamma;
    rz = s * (p.A - az * c) / p.dy;
    rw = (1.0 - p.alpha) * p.fy / p.A * az * c * (s * z);
  }

  struct Step {
    double z, w, err;
  };
  // One Dormand-Prince 5(4) step of size h from (z, w): the 5th-order result and the error estimate
  // (Dormand & Prince 1980, J. Comput. Appl. Math. 6:19; the coefficients of Hairer, Norsett &
  // Wanner, Solving ODEs I, table 5.2).
  static Step rk(const Params& p, double z, double w, double s, double h) {
    constexpr double a21 = 1.0 / 5, a31 = 3.0 / 40, a32 = 9.0 / 40, a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9,
                     a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729,
                     a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                     a65 = -5103.0 / 18656, b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192,
                     b5 = -2187.0 / 6784, b6 = 11.0 / 84, e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920,
                     e5 = -17253.0 / 339200, e6 = 22.0 / 525, e7 = -1.0 / 40;
    double k1, k2, k3, k4, k5, k6, k7, w1, w2, w3, w4, w5, w6, w7;
    rates(p, z, s, k1, w1);
    rates(p, z + h * a21 * k1, s, k2, w2);
    rates(p, z + h * (a31 * k1 + a32 * k2), s, k3, w3);
    rates(p, z + h * (a41 * k1 + a42 * k2 + a43 * k3), s, k4, w4);
    rates(p, z + h * (a51 * k1 + a52 * k2 + a53 * k3 + a54 * k4), s, k5, w5);
    rates(p, z + h * (a61 * k1 + a62 * k2 + a63 * k3 + a64 * k4 + a65 * k5), s, k6, w6);
    const double z5 = z + h * (b1 * k1 + b3 * k3 + b4 * k4 + b5 * k5 + b6 * k6);
    rates(p, z5, s, k7, w7);
    (void)w2, (void)w7;
    return {z5, w + h * (b1 * w1 + b3 * w3 + b4 * w4 + b5 * w5 + b6 * w6),
            std::abs(h * (e1 * k1 + e3 * k3 + e4 * k4 + e5 * k5 + e6 * k6 + e7 * k7))};
  }

  // n = 1: in tau = |d - d_c|, dz/dtau = (s/dy)(A - c sigma z) with sigma = sgn(z), c = beta s sigma +
  // gamma, constant until z reaches 0; so z = z* + (z0 - z*) e^{-lambda tau}, lambda = s c sigma/dy,
  // z* = A/(c sigma), and the dissipation rate (1 - alpha) fy/A c |z| s z = (1 - alpha) fy dy lambda z^2 / A
  // integrates in closed form too. Moving toward zero (s z0 < 0) z reaches it after
  // tau0 = dy log1p(|c| |z0| / A) / |c| (c = gamma - beta <= 0 there), then moves away with c = beta + gamma.
  static void flow_linear(const Params& p, const State& c, double delta, double s, State& out) {
    double z = c.z, w = c.dissipated, left = std::abs(delta);
    const double K = (1.0 - p.alpha) * p.fy / p.A;
    for (int region = 0; region < 2 && left > 0.0; ++region) {
      const double sigma = z != 0.0 ? (z > 0.0 ? 1.0 : -1.0) : s;  // at 0, z moves the way d does
      const double cc = p.beta * s * sigma + p.gamma;
      double tau = left;
      bool lands = false;
      if (s * sigma < 0.0) {  // toward zero: where does it get there?
        const double a = std::abs(cc), to_zero = a == 0.0 ? std::abs(z) * p.dy / p.A : p.dy * std::log1p(a * std::abs(z) / p.A) / a;
        if (to_zero <= left) {
          tau = to_zero;
          lands = true;
        }
      }
      if (cc == 0.0) {  // z moves at the constant rate s A/dy; no dissipation
        z = lands ? 0.0 : z + s * p.A * tau / p.dy;
      } else {
        const double lambda = s * cc * sigma / p.dy, zs = p.A / (cc * sigma), D = z - zs;
        const double e1 = std::expm1(-lambda * tau), e2 = std::expm1(-2.0 * lambda * tau);
        // int_0^tau z^2 = zs^2 tau + 2 zs D (1 - e^{-l tau})/l + D^2 (1 - e^{-2 l tau})/(2 l)
        const double z2 = zs * zs * tau - 2.0 * zs * D * e1 / lambda - D * D * e2 / (2.0 * lambda);
        w += K * p.dy * lambda * z2;
        z = lands ? 0.0 : z + D * e1;  // zs + D e^{-l tau} = z0 + D expm1(-l tau)
      }
      left -= tau;
      if (!lands) break;
    }
    out.z = z;
    out.dissipated = w;
  }

  // z along the increment to a few ulps: adaptive steps, and a step that would carry z across 0
  // (where sgn(d' z) switches and, for n = 1, the slope of |z|^n jumps) shortened to land there, its
  // length found by bracketed secant iterations on the step's own result.
  static void flow(const Params& p, const State& c, double delta, double s, State& out) {
    const double total = std::abs(delta), eps = std::numeric_limits<double>::epsilon();
    const double hmin = 1e-14 * p.dy;
    double z = c.z, w = c.dissipated, tau = 0.0, h = std::min(total, 0.05 * p.dy);
    for (int it = 0; tau < total && it < 1000000; ++it) {
      h = std::min(h, total - tau);
      const Step st = rk(p, z, w, s, h);
      const double scale = 8.0 * eps * std::max(1.0, std::abs(z));
      if (st.err > scale && h > hmin) {
        h *= std::max(0.2, 0.9 * std::pow(scale / st.err, 0.2));
        continue;
      }
      if (z != 0.0 && st.z != 0.0 && (z > 0.0) != (st.z > 0.0)) {
        double ha = 0.0, za = z, hb = h, zb = st.z;
        Step land = st;
        for (int q = 0; q < 200 && std::abs(land.z) > 4.0 * eps; ++q) {
          double hc = hb - zb * (hb - ha) / (zb - za);
          if (!(hc > std::min(ha, hb) && hc < std::max(ha, hb)) || q % 4 == 3) hc = 0.5 * (ha + hb);
          land = rk(p, z, w, s, hc);
          if ((land.z > 0.0) == (za > 0.0)) {
            ha = hc;
            za = land.z;
          } else {
            hb = hc;
            zb = land.z;
          }
          if (land.z == 0.0 || hb - ha <= eps * hb) break;
        }
        tau += (land.z > 0.0) == (z > 0.0) ? ha : hb;
        z = 0.0;
        w = land.w;
        continue;
      }
      tau += h;
      z = st.z;
      w = st.w;
      h *= st.err > 0.0 ? std::min(5.0, std::max(0.2, 0.9 * std::pow(scale / st.err, 0.2))) : 5.0;
    }
    out.z = z;
    out.dissipated = w;
  }

  // One backward-Euler step, R(z) = z - z_c - delta Phi(z) / dy = 0: R is increasing with R' >= 1
  // (beta >= gamma), so its root lies within |R(z_c)| of z_c; Newton from z_c, bisection where a
  // Newton step leaves the bracket. Returns dz/dd, the algorithmic tangent.
  static double euler(const Params& p, const State& c, double delta, double s, State& out) {
    auto R = [&](double z) { return z - c.z - delta * phi(p, z, s) / p.dy; };
    const double eps = std::numeric_limits<double>::epsilon();
    const double r0 = R(c.z);
    double lo = c.z - std::abs(r0), hi = c.z + std::abs(r0), z = c.z;
    for (int it = 0; it < 200; ++it) {
      const double r = R(z);
      if (r == 0.0) break;
      if (r > 0.0)
        hi = std::min(hi, z);
      else
        lo = std::max(lo, z);
      const double dr = 1.0 - delta * dphi(p, z, s) / p.dy;
      double zn = z - r / dr;
      if (!(zn >= lo && zn <= hi)) zn = 0.5 * (lo + hi);  // a Newton step out of the bracket: bisect
      const bool done = std::abs(zn - z) <= 2.0 * eps * std::abs(zn) || hi - lo <= 2.0 * eps * std::abs(hi);
      z = zn;
      if (done) break;
    }
    out.z = z;
    // The work of the hysteretic force over the step by the trapezoid rule, less the stored energy's change.
    const double hk = (1.0 - p.alpha) * p.fy;
    out.dissipated = c.dissipated + hk * 0.5 * (c.z + z) * delta - 0.5 * hk * p.dy * (z * z - c.z * c.z) / p.A;
    return phi(p, z, s) / p.dy / (1.0 - delta * dphi(p, z, s) / p.dy);
  }
};

}  // namespace effects
}  // namespace nvib
