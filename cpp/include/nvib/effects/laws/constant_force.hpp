// A constant load P along the measure's g (a load reads no state; it acts as -P).
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct ConstantForce : LawBase {
  static constexpr const char* key = "constant_force";
  static constexpr const char* doc = "constant load P = value along g";
  static constexpr bool uses_displacement = false, is_load = true;
  static constexpr std::array<Parameter, 1> parameters{{{"value", kRequired, "the load"}}};
  struct Params {
    double value;
  };
  static Params prepare(const double* x, const Signal*) { return {x[0]}; }
  static double value(const Params& p, double, double, double) { return -p.value; }
  static Slopes slopes(const Params&, double, double, double) { return {}; }
};

}  // namespace effects
}  // namespace nvib
