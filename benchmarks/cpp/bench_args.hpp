// Command line, state, saved history and output helpers shared by the benchmark programs (no nvib in
// here: the hand-written loops must not depend on the library they are compared with).
//   PROGRAM DT T_END REPEATS ETA SAVE_EVERY [SAVE_EVERY ...] [--dump=PREFIX]
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

// "key v1 v2 ..." per line ('#' starts a comment): the model files benchmarks/hysteresis.py writes.
inline std::map<std::string, std::vector<double>> read_keyed(const char* path) {
  std::map<std::string, std::vector<double>> out;
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "cannot read %s\n", path);
    std::exit(2);
  }
  std::string line, key;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    if (!(s >> key) || key[0] == '#') continue;
    std::vector<double>& v = out[key];
    double x;
    while (s >> x) v.push_back(x);
  }
  return out;
}

// Removes a trailing --dump=PREFIX from the arguments and returns PREFIX ("" if absent).
inline std::string take_dump(int& argc, char** argv) {
  if (argc > 1 && std::strncmp(argv[argc - 1], "--dump=", 7) == 0) return std::string(argv[--argc] + 7);
  return {};
}

struct BenchArgs {
  double h = 0.0, t_end = 0.0, eta = 0.0;
  int repeats = 0;
  std::vector<std::int64_t> save_every;
  std::string dump;  // with --dump=PREFIX: where to write the saved displacements
};

// False (after printing the usage) when the arguments are missing.
inline bool parse_bench_args(int argc, char** argv, BenchArgs& a) {
  a.dump = take_dump(argc, argv);
  if (argc < 6) {
    std::fprintf(stderr, "usage: %s DT T_END REPEATS ETA SAVE_EVERY [SAVE_EVERY ...] [--dump=PREFIX]\n", argv[0]);
    return false;
  }
  a.h = std::atof(argv[1]);
  a.t_end = std::atof(argv[2]);
  a.repeats = std::atoi(argv[3]);
  a.eta = std::atof(argv[4]);
  for (int i = 5; i < argc; ++i) a.save_every.push_back(std::atoll(argv[i]));
  return true;
}

// Writes count doubles to path (raw, native byte order); false, with a message, when it cannot.
inline bool write_doubles(const std::string& path, const double* x, size_t count) {
  std::FILE* fh = std::fopen(path.c_str(), "wb");
  const bool ok = fh && std::fwrite(x, sizeof(double), count, fh) == count;
  if (fh) std::fclose(fh);
  if (!ok) std::fprintf(stderr, "cannot write %s\n", path.c_str());
  return ok;
}

// Prints "name": [x0, x1, ...] with every digit (a JSON member).
inline void print_json_vector(const char* name, const double* x, int n) {
  std::printf("\"%s\": [", name);
  for (int i = 0; i < n; ++i) std::printf("%s%.17g", i ? ", " : "", x[i]);
  std::printf("]");
}

// The state of a hand-written loop of N DOFs.
template <int N>
struct LoopState {
  double u[N], v[N], a[N];
};

// Its saved history, the rows nvib's solve() returns (steps 0, k, 2k, ... and the last one),
// allocated once before the loop and filled in place.
template <int N>
struct LoopOutput {
  std::unique_ptr<double[]> t, u, v, a;
  std::int64_t rows = 0;

  static LoopOutput allocate(std::int64_t nsteps, std::int64_t k) {
    LoopOutput out;
    out.rows = nsteps / k + 1 + (nsteps % k != 0 ? 1 : 0);
    out.t.reset(new double[out.rows]);
    out.u.reset(new double[out.rows * N]);
    out.v.reset(new double[out.rows * N]);
    out.a.reset(new double[out.rows * N]);
    return out;
  }
  void save(std::int64_t& row, double time, const LoopState<N>& s) {
    t[row] = time;
    std::memcpy(u.get() + row * N, s.u, sizeof s.u);
    std::memcpy(v.get() + row * N, s.v, sizeof s.v);
    std::memcpy(a.get() + row * N, s.a, sizeof s.a);
    ++row;
  }
};

// "u": [...], "v": [...], "a": [...] (JSON members).
template <int N>
void print_json_state(const LoopState<N>& s) {
  print_json_vector("u", s.u, N);
  std::printf(", ");
  print_json_vector("v", s.v, N);
  std::printf(", ");
  print_json_vector("a", s.a, N);
}
