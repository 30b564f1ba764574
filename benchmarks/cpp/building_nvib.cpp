// The building scene through nvib's C++ headers, no Python: the same model as
// building_loop.cpp, built from effects the way nvib.load_scene("building")
// builds it (six hardening_spring effects on the drifts and a
// ground_acceleration effect), integrated with nvib::solve(). benchmarks/
// building.py uses it to split nvib's cost into the C++ core and the Python
// binding; it is also the driver to profile (valgrind --tool=callgrind). It
// also runs the same schemes on the hand-written force given as a C++ functor.
//
// Usage: building_nvib DT T_END REPEATS ETA SAVE_EVERY [SAVE_EVERY ...] [--implicit]
// Output: one JSON object per (scheme, save_every) line, as building_loop.
// With --implicit: Newmark and the paper's generalized-alpha with full Newton
// instead (benchmarks/implicit.py), with the Newton counters.
//
// Build: g++ -std=c++17 -O3 -DNDEBUG -I<nvib>/cpp/include -I<eigen3> building_nvib.cpp -o building_nvib
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <nvib/nvib.hpp>

#include "bench_args.hpp"

namespace {

nvib::Model<nvib::effects::EffectSet> building() {
  using namespace nvib::effects;
  const int n = 6;
  std::vector<Effect> list;
  list.push_back(hardening_spring({{0, 1.0}}, 1e8, 10.0));
  for (int i = 1; i < n; ++i) list.push_back(hardening_spring({{i, 1.0}, {i - 1, -1.0}}, 1e8, 10.0));
  Measure r;
  for (int i = 0; i < n; ++i) r.emplace_back(i, 1.0);
  list.push_back(ground_acceleration(r, Signal::sine(10.0, 3.141592653589793)));
  return make_effect_model(nvib::Mass::diagonal(nvib::Vector::Constant(n, 1e5)), std::move(list));
}

// The hand-written loop's force (building_loop.cpp, acc() before the mass) as a
// C++ functor: nvib's stepper and loop with no effects library, to separate
// the cost of the general effects from that of the rest of nvib.
struct HandForce {
  void operator()(const nvib::CVecRef& u, const nvib::CVecRef&, double t, nvib::VecRef out) const {
    constexpr int N = 6;
    double f[N + 1];
    double prev = 0.0;
    for (int i = 0; i < N; ++i) {
      const double d = u[i] - prev;
      f[i] = 1e8 * (1.0 + 10.0 * d * d) * d;
      prev = u[i];
    }
    f[N] = 0.0;
    const double mag = 1e5 * 10.0 * std::sin(3.141592653589793 * t);  // -P = M r a_g
    for (int i = 0; i < N; ++i) out[i] = (f[i] - f[i + 1]) + mag;
  }
  // K = df/du: tridiagonal, storey stiffnesses k0 (1 + 3 a d^2) (for the implicit schemes).
  void tangent(const nvib::CVecRef& u, const nvib::CVecRef&, double, nvib::MatRef K, nvib::MatRef C) const {
    constexpr int N = 6;
    K.setZero();
    C.setZero();
    double prev = 0.0;
    for (int i = 0; i < N; ++i) {
      const double d = u[i] - prev, k = 1e8 * (1.0 + 30.0 * d * d);
      K(i, i) += k;
      if (i > 0) {
        K(i - 1, i - 1) += k;
        K(i, i - 1) -= k;
        K(i - 1, i) -= k;
      }
      prev = u[i];
    }
  }
  bool uses_velocity() const { return false; }
};

nvib::Model<HandForce> building_functor() {
  return nvib::make_model(nvib::Mass::diagonal(nvib::Vector::Constant(6, 1e5)), HandForce{});
}

// The last saved row (rows of a History are contiguous).
void print_last_row(const char* name, const nvib::History& x) {
  print_json_vector(name, x.data() + (x.rows() - 1) * x.cols(), static_cast<int>(x.cols()));
}

std::string only_label;  // empty: every run

template <class Scheme, class ModelT>
void bench(const char* label, const Scheme& scheme, const ModelT& model, double h, double t_end, int repeats,
           std::int64_t k) {
  if (!only_label.empty() && only_label != label) return;
  const nvib::Vector zero = nvib::Vector::Zero(model.size());
  nvib::SolveOptions opt;
  opt.save_every = k;
  std::vector<double> times, inner;
  nvib::Result res;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    nvib::Result fresh = nvib::solve(model, scheme, h, t_end, zero, zero, opt);
    const auto t1 = std::chrono::steady_clock::now();
    res = std::move(fresh);  // the previous result is freed here, outside the timed region
    times.push_back(std::chrono::duration<double>(t1 - t0).count());
    inner.push_back(res.stats.wall_time);  // nvib's own clock inside solve()
  }
  std::sort(times.begin(), times.end());
  std::sort(inner.begin(), inner.end());
  std::printf("{\"scheme\": \"%s\", \"save_every\": %lld, \"steps\": %lld, \"saved\": %lld, \"repeats\": %d, "
              "\"best\": %.9g, \"median\": %.9g, \"best_wall_time\": %.9g, ",
              label, static_cast<long long>(k), static_cast<long long>(res.stats.num_steps),
              static_cast<long long>(res.t.size()), repeats, times.front(), times[times.size() / 2], inner.front());
  std::printf("\"newton_iters\": %lld, \"force_evals\": %lld, \"tangent_evals\": %lld, \"status\": \"%s\", ",
              static_cast<long long>(res.stats.num_newton_iters), static_cast<long long>(res.stats.num_force_evals),
              static_cast<long long>(res.stats.num_tangent_evals), nvib::to_string(res.status));
  print_last_row("u", res.u);
  std::printf(", ");
  print_last_row("v", res.v);
  std::printf(", ");
  print_last_row("a", res.a);
  std::printf("}\n");
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  // --only=LABEL (last): that run alone (benchmarks/profile_building.py profiles one scheme)
  if (argc > 1 && std::string(argv[argc - 1]).rfind("--only=", 0) == 0) only_label = std::string(argv[--argc] + 7);
  const bool implicit = argc > 1 && std::string(argv[argc - 1]) == "--implicit";
  if (implicit) --argc;
  BenchArgs a;
  if (!parse_bench_args(argc, argv, a)) return 2;
  const auto scene = building();
  const auto functor = building_functor();
  if (implicit) {
    for (const std::int64_t k : a.save_every) {
      bench("newmark", nvib::Newmark(), scene, a.h, a.t_end, a.repeats, k);
      bench("newmark_functor", nvib::Newmark(), functor, a.h, a.t_end, a.repeats, k);
      bench("galpha", nvib::GeneralizedAlpha(), scene, a.h, a.t_end, a.repeats, k);
      bench("galpha_functor", nvib::GeneralizedAlpha(), functor, a.h, a.t_end, a.repeats, k);
    }
    return 0;
  }
  for (const std::int64_t k : a.save_every) {
    bench("cd", nvib::CentralDifference(), scene, a.h, a.t_end, a.repeats, k);
    bench("cd_functor", nvib::CentralDifference(), functor, a.h, a.t_end, a.repeats, k);
  }
  for (const std::int64_t k : a.save_every) {
    bench("cemdts", nvib::CEMDTS(a.eta), scene, a.h, a.t_end, a.repeats, k);
    bench("cemdts_functor", nvib::CEMDTS(a.eta), functor, a.h, a.t_end, a.repeats, k);
  }
  for (const std::int64_t k : a.save_every) {
    bench("zhai", nvib::Zhai(), scene, a.h, a.t_end, a.repeats, k);
    bench("zhai_functor", nvib::Zhai(), functor, a.h, a.t_end, a.repeats, k);
  }
  return 0;
}
