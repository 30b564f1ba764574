// A harmonic load P = amplitude sin(omega t + phase) along the measure's g.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct HarmonicForce : LawBase {
  static constexpr const char* key = "harmonic_force";
  static constexpr const char* doc = "harmonic load P = amplitude sin(omega t + phase) along g";
  static constexpr bool uses_displacement = false, is_load = true;
  static constexpr std::array<Parameter, 3> parameters{
      {{"amplitude", kRequired, "amplitude"}, {"omega", kRequired, "circular frequency [rad/s]"}, {"phase", 0.0, "phase [rad]"}}};
  struct Params {
    double amplitude, omega, phase;
  };
  static Params prepare(const double* x, const Signal*) { return {x[0], x[1], x[2]}; }
  static double value(const Params& p, double, double, double t) { return -p.amplitude * std::sin(p.omega * t + p.phase); }
  static Slopes slopes(const Params&, double, double, double) { return {}; }
  static bool uses_time(const Params&) { return true; }
};

}  // namespace effects
}  // namespace nvib
