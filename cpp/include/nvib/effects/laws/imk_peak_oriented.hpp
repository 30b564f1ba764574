// Peak-oriented hysteresis with strength and stiffness deterioration: the modified
// Ibarra-Medina-Krawinkler model (Ibarra, Medina & Krawinkler 2005, Earthquake Eng. Struct. Dyn.
// 34:1489; Lignos & Krawinkler 2011, J. Struct. Eng. 137(11):1291), in the form of OpenSees'
// IMKPeakOriented (Elkady & Ibrahim, OpenSees 3.7.1), whose forces this law reproduces step for step.
//
// Backbone of each side: elastic k up to the yield force fy; hardening to the capping point (plastic
// deformation up, force fcap_fy fy); a negative post-capping slope that reaches zero force after upc;
// a residual force fres_fy fy; nothing beyond the ultimate deformation uu. Reversals unload along
// the unloading stiffness; each new excursion (the unloading branch reaching zero force) reloads
// toward the peak of the side it goes to (the local peak first where that is steeper), and
// deteriorates that side by beta_i = (E_i / (E_t - sum_j E_j))^c with E_t = lambda fy (fy of the
// positive side, lambda in deformation units): basic strength and hardening by (1 - beta_S D), the
// post-capping line moved toward the origin by (1 - beta_C D), the reloading target pushed out by
// (1 + beta_A D); the unloading stiffness deteriorates by (1 - beta_K) at every reversal. The law
// fails (no force, permanently) when an energy is used up (beta > 1), at the ultimate deformation,
// or when the residual is zero and reached: a structure can collapse.
//
// Where this law departs from OpenSees, on purpose:
//  - the tangent is the slope of the branch the trial ends on (the consistent tangent of the
//    update, so Newton converges quadratically), where OpenSees returns the secant over the step;
//  - lambda = 0 switches a deterioration off for every c (OpenSees: only for c = 1, otherwise NaN);
//    a negative excursion energy deteriorates nothing (OpenSees: NaN for a non-integer c); and an
//    excursion that dissipates more than the energy left fails the law (OpenSees: its ratio turns
//    negative and the mode stops deteriorating), so that no parameter set gives a silent NaN or an
//    element that outlives its energy.
#pragma once

#include <cmath>

#include "../law.hpp"

namespace nvib {
namespace effects {

struct ImkPeakOriented : LawBase {
  static constexpr const char* key = "imk_peak_oriented";
  static constexpr const char* doc =
      "peak-oriented hysteresis with capping, post-capping softening, residual strength and energy-based "
      "cyclic deterioration (modified Ibarra-Medina-Krawinkler)";
  static constexpr const char* source = "Ibarra, Medina & Krawinkler 2005; Lignos & Krawinkler 2011; OpenSees IMKPeakOriented";
  static constexpr std::array<Parameter, 23> parameters{{
      {"k", kRequired, "elastic stiffness"},
      {"fy", kRequired, "yield force (positive side)"},
      {"up", kRequired, "plastic deformation from yield to the capping point (positive side)"},
      {"upc", kRequired, "deformation from the capping point to zero force (positive side)"},
      {"uu", kRequired, "ultimate deformation, measured from zero (positive side)"},
      {"fcap_fy", kRequired, "capping force / yield force (positive side)"},
      {"fres_fy", 0.0, "residual force / yield force (positive side)"},
      unset("fy_neg", "yield force, negative side (default: as positive)"),
      unset("up_neg", "negative side (default: as positive)"),
      unset("upc_neg", "negative side (default: as positive)"),
      unset("uu_neg", "negative side (default: as positive)"),
      unset("fcap_fy_neg", "negative side (default: as positive)"),
      unset("fres_fy_neg", "negative side (default: as positive)"),
      {"lambda_s", 0.0, "reference energy of basic-strength deterioration / fy, a deformation (0: none)"},
      {"lambda_c", 0.0, "... of post-capping deterioration (0: none)"},
      {"lambda_a", 0.0, "... of accelerated reloading stiffness deterioration (0: none)"},
      {"lambda_k", 0.0, "... of unloading stiffness deterioration (0: none)"},
      {"c_s", 1.0, "exponent of basic-strength deterioration"},
      {"c_c", 1.0, "exponent of post-capping deterioration"},
      {"c_a", 1.0, "exponent of accelerated reloading deterioration"},
      {"c_k", 1.0, "exponent of unloading stiffness deterioration"},
      {"d_pos", 1.0, "rate of cyclic deterioration in the positive direction"},
      {"d_neg", 1.0, "rate of cyclic deterioration in the negative direction"},
  }};
  struct Params {
    double k, uu_pos, uu_neg;
    double Et_s, Et_c, Et_a, Et_k;  // reference energies (0: the mode is off)
    double c_s, c_c, c_a, c_k, d_pos, d_neg;
    // the initial backbone of each side (negative side: deformations and forces negative)
    double uy[2], fy[2], ucap[2], fcap[2], ures[2], fres[2], kp[2], kpc[2];
  };
  // The state, as in OpenSees: per side (positive, negative) the backbone and the peaks, then the
  // committed deformation and force, the reloading and unloading stiffnesses, the accumulated and
  // excursion-start energies, the failure flag and the branch.
  struct Side {
    double uy, fy, ucap, fcap, ulocal, flocal, uglobal, fglobal, ures, fres, kp, kpc;
  };
  struct State {
    Side pos, neg;
    double u, f, kreload, kunload, energy, energy_excursion, failed, branch;
  };
  static constexpr std::array<const char*, 32> state_names{
      {"uy_pos", "fy_pos", "ucap_pos", "fcap_pos", "ulocal_pos", "flocal_pos", "uglobal_pos", "fglobal_pos",
       "ures_pos", "fres_pos", "kp_pos", "kpc_pos", "uy_neg", "fy_neg", "ucap_neg", "fcap_neg", "ulocal_neg",
       "flocal_neg", "uglobal_neg", "fglobal_neg", "ures_neg", "fres_neg", "kp_neg", "kpc_neg", "deformation", "force",
       "k_reload", "k_unload", "energy", "energy_excursion_start", "failed", "branch"}};

  static void validate(const double* x) {
    const char* names[] = {"k", "fy", "up", "upc", "uu"};
    for (int q = 0; q < 5; ++q) NVIB_CHECK(x[q] > 0.0, names[q], "must be > 0, got " + detail::fmt(x[q]));
    NVIB_CHECK(x[5] > 0.0, "fcap_fy", "must be > 0, got " + detail::fmt(x[5]));
    NVIB_CHECK(x[6] >= 0.0 && x[6] <= x[5], "fres_fy", "needs 0 <= fres_fy <= fcap_fy, got " + detail::fmt(x[6]));
    const char* neg[] = {"fy_neg", "up_neg", "upc_neg", "uu_neg", "fcap_fy_neg"};
    for (int q = 0; q < 5; ++q)
      if (!is_unset(x[7 + q])) NVIB_CHECK(x[7 + q] > 0.0, neg[q], "must be > 0 (a magnitude), got " + detail::fmt(x[7 + q]));
    if (!is_unset(x[12])) {
      const double cap = is_unset(x[11]) ? x[5] : x[11];
      NVIB_CHECK(x[12] >= 0.0 && x[12] <= cap, "fres_fy_neg", "needs 0 <= fres_fy_neg <= fcap_fy_neg, got " + detail::fmt(x[12]));
    }
    const char* lam[] = {"lambda_s", "lambda_c", "lambda_a", "lambda_k"};
    const char* cs[] = {"c_s", "c_c", "c_a", "c_k"};
    for (int q = 0; q < 4; ++q) {
      NVIB_CHECK(x[13 + q] >= 0.0, lam[q], "must be >= 0 (0: no deterioration), got " + detail::fmt(x[13 + q]));
      NVIB_CHECK(x[17 + q] > 0.0, cs[q], "must be > 0, got " + detail::fmt(x[17 + q]));
    }
    NVIB_CHECK(x[21] >= 0.0 && x[21] <= 1.0, "d_pos", "needs 0 <= d_pos <= 1, got " + detail::fmt(x[21]));
    NVIB_CHECK(x[22] >= 0.0 && x[22] <= 1.0, "d_neg", "needs 0 <= d_neg <= 1, got " + detail::fmt(x[22]));
  }
  static Params prepare(const double* x, const Signal*) {
    auto or_pos = [&](int q) { return is_unset(x[7 + q]) ? x[1 + q] : x[7 + q]; };
    Params p{};
    p.k = x[0];
    const double fy[2] = {x[1], or_pos(0)}, up[2] = {x[2], or_pos(1)}, upc[2] = {x[3], or_pos(2)};
    const double fcap_fy[2] = {x[5], or_pos(4)}, fres_fy[2] = {x[6], is_unset(x[12]) ? x[6] : x[12]};
    p.uu_pos = x[4];
    p.uu_neg = or_pos(3);
    for (int s = 0; s < 2; ++s) {
      const double sign = s == 0 ? 1.0 : -1.0;
      const double uy = fy[s] / p.k, fcap = fcap_fy[s] * fy[s];
      p.uy[s] = sign * uy;
      p.fy[s] = sign * fy[s];
      p.ucap[s] = sign * (uy + up[s]);
      p.fcap[s] = sign * fcap;
      p.kp[s] = (fcap - fy[s]) / up[s];
      p.kpc[s] = -fcap / upc[s];
      p.fres[s] = sign * fy[s] * fres_fy[s];
      p.ures[s] = (p.fres[s] - p.fcap[s]) / p.kpc[s] + p.ucap[s];
    }
    p.Et_s = x[13] * x[1];
    p.Et_c = x[14] * x[1];
    p.Et_a = x[15] * x[1];
    p.Et_k = x[16] * x[1];
    p.c_s = x[17];
    p.c_c = x[18];
    p.c_a = x[19];
    p.c_k = x[20];
    p.d_pos = x[21];
    p.d_neg = x[22];
    return p;
  }
  static State initial(const Params& p) {
    State s{};
    Side* sides[2] = {&s.pos, &s.neg};
    for (int q = 0; q < 2; ++q) {
      Side& b = *sides[q];
      b.uy = p.uy[q];
      b.fy = p.fy[q];
      b.ucap = p.ucap[q];
      b.fcap = p.fcap[q];
      b.ulocal = b.uglobal = p.uy[q];
      b.flocal = b.fglobal = p.fy[q];
      b.ures = p.ures[q];
      b.fres = p.fres[q];
      b.kp = p.kp[q];
      b.kpc = p.kpc[q];
    }
    s.kreload = s.kunload = p.k;
    return s;
  }

  static Trial<State> trial(const Params& p, const State& c, double u, double, double) {
    State s = c;
    const double u1 = c.u, f1 = c.f, du = u - u1;
    s.u = u;
    if (c.failed != 0.0) {
      s.f = 0.0;
      return {0.0, 0.0, 0.0, s};
    }
    if (du == 0.0) return {f1, slope(p, s), 0.0, s};
    bool fail = false;
    int branch = static_cast<int>(c.branch);
    // A reversal on a loading branch: the committed point becomes a peak; the unloading stiffness deteriorates.
    if (branch > 1 && (f1 * du < 0.0 || (f1 == 0.0 && u1 * du <= 0.0))) {
      branch = 1;
      Side& b = f1 > 0.0 ? s.pos : s.neg;
      b.ulocal = u1;
      b.flocal = f1;
      if (f1 > 0.0 ? u1 > b.uglobal : u1 < b.uglobal) {
        b.uglobal = u1;
        b.fglobal = f1;
      }
      const double elastic = 0.5 * (f1 / s.kunload) * f1;
      const double beta_k = beta(s.energy - s.energy_excursion - elastic, p.Et_k, s.energy - elastic, p.c_k, fail);
      s.kunload *= 1.0 - beta_k;
    }
    // The unloading branch reaching zero force: a new excursion, toward the side du goes to.
    if (branch == 1 && f1 * (f1 + s.kunload * du) <= 0.0) {
      const double ei = std::max(0.0, s.energy - s.energy_excursion);
      const double beta_s = beta(ei, p.Et_s, s.energy, p.c_s, fail);
      const double beta_c = beta(ei, p.Et_c, s.energy, p.c_c, fail);
      const double beta_a = beta(ei, p.Et_a, s.energy, p.c_a, fail);
      s.energy_excursion = s.energy;
      const bool positive = du > 0.0;
      Side& b = positive ? s.pos : s.neg;
      const double D = positive ? p.d_pos : p.d_neg;
      double fcap_projected = b.fcap - b.kpc * b.ucap;  // the post-capping line at zero deformation
      b.fy *= 1.0 - beta_s * D;
      b.kp *= 1.0 - beta_s * D;
      fcap_projected *= 1.0 - beta_c * D;
      b.uglobal *= 1.0 + beta_a * D;
      b.uy = b.fy / p.k;
      const double fy_projected = b.fy - b.kp * b.uy;  // the hardening line at zero deformation
      b.ucap = b.kp <= b.kpc ? 0.0 : (fcap_projected - fy_projected) / (b.kp - b.kpc);
      b.fcap = fy_projected + b.kp * b.ucap;
      b.fglobal = backbone(p, b, b.uglobal, positive);
      b.ures = (b.fres - b.fcap + b.kpc * b.ucap) / b.kpc;
      // Reload toward the local peak if it is on a steeper line from the zero-force point, else the global one.
      const double u0 = u1 - f1 / s.kunload;
      const double k_global = b.fglobal / (b.uglobal - u0), k_local = b.flocal / (b.ulocal - u0);
      const bool local = positive ? (u0 < b.ulocal && b.flocal < b.fglobal && k_local > k_global)
                                  : (u0 > b.ulocal && b.flocal > b.fglobal && k_local > k_global);
      branch = (positive ? 0 : 10) + (local ? 3 : 4);
      s.kreload = local ? k_local : k_global;
    }
    // Advance along the branches (several transitions may happen in one step).
    const Side &P = s.pos, &N = s.neg;
    if (branch == 0 && u > P.uy) {
      branch = 5;
    } else if (branch == 0 && u < N.uy) {
      branch = 15;
    } else if (branch == 1 && f1 > 0.0 && u > P.ulocal) {
      s.kreload = reload(P);
      branch = 4;
    } else if (branch == 1 && f1 < 0.0 && u < N.ulocal) {
      s.kreload = reload(N);
      branch = 14;
    }
    if (branch == 3 && u > P.ulocal) {
      s.kreload = reload(P);
      branch = 4;
    }
    if (branch == 4 && u > P.uglobal) branch = 5;
    if (branch == 5 && u > P.ucap) branch = 6;
    if (branch == 6 && u > P.ures) branch = 7;
    if (branch == 13 && u < N.ulocal) {
      s.kreload = reload(N);
      branch = 14;
    }
    if (branch == 14 && u < N.uglobal) branch = 15;
    if (branch == 15 && u < N.ucap) branch = 16;
    if (branch == 16 && u < N.ures) branch = 17;
    s.branch = branch;
    double f = force_on(p, s, branch, u, u1, f1);
    fail = fail || P.fglobal == 0.0 || N.fglobal == 0.0 || (du > 0.0 && u >= p.uu_pos) || (du < 0.0 && u <= -p.uu_neg) ||
           (branch == 7 && f <= 0.0) || (branch == 17 && f >= 0.0);
    if (fail) {
      f = 0.0;
      s.failed = 1.0;
    }
    s.energy += 0.5 * (f + f1) * du;
    s.f = f;
    return {f, slope(p, s), 0.0, s};
  }

  // The energy released by unloading to zero force; the rest of the work done is dissipated.
  static double recoverable(const Params&, const State& s, double) {
    return s.failed != 0.0 || s.kunload <= 0.0 ? 0.0 : 0.5 * s.f * s.f / s.kunload;
  }
  static double dissipated(const Params& p, const State& s) { return s.energy - recoverable(p, s, s.u); }
  static bool failed(const Params&, const State& s) { return s.failed != 0.0; }
  static bool is_linear(const Params&) { return false; }

 private:
  // beta = (e / (Et - used))^c in [0, 1]. A mode whose reference energy Et is zero is off; nothing
  // dissipated (e <= 0) deteriorates nothing; beta > 1, or the energy used up (Et - used <= 0 with
  // e > 0), fails the law.
  static double beta(double e, double Et, double used, double c, bool& fail) {
    if (Et == 0.0 || !(e > 0.0)) return 0.0;
    const double available = Et - used;
    const double b = available > 0.0 ? std::pow(e / available, c) : 2.0;
    if (b > 1.0) {
      fail = true;
      return 1.0;
    }
    return b;
  }
  // The slope from the local to the global peak (0 where they coincide: the next branch then
  // starts at once and the slope is never used).
  static double reload(const Side& b) {
    return b.uglobal == b.ulocal ? 0.0 : (b.fglobal - b.flocal) / (b.uglobal - b.ulocal);
  }
  // The backbone force at deformation ug on side b, floored at the residual.
  static double backbone(const Params& p, const Side& b, double ug, bool positive) {
    double f;
    if (positive) {
      f = ug < b.uy ? p.k * ug : ug < b.ucap ? b.fy + b.kp * (ug - b.uy) : b.fcap + b.kpc * (ug - b.ucap);
      if (f < b.fres) f = b.fres;
    } else {
      f = b.uy < ug ? p.k * ug : b.ucap < ug ? b.fy + b.kp * (ug - b.uy) : b.fcap + b.kpc * (ug - b.ucap);
      if (b.fres < f) f = b.fres;
    }
    return f;
  }
  static double force_on(const Params& p, const State& s, int branch, double u, double u1, double f1) {
    const Side &P = s.pos, &N = s.neg;
    switch (branch) {
      case 0: return p.k * u;
      case 1: return f1 + s.kunload * (u - u1);
      case 3: return P.flocal + s.kreload * (u - P.ulocal);
      case 4: return P.fglobal + s.kreload * (u - P.uglobal);
      case 5: return P.fcap + P.kp * (u - P.ucap);
      case 6: return P.fcap + P.kpc * (u - P.ucap);
      case 7: return P.fres;
      case 13: return N.flocal + s.kreload * (u - N.ulocal);
      case 14: return N.fglobal + s.kreload * (u - N.uglobal);
      case 15: return N.fcap + N.kp * (u - N.ucap);
      case 16: return N.fcap + N.kpc * (u - N.ucap);
      case 17: return N.fres;
    }
    return 0.0;
  }
  // dF/du on the branch a state is on: the consistent tangent of the update.
  static double slope(const Params& p, const State& s) {
    if (s.failed != 0.0) return 0.0;
    switch (static_cast<int>(s.branch)) {
      case 0: return p.k;
      case 1: return s.kunload;
      case 3:
      case 4:
      case 13:
      case 14: return s.kreload;
      case 5: return s.pos.kp;
      case 6: return s.pos.kpc;
      case 15: return s.neg.kp;
      case 16: return s.neg.kpc;
    }
    return 0.0;  // residual
  }
};

}  // namespace effects
}  // namespace nvib
