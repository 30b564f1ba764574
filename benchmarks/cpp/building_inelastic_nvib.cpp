// The scene building_inelastic through nvib's C++ headers, no Python: the model
// of building_inelastic_loop.cpp built from effects the way
// nvib.load_scene("building_inelastic") builds it (a bilinear effect and a
// p_delta effect on each storey drift, a ground_acceleration whose signal is
// the record as a table, the Rayleigh C given as a constant matrix), integrated
// with nvib::solve(). benchmarks/hysteresis.py uses it to split nvib's cost
// into the C++ core and the Python binding; it is also the driver to profile
// (valgrind --tool=callgrind).
//
// Models ("storeys"):
//   bilinear  the scene;
//   elastic   the bilinear effects replaced by springs of the same k (assembled
//             into K with the P-delta: the model is linear);
//   noyield   bilinear effects that never yield (fy = 1e300): the cost of a law
//             with memory on the elastic branch.
// Schemes: CentralDifference() and Newmark() (full Newton, nvib's defaults).
//
// Usage: building_inelastic_nvib MODEL_FILE REPEATS SAVE_EVERY
//   MODEL_FILE as written by hysteresis.py (see building_inelastic_loop.cpp).
// Output: one JSON object per (scheme, storeys): best and median wall time of
// REPEATS nvib::solve() calls, the best Stats::wall_time, nvib's counters, the
// final state and the largest difference between the K nvib assembled and the
// file's.
//
// Build: g++ -std=c++17 -O3 -DNDEBUG -I<nvib include> -I<eigen3> building_inelastic_nvib.cpp -o building_inelastic_nvib
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nvib/nvib.hpp>

#include "bench_args.hpp"

namespace {


struct Input {
  std::map<std::string, std::vector<double>> f;
  int n = 0;
  const std::vector<double>& get(const char* key, std::size_t count) const {
    const auto it = f.find(key);
    if (it == f.end() || (count > 0 && it->second.size() != count)) {
      std::fprintf(stderr, "model file: '%s' missing or not %zu values\n", key, count);
      std::exit(2);
    }
    return it->second;
  }
  // A tridiagonal matrix from its diagonal and off-diagonal.
  nvib::SparseMatrix band(const char* diag, const char* off) const {
    std::vector<Eigen::Triplet<double, int>> t;
    const auto &d = get(diag, n), &o = get(off, n - 1);
    for (int i = 0; i < n; ++i) {
      t.emplace_back(i, i, d[i]);
      if (i + 1 < n) {
        t.emplace_back(i, i + 1, o[i]);
        t.emplace_back(i + 1, i, o[i]);
      }
    }
    nvib::SparseMatrix A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    return A;
  }
};

enum class Storeys { bilinear, elastic, noyield };
const char* name_of(Storeys s) {
  return s == Storeys::bilinear ? "bilinear" : s == Storeys::elastic ? "elastic" : "noyield";
}

// The scene's effects, in its order: storey s's law and its P-delta, then the ground motion.
nvib::Model<nvib::effects::EffectSet> building(const Input& in, Storeys kind) {
  using namespace nvib::effects;
  const int n = in.n;
  const auto &k = in.get("k", n), &fy = in.get("fy", n), &b = in.get("b", n), &P = in.get("P", n),
             &hs = in.get("storey_h", n);
  std::vector<Effect> list;
  for (int s = 0; s < n; ++s) {
    Measure g = s == 0 ? Measure{{0, 1.0}} : Measure{{s, 1.0}, {s - 1, -1.0}};
    if (kind == Storeys::elastic)
      list.push_back(make_effect("spring", g, {{"k", k[s]}}, {}, "storey" + std::to_string(s + 1)));
    else
      list.push_back(make_effect("bilinear", g,
                                 {{"k", k[s]}, {"fy", kind == Storeys::noyield ? 1e300 : fy[s]}, {"b", b[s]}}, {},
                                 "storey" + std::to_string(s + 1)));
    list.push_back(make_effect("p_delta", g, {{"P", P[s]}, {"h", hs[s]}}, {}, "pdelta" + std::to_string(s + 1)));
  }
  Measure r;
  for (int i = 0; i < n; ++i) r.emplace_back(i, 1.0);
  list.push_back(make_effect("ground_acceleration", r, {},
                             Signal::table(in.get("record_t", 0), in.get("record_a", in.get("record_t", 0).size())),
                             "ground"));
  const auto& m = in.get("mass", n);
  nvib::Vector mass(n);
  for (int i = 0; i < n; ++i) mass[i] = m[i];
  return make_effect_model(nvib::Mass::diagonal(mass), std::move(list), nvib::SparseMatrix(),
                           in.band("C_diag", "C_off"));
}

// max |K_nvib - K_file| over the entries (the P-delta K; the elastic model's also holds the springs).
double k_difference(const Input& in, const nvib::SparseMatrix& K, Storeys kind) {
  nvib::Matrix D = nvib::Matrix(K) - nvib::Matrix(in.band("K_diag", "K_off"));
  if (kind == Storeys::elastic) {
    const auto& k = in.get("k", in.n);
    for (int s = 0; s < in.n; ++s) {
      D(s, s) -= k[s];
      if (s > 0) {
        D(s - 1, s - 1) -= k[s];
        D(s, s - 1) += k[s];
        D(s - 1, s) += k[s];
      }
    }
  }
  return D.cwiseAbs().maxCoeff();
}

void print_last_row(const char* name, const nvib::History& x) {
  print_json_vector(name, x.data() + (x.rows() - 1) * x.cols(), static_cast<int>(x.cols()));
}

template <class Scheme, class ModelT>
void bench(const char* label, Storeys kind, const Scheme& scheme, const ModelT& model, double kdiff, double h,
           double t_end, int repeats, std::int64_t k) {
  const nvib::Vector zero = nvib::Vector::Zero(model.size());
  nvib::SolveOptions opt;
  opt.save_every = k;
  std::vector<double> times, inner;
  nvib::Result res = nvib::solve(model, scheme, h, t_end, zero, zero, opt);  // warm-up, untimed
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    nvib::Result fresh = nvib::solve(model, scheme, h, t_end, zero, zero, opt);
    const auto t1 = std::chrono::steady_clock::now();
    res = std::move(fresh);  // the previous result is freed here, outside the timed region
    times.push_back(std::chrono::duration<double>(t1 - t0).count());
    inner.push_back(res.stats.wall_time);
  }
  std::sort(times.begin(), times.end());
  std::sort(inner.begin(), inner.end());
  std::printf("{\"scheme\": \"%s\", \"storeys\": \"%s\", \"save_every\": %lld, \"steps\": %lld, \"saved\": %lld, "
              "\"repeats\": %d, \"best\": %.9g, \"median\": %.9g, \"best_wall_time\": %.9g, \"k_difference\": %.3g, ",
              label, name_of(kind), static_cast<long long>(k), static_cast<long long>(res.stats.num_steps),
              static_cast<long long>(res.t.size()), repeats, times.front(), times[times.size() / 2], inner.front(),
              kdiff);
  std::printf("\"newton_iters\": %lld, \"force_evals\": %lld, \"tangent_evals\": %lld, \"factorizations\": %lld, "
              "\"linear_solver\": \"%s\", \"status\": \"%s\", ",
              static_cast<long long>(res.stats.num_newton_iters), static_cast<long long>(res.stats.num_force_evals),
              static_cast<long long>(res.stats.num_tangent_evals),
              static_cast<long long>(res.stats.num_factorizations), res.stats.linear_solver,
              nvib::to_string(res.status));
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
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s MODEL_FILE REPEATS SAVE_EVERY\n", argv[0]);
    return 2;
  }
  Input in;
  in.f = read_keyed(argv[1]);
  in.n = static_cast<int>(in.get("n", 1)[0]);
  const double h = in.get("dt", 1)[0], t_end = in.get("t_end", 1)[0];
  const int repeats = std::atoi(argv[2]);
  const std::int64_t k = std::atoll(argv[3]);
  if (repeats < 1 || k < 1) return 2;
  for (const Storeys kind : {Storeys::bilinear, Storeys::elastic, Storeys::noyield}) {
    const auto model = building(in, kind);
    const double kdiff = k_difference(in, model.K(), kind);
    bench("cd", kind, nvib::CentralDifference(), model, kdiff, h, t_end, repeats, k);
    bench("newmark", kind, nvib::Newmark(), model, kdiff, h, t_end, repeats, k);
  }
  return 0;
}
