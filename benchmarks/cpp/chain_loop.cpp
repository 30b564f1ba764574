// Hand-written central-difference loop for benchmarks/scale.py: nvib.scenes.chain(n) (a shear
// chain of n storeys: masses m, hardening storey springs f = k0 (1 + a d^2) d and dampers c on
// the drifts d_1 = x_1, d_i = x_i - x_{i-1}, ground acceleration a_g = A sin(w t) applied as
// -M r a_g), with plain arrays, no nvib, no Eigen: the baseline of the explicit schemes' cost
// per step per DOF at scale.
//
//   synchronized leapfrog: u += h v + h^2/2 a; v* = v + h a; a_new = acc(u, v*, t+h);
//                          v += h/2 (a + a_new)
// (the velocity predictor v* because the dampers use velocity, as nvib's CentralDifference does).
//
// Usage: chain_loop N STEPS REPEATS [DT]    (defaults of nvib.scenes.chain: m = 1e5, k0 = 1e8,
// a = 10, damping ratio 0.02, A = 10, w = pi; DT = 0.2 sqrt(m / k0))
// Prints one JSON object: n, steps, best and median wall time, the final u of the top storey.
//
// Build: g++ -std=c++17 -O3 -DNDEBUG chain_loop.cpp -o chain_loop
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

constexpr double MASS = 1e5, K0 = 1e8, HARD = 10.0, ZETA = 0.02;
constexpr double AG_AMP = 10.0, AG_OMEGA = 3.141592653589793;

// a = -(F_s(u) + F_d(v)) / m - a_g(t): storey i acts on floors i-1 and i.
void acc(const std::vector<double>& u, const std::vector<double>& v, double t, double c, std::vector<double>& a) {
  const std::size_t n = u.size();
  const double ag = AG_AMP * std::sin(AG_OMEGA * t), inv_m = 1.0 / MASS;
  double prev_u = 0.0, prev_v = 0.0, f_below = 0.0;
  // f_below: force of storey i (below floor i); the storey above pulls with -f_above.
  double d = u[0], dv = v[0];
  f_below = K0 * (1.0 + HARD * d * d) * d + c * dv;
  for (std::size_t i = 0; i < n; ++i) {
    double f_above = 0.0;
    if (i + 1 < n) {
      prev_u = u[i];
      prev_v = v[i];
      d = u[i + 1] - prev_u;
      dv = v[i + 1] - prev_v;
      f_above = K0 * (1.0 + HARD * d * d) * d + c * dv;
    }
    a[i] = -(f_below - f_above) * inv_m - ag;
    f_below = f_above;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s N STEPS REPEATS [DT]\n", argv[0]);
    return 2;
  }
  const std::size_t n = static_cast<std::size_t>(std::atoll(argv[1]));
  const std::int64_t steps = std::atoll(argv[2]);
  const int repeats = std::atoi(argv[3]);
  const double h = argc > 4 ? std::atof(argv[4]) : 0.2 * std::sqrt(MASS / K0);
  const double c = 2.0 * ZETA * std::sqrt(K0 * MASS);
  std::vector<double> u(n), v(n), a(n), vs(n), an(n);
  std::vector<double> times;
  for (int r = 0; r <= repeats; ++r) {  // the first run warms up, untimed
    std::fill(u.begin(), u.end(), 0.0);
    std::fill(v.begin(), v.end(), 0.0);
    acc(u, v, 0.0, c, a);
    const auto t0 = std::chrono::steady_clock::now();
    for (std::int64_t s = 1; s <= steps; ++s) {
      const double t = static_cast<double>(s) * h;
      for (std::size_t i = 0; i < n; ++i) {
        u[i] += h * v[i] + 0.5 * h * h * a[i];
        vs[i] = v[i] + h * a[i];
      }
      acc(u, vs, t, c, an);
      for (std::size_t i = 0; i < n; ++i) {
        v[i] += 0.5 * h * (a[i] + an[i]);
        a[i] = an[i];
      }
    }
    const auto t1 = std::chrono::steady_clock::now();
    if (r > 0) times.push_back(std::chrono::duration<double>(t1 - t0).count());
  }
  std::sort(times.begin(), times.end());
  std::printf("{\"n\": %zu, \"steps\": %lld, \"dt\": %.17g, \"best\": %.9g, \"median\": %.9g, \"u_top\": %.17g}\n", n,
              static_cast<long long>(steps), h, times.front(), times[times.size() / 2], u[n - 1]);
  return 0;
}
