// Command line shared by the building benchmark programs (no nvib in here: the
// hand-written loop must not depend on the library it is compared with).
//   PROGRAM DT T_END REPEATS ETA SAVE_EVERY [SAVE_EVERY ...]
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

struct BenchArgs {
  double h = 0.0, t_end = 0.0, eta = 0.0;
  int repeats = 0;
  std::vector<std::int64_t> save_every;
};

// False (after printing the usage) when the arguments are missing.
inline bool parse_bench_args(int argc, char** argv, BenchArgs& a) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: %s DT T_END REPEATS ETA SAVE_EVERY [SAVE_EVERY ...]\n", argv[0]);
    return false;
  }
  a.h = std::atof(argv[1]);
  a.t_end = std::atof(argv[2]);
  a.repeats = std::atoi(argv[3]);
  a.eta = std::atof(argv[4]);
  for (int i = 5; i < argc; ++i) a.save_every.push_back(std::atoll(argv[i]));
  return true;
}
