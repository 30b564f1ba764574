// The building scene (python/nvib/scenes/building.toml) for the hand-written loops, plain
// arrays, no nvib: 6 floors of 1e5 kg, storey springs f = k0 (1 + a d^2) d on the drifts
// d_1 = x_1, d_i = x_i - x_{i-1} (k0 = 1e8 N/m, a = 10), ground acceleration
// a_g = 10 sin(pi t) applied as P = -M r a_g (r = 1).
#pragma once

#include <cmath>

namespace building {

constexpr int N = 6;
constexpr double MASS = 1e5, K0 = 1e8, HARD = 10.0;
constexpr double AG_AMP = 10.0, AG_OMEGA = 3.141592653589793;

// f[i] = the force of storey i+1 on its drift, f[N] = 0 (no storey above the roof).
inline void storey_forces(const double* u, double* f) {
  double prev = 0.0;
  for (int i = 0; i < N; ++i) {
    const double d = u[i] - prev;  // drift of storey i+1
    f[i] = K0 * (1.0 + HARD * d * d) * d;
    prev = u[i];
  }
  f[N] = 0.0;
}

inline double ground_acceleration(double t) { return AG_AMP * std::sin(AG_OMEGA * t); }

}  // namespace building
