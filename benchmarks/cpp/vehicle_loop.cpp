// Hand-written reference loop for benchmarks/cost.py: the vehicle scene
// (python/nvib/scenes/vehicle.toml: Huo & Dai 2019's passenger car) integrated with
// plain arrays, no nvib, no Eigen.
//
//   q = [z_c, beta_c, z_t1, beta_t1, z_t2, beta_t2, z_w1, z_w2, z_w3, z_w4], z downward.
//   Secondary suspension (2 K_sz, 2 C_sz per bogie) on d = z_ti - (z_c -/+ l_c beta_c),
//   primary (2 K_pz, 2 C_pz per wheelset) on d = z_wj - (z_ti -/+ l_t beta_ti),
//   Hertz contact on each wheelset, two wheels: f = 2 (max(z_wj, 0) / G)^{3/2},
//   gravity on every bounce DOF:
//       M q'' + F(q, q') = 0,  q(0) = the static equilibrium (given), q'(0) given.
//
// Schemes (the formulas of nvib's headers, written out by hand; the forces use
// the velocity, so both evaluate them with a predicted velocity v*):
//   cd      synchronized leapfrog: u += h v + h^2/2 a; v* = v + h a;
//           a_new = acc(u, v*); v += h/2 (a + a_new)
//   cemdts  CEMDTS(eta): u += h v + h^2 [(1/2 + eta) a_n - eta a_{n-1}];
//           v* = v + h [(1 + eta) a_n - eta a_{n-1}]; a_{n+1} = acc(u, v*);
//           v += h [(1/2 - eta) a_{n+1} + (1/2 + 2 eta) a_n - eta a_{n-1}]; a_{-1} = a_0
//
// The output (t, u, v, a of steps 0, k, 2k, ... and the last) is allocated
// before the loop and reused across the timed runs.
//
// Usage: vehicle_loop DT T_END REPEATS ETA SAVE_EVERY U0_1 .. U0_10 V0_1 .. V0_10 [--dump=PREFIX]
// Prints one JSON object per scheme: best and median wall time of REPEATS
// runs and the final state. With --dump=PREFIX the saved displacements of the
// last run are written to PREFIX.<scheme>.bin (row-major doubles, rows x 10).
//
// Build: g++ -std=c++17 -O3 -DNDEBUG vehicle_loop.cpp -o vehicle_loop
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bench_args.hpp"

namespace {

constexpr int N = 10;
using State = LoopState<N>;
using Output = LoopOutput<N>;
enum { ZC, BC, ZT1, BT1, ZT2, BT2, ZW1, ZW2, ZW3, ZW4 };
constexpr double MASS[N] = {34500.0, 1560400.0, 3500.0, 1722.0, 3500.0, 1722.0, 2200.0, 2200.0, 2200.0, 2200.0};
constexpr double WEIGHT[N] = {338445.0, 0.0, 34335.0, 0.0, 34335.0, 0.0, 21582.0, 21582.0, 21582.0, 21582.0};
constexpr double KS = 1220000.0, CS = 19600.0;  // secondary, per bogie (2 x K_sz, 2 x C_sz)
constexpr double KP = 2346000.0, CP = 39200.0;  // primary, per wheelset (2 x K_pz, 2 x C_pz)
constexpr double LC = 8.75, LT = 1.25, G = 5.18e-08, WHEELS = 2.0;

// a = -M^{-1} F(u, v)
inline void acc(const double* u, const double* v, double* a) {
  double f[N];
  for (int i = 0; i < N; ++i) f[i] = -WEIGHT[i];
  // secondary suspension: front bogie (-l_c beta_c side), rear bogie (+)
  {
    const double s1 = KS * (u[ZT1] - u[ZC] + LC * u[BC]) + CS * (v[ZT1] - v[ZC] + LC * v[BC]);
    const double s2 = KS * (u[ZT2] - u[ZC] - LC * u[BC]) + CS * (v[ZT2] - v[ZC] - LC * v[BC]);
    f[ZT1] += s1;
    f[ZT2] += s2;
    f[ZC] -= s1 + s2;
    f[BC] += LC * (s1 - s2);
  }
  // primary suspension: each bogie carries a front (-l_t beta_t) and a rear (+) wheelset
  for (int b = 0; b < 2; ++b) {
    const int zt = b == 0 ? ZT1 : ZT2, bt = zt + 1, wf = ZW1 + 2 * b, wr = wf + 1;
    const double pf = KP * (u[wf] - u[zt] + LT * u[bt]) + CP * (v[wf] - v[zt] + LT * v[bt]);
    const double pr = KP * (u[wr] - u[zt] - LT * u[bt]) + CP * (v[wr] - v[zt] - LT * v[bt]);
    f[wf] += pf;
    f[wr] += pr;
    f[zt] -= pf + pr;
    f[bt] += LT * (pf - pr);
  }
  // wheel-rail contact on a rigid smooth rail: zero force once the wheel leaves it
  for (int w = ZW1; w <= ZW4; ++w) {
    if (u[w] > 0.0) {
      const double r = u[w] / G;
      f[w] += WHEELS * r * std::sqrt(r);
    }
  }
  for (int i = 0; i < N; ++i) a[i] = -f[i] / MASS[i];
}





State start(const double* u0, const double* v0) {
  State s{};
  for (int i = 0; i < N; ++i) {
    s.u[i] = u0[i];
    s.v[i] = v0[i];
  }
  acc(s.u, s.v, s.a);
  return s;
}

State run_cd(const double* u0, const double* v0, double h, std::int64_t nsteps, std::int64_t k, Output& out) {
  State s = start(u0, v0);
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  const double hh2 = 0.5 * h * h, h2 = 0.5 * h;
  double anew[N], vstar[N];
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    for (int i = 0; i < N; ++i) {
      s.u[i] += h * s.v[i] + hh2 * s.a[i];
      vstar[i] = s.v[i] + h * s.a[i];
    }
    acc(s.u, vstar, anew);
    for (int i = 0; i < N; ++i) {
      s.v[i] += h2 * (s.a[i] + anew[i]);
      s.a[i] = anew[i];
    }
    if (n % k == 0 || n == nsteps) out.save(row, static_cast<double>(n) * h, s);
  }
  return s;
}

State run_cemdts(const double* u0, const double* v0, double h, double eta, std::int64_t nsteps, std::int64_t k,
                 Output& out) {
  State s = start(u0, v0);
  double aprev[N], anew[N], vstar[N];
  for (int i = 0; i < N; ++i) aprev[i] = s.a[i];  // a_{-1} = a_0
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  const double hh = h * h;
  const double cu1 = (0.5 + eta) * hh, cu2 = eta * hh;
  const double cp1 = (1.0 + eta) * h, cp2 = eta * h;
  const double cv1 = (0.5 - eta) * h, cv2 = (0.5 + 2.0 * eta) * h, cv3 = eta * h;
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    for (int i = 0; i < N; ++i) {
      s.u[i] += h * s.v[i] + cu1 * s.a[i] - cu2 * aprev[i];
      vstar[i] = s.v[i] + cp1 * s.a[i] - cp2 * aprev[i];
    }
    acc(s.u, vstar, anew);
    for (int i = 0; i < N; ++i) {
      s.v[i] += cv1 * anew[i] + cv2 * s.a[i] - cv3 * aprev[i];
      aprev[i] = s.a[i];
      s.a[i] = anew[i];
    }
    if (n % k == 0 || n == nsteps) out.save(row, static_cast<double>(n) * h, s);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dump = take_dump(argc, argv);
  if (argc != 6 + 2 * N) {
    std::fprintf(stderr, "usage: %s DT T_END REPEATS ETA SAVE_EVERY U0 x10 V0 x10 [--dump=PREFIX]\n", argv[0]);
    return 2;
  }
  const double h = std::atof(argv[1]), t_end = std::atof(argv[2]);
  const int repeats = std::max(1, std::atoi(argv[3]));
  const double eta = std::atof(argv[4]);
  const std::int64_t k = std::max<std::int64_t>(1, std::atoll(argv[5]));
  double u0[N], v0[N];
  for (int i = 0; i < N; ++i) {
    u0[i] = std::atof(argv[6 + i]);
    v0[i] = std::atof(argv[6 + N + i]);
  }
  const std::int64_t nsteps = std::llround(t_end / h);
  using clock = std::chrono::steady_clock;

  for (int scheme = 0; scheme < 2; ++scheme) {
    Output out = Output::allocate(nsteps, k);
    auto run = [&]() {
      return scheme == 0 ? run_cd(u0, v0, h, nsteps, k, out) : run_cemdts(u0, v0, h, eta, nsteps, k, out);
    };
    State last = run();  // warm-up: pages the output in
    std::vector<double> times;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = clock::now();
      last = run();
      const auto t1 = clock::now();
      times.push_back(std::chrono::duration<double>(t1 - t0).count());
    }
    const char* name = scheme == 0 ? "cd" : "cemdts";
    if (!dump.empty()) {
      const std::string path = dump + "." + name + ".bin";
      if (!write_doubles(path, out.u.get(), static_cast<size_t>(out.rows * N))) return 1;
    }
    std::sort(times.begin(), times.end());
    std::printf("{\"scheme\": \"%s\", \"save_every\": %lld, \"steps\": %lld, \"saved\": %lld, \"repeats\": %d, "
                "\"best\": %.9g, \"median\": %.9g, ",
                name, static_cast<long long>(k), static_cast<long long>(nsteps), static_cast<long long>(out.rows),
                repeats, times.front(), times[times.size() / 2]);
    print_json_state(last);
    std::printf("}\n");
    std::fflush(stdout);
  }
  return 0;
}
