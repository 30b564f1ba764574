// Hand-written loops for benchmarks/hysteresis.py: the scene building_inelastic
// (python/nvib/scenes/building_inelastic.toml) integrated with plain arrays, no
// nvib, no Eigen, as an engineer would write it for this one model.
//
//   6 floors of mass m_i; storey s carries a bilinear spring (stiffness k_s,
//   yield force fy_s, post-yield stiffness b k_s, kinematic hardening) on its
//   drift d_1 = x_1, d_s = x_s - x_{s-1}; K (the P-delta geometric stiffness)
//   and C (Rayleigh damping) are constant and tridiagonal; the ground
//   acceleration a_g(t) is a record interpolated linearly between its samples
//   (0 outside them), applied as P = -M r a_g (r = 1):
//       M x'' + C x' + K x + F_s(x, history) = -M r a_g(t),   x(0) = x'(0) = 0.
// Every number (masses, k, fy, b, the bands of K and C, the record's times and
// values) is read from MODEL_FILE, written by hysteresis.py from the nvib
// model, so that both programs integrate the same numbers.
//
// The bilinear storey (the return mapping of nvib's effects/laws/bilinear.hpp,
// Simo & Hughes 1998, boxes 1.4-1.5; H = b k / (1 - b)): state dp, the plastic
// deformation;
//   f = k (d - dp); xi = f - H dp; if |xi| > fy: slip = (|xi| - fy) / (k + H),
//   dp += sign(xi) slip, f -= k slip sign(xi); the tangent is k, or k H / (k + H)
//   while yielding.
// The central difference evaluates the force once per step, at the state it
// accepts, so dp is updated in place where it is evaluated (one pass over the
// storeys). Newton keeps the trial dp apart and commits it when the step
// converges.
//
// Schemes:
//   cd       synchronized central difference with the velocity predictor of
//            nvib's CentralDifference (the damping reads v):
//              u += h v + h^2/2 a;  v* = v + h a;  a_new = M^-1 (P - F(u, v*));
//              v += h/2 (a + a_new)
//   newmark  Newmark (beta = 1/4, gamma = 1/2) with full Newton and nvib's
//            convergence test (as benchmarks/cpp/building_newton_loop.cpp):
//            predictor u1 = u_n, residual r = M a1 + G(u1, v1, t1), converged
//            after at least one iteration when max|r_i| <= atol + rtol s (s the
//            largest |M a1|, |G| entry), tangent re-evaluated every iteration;
//            the force pass returns the storey forces and their tangents together.
//            Linear solve by Gaussian elimination with partial pivoting on the
//            dense 6 x 6 (the algorithm nvib uses at this size) or by the Thomas
//            algorithm on the three diagonals.
//   newmark_linear   (elastic storeys only) the linear model as nvib runs one:
//            S factorised once per run, one force evaluation and one solve per step.
// Storeys: "bilinear" (the scene), "elastic" (the same loop with f = k d).
//
// The saved history (t, u, v, a every SAVE_EVERY steps and the last one, the
// rows nvib's solve() returns) is allocated before the timed runs and reused.
//
// Usage:
//   building_inelastic_loop MODEL_FILE REPEATS SAVE_EVERY [--dump=PREFIX]
//     one JSON object per (scheme, storeys, solver): best and median wall time
//     of REPEATS runs, steps, Newton counters, the fraction of storey
//     evaluations on the yield branch (counted in an extra untimed run), the
//     final state. --dump=PREFIX writes the saved u of each case to
//     PREFIX.<scheme>.<storeys>.<solver>.bin (rows x 6 doubles).
//   building_inelastic_loop --chain N STEPS REPEATS DT MASS K FY B C AG_AMP AG_OMEGA [V0_FILE] [--dump=PREFIX]
//     the chain of hysteresis.py, table (c): N storeys of mass MASS, each a
//     spring (elastic) or a bilinear spring (k = K, FY, B) and a damper C on its
//     drift, a_g = AG_AMP sin(AG_OMEGA t); central difference as above, fused
//     into one pass over the storeys; v0 from V0_FILE (N raw doubles) or 0.
//     Prints one JSON object per law (elastic, bilinear); --dump writes the
//     final u to PREFIX.chain.<law>.bin.
//
// Build: g++ -std=c++17 -O3 -DNDEBUG building_inelastic_loop.cpp -o building_inelastic_loop
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "bench_args.hpp"

namespace {

constexpr int N = 6;
constexpr double RTOL = 1e-10, ATOL = 1e-12, EPS = 2.220446049250313e-16;
constexpr int MAX_ITER = 20;
using State = LoopState<N>;
using Output = LoopOutput<N>;
using Clock = std::chrono::steady_clock;

// ---- the model ----------------------------------------------------------------------------------
struct Building {
  double h = 0.0, t_end = 0.0;
  double m[N], minv[N];          // masses and -1/m
  double k[N], fy[N], H[N];      // storeys: H = b k / (1 - b)
  double Kd[N], Ko[N], Cd[N], Co[N];  // diagonals and off-diagonals (K[i][i+1] = K[i+1][i] = Ko[i], Ko[N-1] = 0)
  std::vector<double> rt, ra;    // the record: times, values
};


Building read_building(const char* path) {
  auto f = read_keyed(path);
  auto get = [&](const char* key, std::size_t count) -> const std::vector<double>& {
    const auto it = f.find(key);
    if (it == f.end() || (count > 0 && it->second.size() != count)) {
      std::fprintf(stderr, "%s: '%s' missing or not %zu values\n", path, key, count);
      std::exit(2);
    }
    return it->second;
  };
  Building b;
  if (get("n", 1)[0] != N) {
    std::fprintf(stderr, "%s: this loop is written for %d floors\n", path, N);
    std::exit(2);
  }
  b.h = get("dt", 1)[0];
  b.t_end = get("t_end", 1)[0];
  for (int i = 0; i < N; ++i) {
    b.m[i] = get("mass", N)[i];
    b.minv[i] = -1.0 / b.m[i];
    b.k[i] = get("k", N)[i];
    b.fy[i] = get("fy", N)[i];
    const double bb = get("b", N)[i];
    b.H[i] = bb * b.k[i] / (1.0 - bb);
    b.Kd[i] = get("K_diag", N)[i];
    b.Cd[i] = get("C_diag", N)[i];
    b.Ko[i] = i + 1 < N ? get("K_off", N - 1)[i] : 0.0;
    b.Co[i] = i + 1 < N ? get("C_off", N - 1)[i] : 0.0;
  }
  b.rt = get("record_t", 0);
  b.ra = get("record_a", b.rt.size());
  return b;
}

// The record, linear between samples, 0 outside them; the segment is carried from step to step
// (time only grows within a run).
struct Ground {
  const double *t, *a;
  std::size_t n, seg = 0;
  explicit Ground(const Building& b) : t(b.rt.data()), a(b.ra.data()), n(b.rt.size()) {}
  double operator()(double time) {
    if (time < t[0] || time > t[n - 1]) return 0.0;
    while (seg + 2 < n && time >= t[seg + 1]) ++seg;
    const double w = (time - t[seg]) / (t[seg + 1] - t[seg]);
    return (1.0 - w) * a[seg] + w * a[seg + 1];
  }
};

// The bilinear storey: its force at drift d, dp updated (committed) in place.
inline double bilinear(double k, double fy, double H, double d, double& dp) {
  const double f = k * (d - dp);
  const double xi = f - H * dp;
  const double excess = std::abs(xi) - fy;
  if (excess <= 0.0) return f;
  const double slip = excess / (k + H);
  const double s = xi > 0.0 ? 1.0 : -1.0;
  dp += s * slip;
  return f - k * slip * s;
}

// The same as a trial from the committed dp: force, tangent kt and trial state dpt.
inline double bilinear_trial(double k, double fy, double H, double d, double dp, double& dpt, double& kt) {
  const double f = k * (d - dp);
  const double xi = f - H * dp;
  const double excess = std::abs(xi) - fy;
  if (excess <= 0.0) {
    dpt = dp;
    kt = k;
    return f;
  }
  const double slip = excess / (k + H);
  const double s = xi > 0.0 ? 1.0 : -1.0;
  dpt = dp + s * slip;
  kt = k * H / (k + H);
  return f - k * slip * s;
}

// out_i = m_i a_g + f_i - f_{i+1} + (K u)_i + (C v)_i: everything on the left of M a + ... = 0, the
// storey forces f given (f[N] = 0); K u and C v by columns i-1, i, i+1.
inline double row_force(const Building& b, int i, double ag, const double* f, const double* u, const double* v) {
  double F = b.m[i] * ag + f[i] - f[i + 1];
  if (i > 0) F += b.Ko[i - 1] * u[i - 1];
  F += b.Kd[i] * u[i];
  if (i + 1 < N) F += b.Ko[i] * u[i + 1];
  if (i > 0) F += b.Co[i - 1] * v[i - 1];
  F += b.Cd[i] * v[i];
  if (i + 1 < N) F += b.Co[i] * v[i + 1];
  return F;
}

// a = -M^-1 (M r a_g + F_s(u) + K u + C v), the storeys' dp updated in place (central difference).
template <bool Elastic, bool Count>
inline void acceleration(const Building& b, const double* u, const double* v, double ag, double* dp, double* a,
                         std::int64_t& yields) {
  double f[N + 1];
  double prev = 0.0;
  for (int s = 0; s < N; ++s) {
    const double d = u[s] - prev;
    if (Elastic) {
      f[s] = b.k[s] * d;
    } else {
      if (Count) {
        const double before = dp[s];
        f[s] = bilinear(b.k[s], b.fy[s], b.H[s], d, dp[s]);
        yields += dp[s] != before;
      } else {
        f[s] = bilinear(b.k[s], b.fy[s], b.H[s], d, dp[s]);
      }
    }
    prev = u[s];
  }
  f[N] = 0.0;
  for (int i = 0; i < N; ++i) a[i] = row_force(b, i, ag, f, u, v) * b.minv[i];
}

// One run of the central difference; returns the final state (dp: the final plastic deformations).
template <bool Elastic, bool Count = false>
State run_cd(const Building& b, std::int64_t nsteps, std::int64_t k, Output& out, double* dp, std::int64_t& yields) {
  State s{};
  for (int i = 0; i < N; ++i) dp[i] = 0.0;
  yields = 0;
  Ground ground(b);
  acceleration<Elastic, Count>(b, s.u, s.v, ground(0.0), dp, s.a, yields);
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  const double h = b.h, hh2 = 0.5 * h * h, h2 = 0.5 * h;
  double vs[N], anew[N];
  std::int64_t to_save = k;
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    const double t = static_cast<double>(n) * h;
    for (int i = 0; i < N; ++i) {
      s.u[i] += h * s.v[i] + hh2 * s.a[i];
      vs[i] = s.v[i] + h * s.a[i];
    }
    acceleration<Elastic, Count>(b, s.u, vs, ground(t), dp, anew, yields);
    for (int i = 0; i < N; ++i) {
      s.v[i] += h2 * (s.a[i] + anew[i]);
      s.a[i] = anew[i];
    }
    if (--to_save == 0 || n == nsteps) {
      out.save(row, t, s);
      to_save = k;
    }
  }
  return s;
}

// ---- Newmark + Newton --------------------------------------------------------------------------
struct Counts {
  std::int64_t iters = 0, force_evals = 0, factorizations = 0, yields = 0;
};

// G = M r a_g + F_s(u) + K u + C v at the trial from the committed dp: the storeys' trial states to
// dpt, their tangents to kt (kt[N] = 0).
template <bool Elastic>
inline void force(const Building& b, const double* u, const double* v, double ag, const double* dp, double* dpt,
                  double* kt, double* g) {
  double f[N + 1];
  double prev = 0.0;
  for (int s = 0; s < N; ++s) {
    const double d = u[s] - prev;
    if (Elastic) {
      f[s] = b.k[s] * d;
      kt[s] = b.k[s];
    } else {
      f[s] = bilinear_trial(b.k[s], b.fy[s], b.H[s], d, dp[s], dpt[s], kt[s]);
    }
    prev = u[s];
  }
  f[N] = 0.0;
  kt[N] = 0.0;
  for (int i = 0; i < N; ++i) g[i] = row_force(b, i, ag, f, u, v);
}

// Round-off scale of G (the stall test, rarely reached): per DOF the sum of |terms|.
template <bool Elastic>
inline void force_magnitude(const Building& b, const double* u, const double* v, double ag, const double* dp,
                            double* g) {
  double f[N + 1], dpt, kt;
  double prev = 0.0;
  for (int s = 0; s < N; ++s) {
    const double d = u[s] - prev;
    f[s] = std::abs(Elastic ? b.k[s] * d : bilinear_trial(b.k[s], b.fy[s], b.H[s], d, dp[s], dpt, kt));
    prev = u[s];
  }
  f[N] = 0.0;
  for (int i = 0; i < N; ++i) {
    double x = std::abs(b.m[i] * ag) + f[i] + f[i + 1] + std::abs(b.Kd[i] * u[i]) + std::abs(b.Cd[i] * v[i]);
    if (i > 0) x += std::abs(b.Ko[i - 1] * u[i - 1]) + std::abs(b.Co[i - 1] * v[i - 1]);
    if (i + 1 < N) x += std::abs(b.Ko[i] * u[i + 1]) + std::abs(b.Co[i] * v[i + 1]);
    g[i] = x;
  }
}

// S = cm M + cc C + K + K_s(kt): diagonal and off-diagonal.
inline void iteration_matrix(const Building& b, const double* kt, double cm, double cc, double* diag, double* off) {
  for (int i = 0; i < N; ++i) {
    diag[i] = cm * b.m[i] + cc * b.Cd[i] + b.Kd[i] + kt[i] + kt[i + 1];
    off[i] = i + 1 < N ? cc * b.Co[i] + b.Ko[i] - kt[i + 1] : 0.0;
  }
}

// Dense LU with partial pivoting of the (tridiagonal) S stored as a full 6 x 6 (row-major), in place.
struct DenseLU {
  double S[N][N];
  int perm[N];
  void factor(const double* diag, const double* off) {
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) S[i][j] = 0.0;
    for (int i = 0; i < N; ++i) {
      S[i][i] = diag[i];
      if (i + 1 < N) S[i][i + 1] = S[i + 1][i] = off[i];
    }
    for (int c = 0; c < N; ++c) {
      int p = c;
      for (int i = c + 1; i < N; ++i)
        if (std::abs(S[i][c]) > std::abs(S[p][c])) p = i;
      perm[c] = p;
      if (p != c)
        for (int j = 0; j < N; ++j) std::swap(S[c][j], S[p][j]);
      const double inv = 1.0 / S[c][c];
      for (int i = c + 1; i < N; ++i) {
        S[i][c] *= inv;
        for (int j = c + 1; j < N; ++j) S[i][j] -= S[i][c] * S[c][j];
      }
    }
  }
  void solve(double* x) const {
    for (int c = 0; c < N; ++c) {
      if (perm[c] != c) std::swap(x[c], x[perm[c]]);
      for (int i = c + 1; i < N; ++i) x[i] -= S[i][c] * x[c];
    }
    for (int i = N - 1; i >= 0; --i) {
      double s = x[i];
      for (int j = i + 1; j < N; ++j) s -= S[i][j] * x[j];
      x[i] = s / S[i][i];
    }
  }
};

// The Thomas algorithm on the three diagonals (S is diagonally dominant: no pivoting).
struct Tridiag {
  double d[N], o[N], l[N];
  void factor(const double* diag, const double* off) {
    d[0] = diag[0];
    for (int i = 1; i < N; ++i) {
      l[i] = off[i - 1] / d[i - 1];
      d[i] = diag[i] - l[i] * off[i - 1];
    }
    for (int i = 0; i < N; ++i) o[i] = off[i];
  }
  void solve(double* x) const {
    for (int i = 1; i < N; ++i) x[i] -= l[i] * x[i - 1];
    x[N - 1] /= d[N - 1];
    for (int i = N - 2; i >= 0; --i) x[i] = (x[i] - o[i] * x[i + 1]) / d[i];
  }
};

// One Newmark run. Linear: S factorised once per run, one solve per step (elastic storeys only).
// False if a step does not converge.
template <bool Elastic, class Solver, bool Linear>
bool run_newmark(const Building& b, std::int64_t nsteps, std::int64_t k, Output& out, State& s, double* dp,
                 Counts& c) {
  static_assert(Elastic || !Linear, "a bilinear model is not linear");
  constexpr double beta = 0.25, gamma = 0.5;
  s = State{};
  c = Counts{};
  for (int i = 0; i < N; ++i) dp[i] = 0.0;
  const double h = b.h;
  const double c0 = 1.0 / (beta * h * h), c1 = gamma / (beta * h), ca = 0.5 / beta - 1.0;
  double g[N], u1[N], v1[N], a1[N], r[N], kt[N + 1], dpt[N], diag[N], off[N];
  Ground ground(b);
  force<Elastic>(b, s.u, s.v, ground(0.0), dp, dpt, kt, g);  // a_0 = -M^-1 G(u_0, v_0, 0)
  ++c.force_evals;
  for (int i = 0; i < N; ++i) s.a[i] = g[i] * b.minv[i];
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  Solver solver;
  bool factorized = false;
  std::int64_t to_save = k;
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    const double t1 = static_cast<double>(n) * h, ag = ground(t1);
    for (int i = 0; i < N; ++i) {  // predictor u1 = u_n; a1, v1 by the Newmark relations
      u1[i] = s.u[i];
      a1[i] = c0 * (u1[i] - s.u[i] - h * s.v[i]) - ca * s.a[i];
      v1[i] = s.v[i] + h * (1.0 - gamma) * s.a[i] + h * gamma * a1[i];
    }
    double previous = 0.0;
    bool small_step = false;
    for (int it = 0;; ++it) {
      force<Elastic>(b, u1, v1, ag, dp, dpt, kt, g);
      ++c.force_evals;
      double norm = 0.0, scale = 0.0;
      for (int i = 0; i < N; ++i) {
        const double inertia = b.m[i] * a1[i];
        r[i] = inertia + g[i];
        norm = std::max(norm, std::abs(r[i]));
        scale = std::max(scale, std::max(std::abs(inertia), std::abs(g[i])));
      }
      const double tol = ATOL + RTOL * scale;
      if ((it > 0 && norm <= tol) || (it == 0 && norm == 0.0)) break;
      if (!Linear && it > 0 && small_step && norm >= previous) {
        double mag[N], roundoff = 0.0;
        force_magnitude<Elastic>(b, u1, v1, ag, dp, mag);
        for (int i = 0; i < N; ++i) {
          const double w = c0 * (std::abs(u1[i] - s.u[i]) + h * std::abs(s.v[i])) + std::abs(ca) * std::abs(s.a[i]);
          roundoff = std::max(roundoff, b.m[i] * w + mag[i]);
        }
        if (norm <= tol + 8.0 * EPS * roundoff) break;
        return false;  // stalled above the tolerance
      }
      if (it >= MAX_ITER || !(norm == norm)) return false;
      previous = norm;
      if (!Linear || !factorized) {
        iteration_matrix(b, kt, c0, c1, diag, off);
        solver.factor(diag, off);
        factorized = true;
        ++c.factorizations;
      }
      for (int i = 0; i < N; ++i) r[i] = -r[i];
      solver.solve(r);
      double du = 0.0, un = 0.0;
      for (int i = 0; i < N; ++i) {  // the kinematics by increments: da1 = c0 du, dv1 = c1 du
        u1[i] += r[i];
        a1[i] += c0 * r[i];
        v1[i] += c1 * r[i];
        du = std::max(du, std::abs(r[i]));
        un = std::max(un, std::abs(u1[i]));
      }
      small_step = du <= ATOL + 1e-3 * RTOL * un;
      ++c.iters;
      if (Linear) break;  // in equilibrium after one solve (the residual is not evaluated again)
    }
    for (int i = 0; i < N; ++i) {
      s.u[i] = u1[i];
      s.v[i] = v1[i];
      s.a[i] = a1[i];
      if (!Elastic) {
        c.yields += dpt[i] != dp[i];
        dp[i] = dpt[i];  // commit the converged trial
      }
    }
    if (--to_save == 0 || n == nsteps) {
      out.save(row, t1, s);
      to_save = k;
    }
  }
  return true;
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void print_times(std::vector<double>& times) {
  std::sort(times.begin(), times.end());
  std::printf("\"best\": %.9g, \"median\": %.9g, ", times.front(), times[times.size() / 2]);
}

double checksum_of(const Output& out) {
  double c = 0.0;  // read the saved history so that it is observable
  for (std::int64_t j = 0; j < out.rows * N; j += 97) c += out.u[j];
  return c;
}

bool dump_output(const std::string& dump, const std::string& tag, const Output& out) {
  if (dump.empty()) return true;
  return write_doubles(dump + "." + tag + ".bin", out.u.get(), static_cast<size_t>(out.rows * N));
}

template <bool Elastic>
int bench_cd(const Building& b, std::int64_t nsteps, std::int64_t k, int repeats, const std::string& dump) {
  Output out = Output::allocate(nsteps, k);
  double dp[N];
  std::int64_t yields = 0;
  State s = run_cd<Elastic, true>(b, nsteps, k, out, dp, yields);  // untimed: warms up, counts the yield branch
  const std::int64_t counted = yields;
  std::vector<double> times;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    s = run_cd<Elastic>(b, nsteps, k, out, dp, yields);
    times.push_back(seconds_since(t0));
  }
  if (!dump_output(dump, std::string("cd.") + (Elastic ? "elastic" : "bilinear") + ".-", out)) return 1;
  std::printf("{\"scheme\": \"cd\", \"storeys\": \"%s\", \"solver\": \"-\", \"save_every\": %lld, \"steps\": %lld, "
              "\"saved\": %lld, \"repeats\": %d, ",
              Elastic ? "elastic" : "bilinear", static_cast<long long>(k), static_cast<long long>(nsteps),
              static_cast<long long>(out.rows), repeats);
  print_times(times);
  std::printf("\"force_evals\": %lld, \"newton_iters\": 0, \"factorizations\": 0, \"yield_fraction\": %.6g, "
              "\"checksum\": %.17g, ",
              static_cast<long long>(nsteps + 1), static_cast<double>(counted) / (N * static_cast<double>(nsteps + 1)),
              checksum_of(out));
  print_json_vector("dp", dp, N);
  std::printf(", ");
  print_json_state(s);
  std::printf("}\n");
  std::fflush(stdout);
  return 0;
}

template <bool Elastic, class Solver, bool Linear>
int bench_newmark(const Building& b, std::int64_t nsteps, std::int64_t k, int repeats, const char* solver,
                  const std::string& dump) {
  Output out = Output::allocate(nsteps, k);
  State s{};
  Counts c{};
  double dp[N];
  const char* scheme = Linear ? "newmark_linear" : "newmark";
  if (!run_newmark<Elastic, Solver, Linear>(b, nsteps, k, out, s, dp, c)) {  // warm-up, untimed
    std::fprintf(stderr, "%s %s: Newton did not converge\n", scheme, solver);
    return 1;
  }
  std::vector<double> times;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    const bool ok = run_newmark<Elastic, Solver, Linear>(b, nsteps, k, out, s, dp, c);
    times.push_back(seconds_since(t0));
    if (!ok) return 1;
  }
  if (!dump_output(dump, std::string(scheme) + "." + (Elastic ? "elastic" : "bilinear") + "." + solver, out)) return 1;
  std::printf("{\"scheme\": \"%s\", \"storeys\": \"%s\", \"solver\": \"%s\", \"save_every\": %lld, \"steps\": %lld, "
              "\"saved\": %lld, \"repeats\": %d, ",
              scheme, Elastic ? "elastic" : "bilinear", solver, static_cast<long long>(k),
              static_cast<long long>(nsteps), static_cast<long long>(out.rows), repeats);
  print_times(times);
  std::printf("\"force_evals\": %lld, \"newton_iters\": %lld, \"factorizations\": %lld, \"yield_fraction\": %.6g, "
              "\"checksum\": %.17g, ",
              static_cast<long long>(c.force_evals), static_cast<long long>(c.iters),
              static_cast<long long>(c.factorizations),
              Elastic ? 0.0 : static_cast<double>(c.yields) / (N * static_cast<double>(nsteps)), checksum_of(out));
  print_json_vector("dp", dp, N);
  std::printf(", ");
  print_json_state(s);
  std::printf("}\n");
  std::fflush(stdout);
  return 0;
}

int building_main(int argc, char** argv) {
  std::string dump = take_dump(argc, argv);
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s MODEL_FILE REPEATS SAVE_EVERY [--dump=PREFIX]\n", argv[0]);
    return 2;
  }
  const Building b = read_building(argv[1]);
  const int repeats = std::atoi(argv[2]);
  const std::int64_t k = std::atoll(argv[3]);
  const std::int64_t nsteps = std::llround(b.t_end / b.h);
  if (repeats < 1 || k < 1) return 2;
  int rc = 0;
  rc |= bench_cd<false>(b, nsteps, k, repeats, dump);
  rc |= bench_cd<true>(b, nsteps, k, repeats, dump);
  rc |= bench_newmark<false, DenseLU, false>(b, nsteps, k, repeats, "dense", dump);
  rc |= bench_newmark<false, Tridiag, false>(b, nsteps, k, repeats, "tridiag", dump);
  rc |= bench_newmark<true, DenseLU, false>(b, nsteps, k, repeats, "dense", dump);
  rc |= bench_newmark<true, DenseLU, true>(b, nsteps, k, repeats, "dense", dump);
  rc |= bench_newmark<true, Tridiag, true>(b, nsteps, k, repeats, "tridiag", dump);
  return rc;
}

// ---- the chain (table (c)) ----------------------------------------------------------------------
struct Chain {
  std::size_t n = 0;
  double h = 0.0, m = 0.0, k = 0.0, fy = 0.0, H = 0.0, c = 0.0, ag_amp = 0.0, ag_omega = 0.0;
};

// One step's force pass, fused: a_i = -(m a_g + f_i - f_{i+1}) / m, f_i the storey's spring (law)
// and damper on its drift (storey 0 against the ground, no storey above the top); dp in place.
template <bool Elastic, bool Count>
inline void chain_acceleration(const Chain& ch, const double* __restrict u, const double* __restrict v, double t,
                               double* __restrict dp, double* __restrict a, std::int64_t& yields) {
  const std::size_t n = ch.n;
  const double mag = ch.m * (ch.ag_amp * std::sin(ch.ag_omega * t)), minv = -1.0 / ch.m;
  auto storey = [&](std::size_t s, double d, double dd) {
    double f;
    if (Elastic) {
      f = ch.k * d;
    } else if (Count) {
      const double before = dp[s];
      f = bilinear(ch.k, ch.fy, ch.H, d, dp[s]);
      yields += dp[s] != before;
    } else {
      f = bilinear(ch.k, ch.fy, ch.H, d, dp[s]);
    }
    return f + ch.c * dd;
  };
  double below = storey(0, u[0], v[0]);
  for (std::size_t i = 0; i < n; ++i) {
    const double above = i + 1 < n ? storey(i + 1, u[i + 1] - u[i], v[i + 1] - v[i]) : 0.0;
    a[i] = (mag + below - above) * minv;
    below = above;
  }
}

template <bool Elastic, bool Count = false>
void run_chain(const Chain& ch, std::int64_t steps, const std::vector<double>& v0, std::vector<double>& u,
               std::vector<double>& v, std::vector<double>& a, std::vector<double>& vs, std::vector<double>& an,
               std::vector<double>& dp, std::int64_t& yields) {
  const std::size_t n = ch.n;
  std::fill(u.begin(), u.end(), 0.0);
  std::copy(v0.begin(), v0.end(), v.begin());
  std::fill(dp.begin(), dp.end(), 0.0);
  yields = 0;
  chain_acceleration<Elastic, Count>(ch, u.data(), v.data(), 0.0, dp.data(), a.data(), yields);
  const double h = ch.h, hh2 = 0.5 * h * h, h2 = 0.5 * h;
  double *__restrict up = u.data(), *__restrict vp = v.data(), *__restrict ap = a.data(), *__restrict vsp = vs.data(),
                     *__restrict anp = an.data();
  for (std::int64_t s = 1; s <= steps; ++s) {
    const double t = static_cast<double>(s) * h;
    for (std::size_t i = 0; i < n; ++i) {
      up[i] += h * vp[i] + hh2 * ap[i];
      vsp[i] = vp[i] + h * ap[i];
    }
    chain_acceleration<Elastic, Count>(ch, up, vsp, t, dp.data(), anp, yields);
    for (std::size_t i = 0; i < n; ++i) {
      vp[i] += h2 * (ap[i] + anp[i]);
      ap[i] = anp[i];
    }
  }
}

template <bool Elastic>
int bench_chain(const Chain& ch, std::int64_t steps, int repeats, const std::vector<double>& v0,
                const std::string& dump) {
  const std::size_t n = ch.n;
  std::vector<double> u(n), v(n), a(n), vs(n), an(n), dp(n);
  std::int64_t yields = 0;
  run_chain<Elastic, true>(ch, steps, v0, u, v, a, vs, an, dp, yields);  // untimed: warms up, counts
  const std::int64_t counted = yields;
  std::vector<double> times;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    run_chain<Elastic>(ch, steps, v0, u, v, a, vs, an, dp, yields);
    times.push_back(seconds_since(t0));
  }
  if (!dump.empty() && !write_doubles(dump + ".chain." + (Elastic ? "elastic" : "bilinear") + ".bin", u.data(), n))
    return 1;
  std::printf("{\"law\": \"%s\", \"n\": %zu, \"steps\": %lld, \"dt\": %.17g, \"repeats\": %d, ",
              Elastic ? "elastic" : "bilinear", n, static_cast<long long>(steps), ch.h, repeats);
  print_times(times);
  std::printf("\"yield_fraction\": %.6g, \"u_top\": %.17g}\n",
              static_cast<double>(counted) / (static_cast<double>(n) * static_cast<double>(steps + 1)), u[n - 1]);
  std::fflush(stdout);
  return 0;
}

int chain_main(int argc, char** argv) {
  std::string dump = take_dump(argc, argv);
  if (argc != 13 && argc != 14) {
    std::fprintf(stderr,
                 "usage: %s --chain N STEPS REPEATS DT MASS K FY B C AG_AMP AG_OMEGA [V0_FILE] [--dump=PREFIX]\n",
                 argv[0]);
    return 2;
  }
  Chain ch;
  ch.n = static_cast<std::size_t>(std::atoll(argv[2]));
  const std::int64_t steps = std::atoll(argv[3]);
  const int repeats = std::atoi(argv[4]);
  ch.h = std::atof(argv[5]);
  ch.m = std::atof(argv[6]);
  ch.k = std::atof(argv[7]);
  ch.fy = std::atof(argv[8]);
  const double b = std::atof(argv[9]);
  ch.H = b * ch.k / (1.0 - b);
  ch.c = std::atof(argv[10]);
  ch.ag_amp = std::atof(argv[11]);
  ch.ag_omega = std::atof(argv[12]);
  std::vector<double> v0(ch.n, 0.0);
  if (argc == 14) {
    std::FILE* fh = std::fopen(argv[13], "rb");
    if (!fh || std::fread(v0.data(), sizeof(double), ch.n, fh) != ch.n) {
      std::fprintf(stderr, "cannot read %zu doubles from %s\n", ch.n, argv[13]);
      return 2;
    }
    std::fclose(fh);
  }
  if (ch.n < 2 || steps < 1 || repeats < 1) return 2;
  int rc = 0;
  rc |= bench_chain<true>(ch, steps, repeats, v0, dump);
  rc |= bench_chain<false>(ch, steps, repeats, v0, dump);
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "--chain") == 0) return chain_main(argc, argv);
  return building_main(argc, argv);
}
