// Hand-written implicit loops for benchmarks/implicit.py: the building scene
// (python/nvib/scenes/building.toml) integrated by Newmark and by generalized-
// alpha with full Newton iteration, plain arrays, no nvib, no Eigen.
//
//   6 floors, m = 1e5 kg each; storey springs f = k0 (1 + a d^2) d on the
//   drifts d1 = x1, d_i = x_i - x_{i-1} (k0 = 1e8 N/m, a = 10); ground
//   acceleration a_g = 10 sin(pi t) applied as P = -M r a_g (r = 1):
//       M x'' + G(x, t) = 0,  G = F_s(x) + M r a_g(t),   x(0) = x'(0) = 0.
//
// Each step solves the equation of the step for u_{n+1} by Newton's method,
// as nvib's Newton component does (newton/newton.hpp) and with its convergence
// test, so that both make the same iterations:
//   predictor u_{n+1} = u_n; Newmark relations for a_{n+1}, v_{n+1};
//   residual    r = (1-am) M a_{n+1} + am M a_n + G(u_a, t_a),
//               u_a = (1-af) u_{n+1} + af u_n, t_a = t_{n+1} - af h
//   converged   after at least one iteration, when max|r_i| <= atol + rtol s,
//               s the largest |term| of the three in any row (a residual of
//               exactly 0 at the predictor is accepted at once);
//   iteration   S du = -r, S = (1-am)/(beta h^2) M + (1-af) K_t(u_a), the
//               tangent re-evaluated every iteration (full Newton); a_{n+1}
//               and v_{n+1} follow u_{n+1} by increments, c0 du and c1 du;
//   round-off   when the last increment was negligible (|du| <= atol +
//               1e-3 rtol |u|) and the residual no longer falls, the step is
//               accepted if the residual is within the round-off of its own
//               evaluation (8 eps times the largest row sum of the magnitudes
//               that enter it), else the run stops.
// Newmark is am = af = 0 (beta = 1/4, gamma = 1/2); the paper's GaM is
// am = af = 1/2. rtol = 1e-10 and atol = 1e-12, nvib's defaults; at most 20
// iterations (nvib's default), beyond which the run stops with an error.
//
// Linear solves, two variants (both stated in the output):
//   dense    Gaussian elimination with partial pivoting on the 6 x 6 matrix,
//            sizes fixed at compile time (the algorithm nvib uses at this size);
//   tridiag  the Thomas algorithm on the three diagonals of S (the building's
//            tangent is tridiagonal; no pivoting: S is diagonally dominant).
//
// The saved history (t, u, v, a every SAVE_EVERY steps and the last one, the
// rows nvib's solve() returns) is allocated before the timed loops.
//
// Usage: building_newton_loop DT T_END REPEATS SAVE_EVERY
// Prints one JSON object per (scheme, solver): best and median wall time of
// REPEATS runs, steps, Newton iterations, force and tangent evaluations, the
// final state.
//
// Build: g++ -std=c++17 -O3 -DNDEBUG building_newton_loop.cpp -o building_newton_loop
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <utility>
#include <vector>

#include "bench_args.hpp"
#include "building_model.hpp"

namespace {

using namespace building;
using State = LoopState<N>;
using Output = LoopOutput<N>;
constexpr double RTOL = 1e-10, ATOL = 1e-12;
constexpr int MAX_ITER = 20;

// G(u, t) = F_s(u) + M r a_g(t): everything but the inertia.
inline void force(const double* u, double t, double* g) {
  double f[N + 1];
  storey_forces(u, f);
  const double mag = MASS * ground_acceleration(t);
  for (int i = 0; i < N; ++i) g[i] = (f[i] - f[i + 1]) + mag;
}

// Round-off scale of G: per DOF the sum of |terms| (storey forces on both ends, |M a_g|).
inline void force_magnitude(const double* u, double t, double* g) {
  double f[N + 1];
  storey_forces(u, f);
  const double mag = std::abs(MASS * ground_acceleration(t));
  for (int i = 0; i < N; ++i) g[i] = std::abs(f[i]) + std::abs(f[i + 1]) + mag;
}

// The storey stiffnesses df/dd = k0 (1 + 3 a d^2); K_t is tridiagonal:
// K_ii = k_i + k_{i+1}, K_{i,i+1} = K_{i+1,i} = -k_{i+1} (k_N = 0).
inline void storey_stiffness(const double* u, double* k) {
  double prev = 0.0;
  for (int i = 0; i < N; ++i) {
    const double d = u[i] - prev;
    k[i] = K0 * (1.0 + 3.0 * HARD * d * d);
    prev = u[i];
  }
  k[N] = 0.0;
}

// x <- S^{-1} x for S = diag(c) + cK K_t, S stored densely, by Gaussian elimination with partial pivoting.
inline void solve_dense(const double* k, double cm, double ck, double* x) {
  double S[N][N] = {};
  for (int i = 0; i < N; ++i) {
    S[i][i] = cm * MASS + ck * (k[i] + k[i + 1]);
    if (i + 1 < N) S[i][i + 1] = S[i + 1][i] = -ck * k[i + 1];
  }
  for (int c = 0; c < N; ++c) {
    int p = c;
    for (int i = c + 1; i < N; ++i)
      if (std::abs(S[i][c]) > std::abs(S[p][c])) p = i;
    if (p != c) {
      for (int j = 0; j < N; ++j) std::swap(S[c][j], S[p][j]);
      std::swap(x[c], x[p]);
    }
    const double inv = 1.0 / S[c][c];
    for (int i = c + 1; i < N; ++i) {
      const double l = S[i][c] * inv;
      for (int j = c + 1; j < N; ++j) S[i][j] -= l * S[c][j];
      x[i] -= l * x[c];
    }
  }
  for (int i = N - 1; i >= 0; --i) {
    double s = x[i];
    for (int j = i + 1; j < N; ++j) s -= S[i][j] * x[j];
    x[i] = s / S[i][i];
  }
}

// The same system by the Thomas algorithm on its three diagonals.
inline void solve_tridiag(const double* k, double cm, double ck, double* x) {
  double diag[N], upper[N];
  for (int i = 0; i < N; ++i) {
    diag[i] = cm * MASS + ck * (k[i] + k[i + 1]);
    upper[i] = -ck * k[i + 1];  // S_{i,i+1} = S_{i+1,i}
  }
  for (int i = 1; i < N; ++i) {
    const double l = upper[i - 1] / diag[i - 1];
    diag[i] -= l * upper[i - 1];
    x[i] -= l * x[i - 1];
  }
  x[N - 1] /= diag[N - 1];
  for (int i = N - 2; i >= 0; --i) x[i] = (x[i] - upper[i] * x[i + 1]) / diag[i];
}



struct Counts {
  std::int64_t iters = 0, force_evals = 0, tangent_evals = 0;
};



// One run; false if a step did not converge in MAX_ITER iterations.
template <bool Tridiagonal>
bool run(double h, double am, double af, double beta, double gamma, std::int64_t nsteps, std::int64_t k,
         Output& out, State& s, Counts& c) {
  s = State{};
  c = Counts{};
  double g[N], u1[N], v1[N], a1[N], ua[N], r[N], kt[N + 1];
  force(s.u, 0.0, g);  // a_0 = -M^{-1} G(u_0, 0)
  ++c.force_evals;
  for (int i = 0; i < N; ++i) s.a[i] = -g[i] / MASS;
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  const double c0 = 1.0 / (beta * h * h), c1 = gamma / (beta * h), ca = 0.5 / beta - 1.0;
  const double cm = (1.0 - am) * c0, ck = 1.0 - af;
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    const double t1 = static_cast<double>(n) * h, ta = t1 - af * h;
    for (int i = 0; i < N; ++i) {  // predictor u1 = u_n, its a1 and v1 by the Newmark relations
      u1[i] = s.u[i];
      a1[i] = c0 * (u1[i] - s.u[i] - h * s.v[i]) - ca * s.a[i];
      v1[i] = s.v[i] + h * (1.0 - gamma) * s.a[i] + h * gamma * a1[i];
    }
    double previous = 0.0;
    bool small_step = false;
    for (int it = 0;; ++it) {
      for (int i = 0; i < N; ++i) ua[i] = (1.0 - af) * u1[i] + af * s.u[i];
      force(ua, ta, g);
      ++c.force_evals;
      double norm = 0.0, scale = 0.0;
      for (int i = 0; i < N; ++i) {
        const double inew = (1.0 - am) * MASS * a1[i], iold = am * MASS * s.a[i];
        r[i] = inew + iold + g[i];
        norm = std::max(norm, std::abs(r[i]));
        scale = std::max(scale, std::max(std::abs(inew), std::max(std::abs(iold), std::abs(g[i]))));
      }
      const double tol = ATOL + RTOL * scale;
      if ((it > 0 && norm <= tol) || (it == 0 && norm == 0.0)) break;
      if (it > 0 && small_step && norm >= previous) {
        double mag[N], roundoff = 0.0;
        force_magnitude(ua, ta, mag);
        for (int i = 0; i < N; ++i) {
          const double w = (1.0 - am) * (c0 * (std::abs(u1[i] - s.u[i]) + h * std::abs(s.v[i])) +
                                         std::abs(ca) * std::abs(s.a[i])) +
                           std::abs(am) * std::abs(s.a[i]);
          roundoff = std::max(roundoff, MASS * w + mag[i]);
        }
        if (norm <= tol + 8.0 * 2.220446049250313e-16 * roundoff) break;
        return false;  // stalled above the tolerance
      }
      if (it >= MAX_ITER || !(norm == norm)) return false;
      previous = norm;
      storey_stiffness(ua, kt);
      ++c.tangent_evals;
      for (int i = 0; i < N; ++i) r[i] = -r[i];
      if (Tridiagonal)
        solve_tridiag(kt, cm, ck, r);
      else
        solve_dense(kt, cm, ck, r);
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
    }
    for (int i = 0; i < N; ++i) {
      s.u[i] = u1[i];
      s.v[i] = v1[i];
      s.a[i] = a1[i];
    }
    if (n % k == 0 || n == nsteps) out.save(row, t1, s);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s DT T_END REPEATS SAVE_EVERY\n", argv[0]);
    return 2;
  }
  const double h = std::atof(argv[1]), t_end = std::atof(argv[2]);
  const int repeats = std::atoi(argv[3]);
  const std::int64_t k = std::atoll(argv[4]);
  const std::int64_t nsteps = std::llround(t_end / h);
  using clock = std::chrono::steady_clock;
  struct Case {
    const char* scheme;
    double am, af, beta, gamma;
  };
  const Case cases[] = {{"newmark", 0.0, 0.0, 0.25, 0.5}, {"galpha", 0.5, 0.5, 0.25, 0.5}};
  for (const Case& cs : cases) {
    for (int tri = 0; tri < 2; ++tri) {
      Output out = Output::allocate(nsteps, k);
      State s{};
      Counts c{};
      auto once = [&]() {
        return tri ? run<true>(h, cs.am, cs.af, cs.beta, cs.gamma, nsteps, k, out, s, c)
                   : run<false>(h, cs.am, cs.af, cs.beta, cs.gamma, nsteps, k, out, s, c);
      };
      if (!once()) {  // warm-up, untimed
        std::fprintf(stderr, "%s: Newton did not converge\n", cs.scheme);
        return 1;
      }
      std::vector<double> times;
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = clock::now();
        const bool ok = once();
        const auto t1 = clock::now();
        if (!ok) return 1;
        times.push_back(std::chrono::duration<double>(t1 - t0).count());
      }
      double checksum = 0.0;  // read the history so that it is observable
      for (std::int64_t j = 0; j < out.rows * N; j += 97) checksum += out.u[j];
      std::sort(times.begin(), times.end());
      std::printf("{\"scheme\": \"%s\", \"solver\": \"%s\", \"steps\": %lld, \"save_every\": %lld, \"repeats\": %d, "
                  "\"best\": %.9g, \"median\": %.9g, \"newton_iters\": %lld, \"force_evals\": %lld, "
                  "\"tangent_evals\": %lld, \"checksum\": %.17g, ",
                  cs.scheme, tri ? "tridiag" : "dense", static_cast<long long>(nsteps), static_cast<long long>(k),
                  repeats, times.front(), times[times.size() / 2], static_cast<long long>(c.iters),
                  static_cast<long long>(c.force_evals), static_cast<long long>(c.tangent_evals), checksum);
      print_json_state(s);
      std::printf("}\n");
      std::fflush(stdout);
    }
  }
  return 0;
}
