// Hand-written reference loop for benchmarks/building.py: the building scene
// (python/nvib/scenes/building.toml) integrated with plain arrays, no nvib,
// no Eigen.
//
//   6 floors, m = 1e5 kg each; storey springs f = k0 (1 + a d^2) d on the
//   drifts d1 = x1, d_i = x_i - x_{i-1} (k0 = 1e8 N/m, a = 10); ground
//   acceleration a_g = 10 sin(pi t) applied as P = -M r a_g (r = 1):
//       M x'' + F_s(x) = -M r a_g(t),   x(0) = x'(0) = 0.
//
// Schemes (the formulas of nvib's headers, written out by hand):
//   cd      synchronized leapfrog central difference
//             u += h v + h^2/2 a;  a_new = acc(u, t+h);  v += h/2 (a + a_new)
//   cemdts  CEMDTS(eta):
//             u_{n+1} = u_n + h v_n + h^2 [(1/2 + eta) a_n - eta a_{n-1}]
//             a_{n+1} = acc(u_{n+1}, t_{n+1})
//             v_{n+1} = v_n + h [(1/2 - eta) a_{n+1} + (1/2 + 2 eta) a_n - eta a_{n-1}]
//             a_{-1} = a_0
//   zhai    Zhai(psi, phi) at psi = phi = 1/2 (nvib's defaults):
//             u_{n+1} = u_n + h v_n + h^2 [(1/2 + psi) a_n - psi a_{n-1}]
//             v_{n+1} = v_n + h [(1 + phi) a_n - phi a_{n-1}]
//             a_{n+1} = acc(u_{n+1}, t_{n+1}),   a_{-1} = a_0
//
// The output (t, u, v, a of the saved states: steps 0, k, 2k, ... and the last
// one, the rows nvib's solve() returns) is allocated before the loop and
// filled in place. "best" reuses one preallocated output for every run (no
// page faults); "best_fresh" allocates it inside every timed run, as
// nvib::solve() does (fresh memory from the OS faults in on first touch).
//
// Usage: building_loop DT T_END REPEATS ETA SAVE_EVERY [SAVE_EVERY ...] [--dump=PREFIX]
// Prints one JSON object per (scheme, save_every) line: the best and median
// wall time of REPEATS runs, the best with fresh output, and the final state
// (so the work cannot be optimised away, and so the caller can compare with
// nvib). With --dump=PREFIX the saved displacements of the reused output are
// written to PREFIX.<scheme>.<save_every>.bin (row-major doubles, rows x 6),
// so benchmarks/cost.py can measure the loop's own error.
//
// Build: g++ -std=c++17 -O3 -DNDEBUG building_loop.cpp -o building_loop
// (the flags of nvib's Release wheel: no -march=native).
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
#include "building_model.hpp"

namespace {

using namespace building;
using State = LoopState<N>;
using Output = LoopOutput<N>;

// a = M^{-1} (-F_s(u)) - r a_g(t)
inline void acc(const double* u, double t, double* a) {
  double f[N + 1];
  storey_forces(u, f);
  const double ag = ground_acceleration(t);
  for (int i = 0; i < N; ++i) a[i] = -(f[i] - f[i + 1]) / MASS - ag;
}





// One run of the central difference; returns the final state.
State run_cd(double h, std::int64_t nsteps, std::int64_t k, Output& out) {
  State s{};
  acc(s.u, 0.0, s.a);
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  const double hh2 = 0.5 * h * h, h2 = 0.5 * h;
  double anew[N];
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    const double t = static_cast<double>(n) * h;
    for (int i = 0; i < N; ++i) s.u[i] += h * s.v[i] + hh2 * s.a[i];
    acc(s.u, t, anew);
    for (int i = 0; i < N; ++i) {
      s.v[i] += h2 * (s.a[i] + anew[i]);
      s.a[i] = anew[i];
    }
    if (n % k == 0 || n == nsteps) out.save(row, t, s);
  }
  return s;
}

// One run of CEMDTS(eta); returns the final state.
State run_cemdts(double h, double eta, std::int64_t nsteps, std::int64_t k, Output& out) {
  State s{};
  acc(s.u, 0.0, s.a);
  double aprev[N], anew[N];
  for (int i = 0; i < N; ++i) aprev[i] = s.a[i];  // a_{-1} = a_0
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  const double hh = h * h;
  const double cu1 = (0.5 + eta) * hh, cu2 = eta * hh;
  const double cv1 = (0.5 - eta) * h, cv2 = (0.5 + 2.0 * eta) * h, cv3 = eta * h;
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    const double t = static_cast<double>(n) * h;
    for (int i = 0; i < N; ++i) s.u[i] += h * s.v[i] + cu1 * s.a[i] - cu2 * aprev[i];
    acc(s.u, t, anew);
    for (int i = 0; i < N; ++i) {
      s.v[i] += cv1 * anew[i] + cv2 * s.a[i] - cv3 * aprev[i];
      aprev[i] = s.a[i];
      s.a[i] = anew[i];
    }
    if (n % k == 0 || n == nsteps) out.save(row, t, s);
  }
  return s;
}

// One run of Zhai(psi, phi); returns the final state.
State run_zhai(double h, double psi, double phi, std::int64_t nsteps, std::int64_t k, Output& out) {
  State s{};
  acc(s.u, 0.0, s.a);
  double aprev[N];
  for (int i = 0; i < N; ++i) aprev[i] = s.a[i];  // a_{-1} = a_0
  std::int64_t row = 0;
  out.save(row, 0.0, s);
  const double hh = h * h;
  const double cu1 = (0.5 + psi) * hh, cu2 = psi * hh, cv1 = (1.0 + phi) * h, cv2 = phi * h;
  for (std::int64_t n = 1; n <= nsteps; ++n) {
    const double t = static_cast<double>(n) * h;
    for (int i = 0; i < N; ++i) {
      s.u[i] += h * s.v[i] + cu1 * s.a[i] - cu2 * aprev[i];
      s.v[i] += cv1 * s.a[i] - cv2 * aprev[i];
      aprev[i] = s.a[i];
    }
    acc(s.u, t, s.a);
    if (n % k == 0 || n == nsteps) out.save(row, t, s);
  }
  return s;
}

const char* const kSchemes[] = {"cd", "cemdts", "zhai"};

}  // namespace

int main(int argc, char** argv) {
  BenchArgs args;
  if (!parse_bench_args(argc, argv, args)) return 2;
  const double h = args.h, t_end = args.t_end, eta = args.eta;
  const int repeats = args.repeats;
  const std::string& dump = args.dump;
  const std::int64_t nsteps = std::llround(t_end / h);
  using clock = std::chrono::steady_clock;

  for (int scheme = 0; scheme < 3; ++scheme) {
    for (const std::int64_t k : args.save_every) {
      // reuse: one preallocated output, warmed by an untimed run, filled again by every timed run.
      // fresh: the output allocated in every timed run (inside the timing, page faults included).
      std::vector<double> times, fresh;
      State last{};
      double checksum = 0.0;
      std::int64_t rows = 0;
      auto run = [&](Output& out) {
        if (scheme == 0) return run_cd(h, nsteps, k, out);
        if (scheme == 1) return run_cemdts(h, eta, nsteps, k, out);
        return run_zhai(h, 0.5, 0.5, nsteps, k, out);
      };
      Output kept = Output::allocate(nsteps, k);
      last = run(kept);
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = clock::now();
        last = run(kept);
        const auto t1 = clock::now();
        times.push_back(std::chrono::duration<double>(t1 - t0).count());
      }
      // Read the saved history outside the timed region so it is observable.
      for (std::int64_t j = 0; j < kept.rows * N; j += 97) checksum += kept.u[j];
      rows = kept.rows;
      if (!dump.empty()) {
        const std::string path = dump + "." + kSchemes[scheme] + "." + std::to_string(k) + ".bin";
        if (!write_doubles(path, kept.u.get(), static_cast<size_t>(kept.rows * N))) return 1;
      }
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = clock::now();
        Output out = Output::allocate(nsteps, k);
        const State s = run(out);
        const auto t1 = clock::now();
        fresh.push_back(std::chrono::duration<double>(t1 - t0).count());
        double c = 0.0;
        for (std::int64_t j = 0; j < out.rows * N; j += 97) c += out.u[j];
        if (c != checksum || s.u[0] != last.u[0]) {
          std::fprintf(stderr, "fresh and reused runs differ\n");
          return 1;
        }
      }
      std::sort(times.begin(), times.end());
      std::sort(fresh.begin(), fresh.end());
      std::printf("{\"scheme\": \"%s\", \"save_every\": %lld, \"steps\": %lld, \"saved\": %lld, \"repeats\": %d, "
                  "\"best\": %.9g, \"median\": %.9g, \"best_fresh\": %.9g, \"checksum\": %.17g, ",
                  kSchemes[scheme], static_cast<long long>(k), static_cast<long long>(nsteps),
                  static_cast<long long>(rows), repeats, times.front(), times[times.size() / 2], fresh.front(),
                  checksum);
      print_json_state(last);
      std::printf("}\n");
      std::fflush(stdout);
    }
  }
  return 0;
}
